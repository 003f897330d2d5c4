//! A differential-drive (unicycle) body: commanded forward speed and yaw rate, limited in magnitude and rate of
//! change, integrated exactly along arcs.

/// The body's limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Top forward speed, m/s.
    pub v_max: f64,
    /// Forward acceleration and braking, m/s².
    pub a_max: f64,
    /// Top yaw rate, rad/s.
    pub w_max: f64,
    /// Yaw acceleration, rad/s².
    pub alpha_max: f64,
}

/// Pose and velocities of a body in the map frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DiffDrive {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians in (−π, π].
    pub yaw: f64,
    /// Forward speed, m/s (never negative: the robots do not reverse).
    pub v: f64,
    /// Yaw rate, rad/s.
    pub w: f64,
}

fn toward(current: f64, wanted: f64, max_change: f64) -> f64 {
    current + (wanted - current).clamp(-max_change, max_change)
}

/// `a` wrapped to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let t = a.rem_euclid(std::f64::consts::TAU);
    if t > std::f64::consts::PI {
        t - std::f64::consts::TAU
    } else {
        t
    }
}

impl DiffDrive {
    /// A body at rest at `(x, y, yaw)`.
    pub fn at(x: f64, y: f64, yaw: f64) -> Self {
        Self {
            x,
            y,
            yaw: wrap(yaw),
            v: 0.0,
            w: 0.0,
        }
    }

    /// Moves the velocities toward the command within the limits, then drives for `dt` seconds along the arc;
    /// returns the distance driven.
    pub fn step(&mut self, v_cmd: f64, w_cmd: f64, lim: &Limits, dt: f64) -> f64 {
        let v_cmd = v_cmd.clamp(0.0, lim.v_max);
        let w_cmd = w_cmd.clamp(-lim.w_max, lim.w_max);
        let v0 = self.v;
        self.v = toward(self.v, v_cmd, lim.a_max * dt).max(0.0);
        self.w = toward(self.w, w_cmd, lim.alpha_max * dt);
        // Trapezoid for the distance; the arc at the mean speed.
        let ds = 0.5 * (v0 + self.v) * dt;
        let dyaw = self.w * dt;
        if dyaw.abs() < 1e-9 {
            self.x += ds * self.yaw.cos();
            self.y += ds * self.yaw.sin();
        } else {
            let r = ds / dyaw;
            self.x += r * ((self.yaw + dyaw).sin() - self.yaw.sin());
            self.y -= r * ((self.yaw + dyaw).cos() - self.yaw.cos());
        }
        self.yaw = wrap(self.yaw + dyaw);
        ds
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const LIM: Limits = Limits {
        v_max: 1.0,
        a_max: 0.5,
        w_max: 1.0,
        alpha_max: 2.0,
    };

    #[test]
    fn it_accelerates_within_the_limit_and_drives_straight() {
        let mut d = DiffDrive::at(0.0, 0.0, 0.0);
        let mut s = 0.0;
        for _ in 0..40 {
            s += d.step(1.0, 0.0, &LIM, 0.05);
        }
        // 2 s at 0.5 m/s²: v = 1.0, s = 1.0 m.
        assert!((d.v - 1.0).abs() < 1e-9);
        assert!((s - 1.0).abs() < 1e-9 && (d.x - 1.0).abs() < 1e-9 && d.y.abs() < 1e-12);
    }

    proptest! {
        #[test]
        fn arcs_keep_their_radius(v in 0.1f64..1.0, w in -1.0f64..1.0) {
            prop_assume!(w.abs() > 0.05);
            let mut d = DiffDrive { x: 0.0, y: 0.0, yaw: 0.0, v, w };
            let r = v / w;
            // Circle centre at (0, r).
            for _ in 0..100 {
                d.step(v, w, &LIM, 0.05);
                let dist = ((d.x).powi(2) + (d.y - r).powi(2)).sqrt();
                prop_assert!((dist - r.abs()).abs() < 1e-9, "{dist} vs {r}");
            }
        }

        #[test]
        fn wrap_stays_in_range(a in -100.0f64..100.0) {
            let w = wrap(a);
            prop_assert!(w > -std::f64::consts::PI - 1e-12 && w <= std::f64::consts::PI + 1e-12);
            prop_assert!(((a - w) / std::f64::consts::TAU - ((a - w) / std::f64::consts::TAU).round()).abs() < 1e-9);
        }
    }
}
