//! The knobs of a correction ([`CorrectParams`]), with defaults derived from the robot radius.

use super::error::CorrectError;

/// Knobs of judging and repairing a plan around a robot. Distances in metres, curvature in 1/m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectParams {
    /// Robot radius, metres: the hard clearance every returned path keeps (> 0).
    pub robot_radius_m: f64,
    /// Clearance the plan itself keeps from the static map, metres (in (0, robot_radius_m]; default
    /// `robot_radius_m`). A footprint robot's plan is checked against the static map by heading, so its centre
    /// passes a doorway closer than its circumscribed radius; the judge asks the static map for this much and
    /// new (live) obstacles for d_safe, so the plan's own passage is no breach.
    pub static_radius_m: f64,
    /// Extra clearance wanted on top of the radius, metres (> 0, default 0.05): d_safe = radius + margin.
    pub margin_m: f64,
    /// Radius of the judged window around the robot, metres (default 3.0).
    pub window_radius_m: f64,
    /// Largest curvature allowed at a waypoint without cost, 1/m (> 0; `f64::INFINITY`, the default,
    /// disables the curvature term: coverage plans turn on the spot at their sharp corners, see
    /// [`crate::speed::samples::curvature_cap`], so a sharp plan corner is not a fault by itself).
    pub max_curvature_per_m: f64,
    /// J_th: a non-compliant stretch is reported when its cost J exceeds this, metres (≥ 0, default 0.02;
    /// see [`super::judge`] for J). A stretch closer than the robot radius is reported whatever its cost.
    pub j_threshold: f64,
    /// Weight of J_len (squared segment lengths over the spacing, ≈ path length in metres), ≥ 0.
    pub w_len: f64,
    /// Weight of J_smooth (squared second differences over spacing³, ≈ ∫κ² ds), ≥ 0.
    pub w_smooth: f64,
    /// Weight of J_obs (hinge-squared clearance deficit below d_safe, in units of the margin, per metre), > 0.
    pub w_obs: f64,
    /// Spacing of the optimised points, metres (> 0, default 0.1).
    pub spacing_m: f64,
    /// Largest number of L-BFGS iterations per optimisation (≥ 1, default 50).
    pub max_iterations: u32,
    /// Largest arc length of the sliding window, metres (default 12.0; at least 2 × window_radius_m is
    /// sensible).
    pub max_window_m: f64,
    /// How far along the plan beyond a blocked stretch a skip looks for a point to rejoin, metres
    /// (default 50.0).
    pub skip_search_m: f64,
}

impl CorrectParams {
    /// Defaults for a robot of radius `robot_radius_m` metres.
    pub fn for_robot(robot_radius_m: f64) -> Self {
        Self {
            robot_radius_m,
            static_radius_m: robot_radius_m,
            margin_m: 0.05,
            window_radius_m: 3.0,
            max_curvature_per_m: f64::INFINITY,
            j_threshold: 0.02,
            w_len: 1.0,
            w_smooth: 0.5,
            w_obs: 50.0,
            spacing_m: 0.1,
            max_iterations: 50,
            max_window_m: 12.0,
            skip_search_m: 50.0,
        }
    }

    /// d_safe = robot radius + margin, metres.
    pub fn d_safe(&self) -> f64 {
        self.robot_radius_m + self.margin_m
    }

    /// Checks every field's range (finite where a number must be).
    pub fn validate(&self) -> Result<(), CorrectError> {
        let checks: [(&'static str, f64, bool, &str); 13] = [
            (
                "robot_radius_m",
                self.robot_radius_m,
                self.robot_radius_m > 0.0 && self.robot_radius_m.is_finite(),
                "must be > 0 m and finite",
            ),
            (
                "static_radius_m",
                self.static_radius_m,
                self.static_radius_m > 0.0 && self.static_radius_m <= self.robot_radius_m,
                "must be > 0 m and at most robot_radius_m",
            ),
            (
                "margin_m",
                self.margin_m,
                self.margin_m > 0.0 && self.margin_m.is_finite(),
                "must be > 0 m and finite",
            ),
            (
                "window_radius_m",
                self.window_radius_m,
                self.window_radius_m > 0.0 && self.window_radius_m.is_finite(),
                "must be > 0 m and finite",
            ),
            (
                "max_curvature_per_m",
                self.max_curvature_per_m,
                self.max_curvature_per_m > 0.0,
                "must be > 0 1/m (infinite disables it)",
            ),
            (
                "j_threshold",
                self.j_threshold,
                self.j_threshold >= 0.0 && self.j_threshold.is_finite(),
                "must be >= 0 and finite",
            ),
            (
                "w_len",
                self.w_len,
                self.w_len >= 0.0 && self.w_len.is_finite(),
                "must be >= 0 and finite",
            ),
            (
                "w_smooth",
                self.w_smooth,
                self.w_smooth >= 0.0 && self.w_smooth.is_finite(),
                "must be >= 0 and finite",
            ),
            (
                "w_obs",
                self.w_obs,
                self.w_obs > 0.0 && self.w_obs.is_finite(),
                "must be > 0 and finite",
            ),
            (
                "spacing_m",
                self.spacing_m,
                self.spacing_m > 0.0 && self.spacing_m.is_finite(),
                "must be > 0 m and finite",
            ),
            (
                "max_iterations",
                f64::from(self.max_iterations),
                self.max_iterations >= 1,
                "must be >= 1",
            ),
            (
                "max_window_m",
                self.max_window_m,
                self.max_window_m > 0.0 && self.max_window_m.is_finite(),
                "must be > 0 m and finite",
            ),
            (
                "skip_search_m",
                self.skip_search_m,
                self.skip_search_m >= 0.0 && self.skip_search_m.is_finite(),
                "must be >= 0 m and finite",
            ),
        ];
        for (name, value, ok, what) in checks {
            if !ok {
                return Err(CorrectError::InvalidParam {
                    name,
                    reason: format!("got {value}; {what}"),
                });
            }
        }
        Ok(())
    }
}

impl Default for CorrectParams {
    /// [`CorrectParams::for_robot`] with a 0.3 m radius.
    fn default() -> Self {
        Self::for_robot(0.3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_bad_values_are_named() {
        assert!(CorrectParams::default().validate().is_ok());
        assert!(CorrectParams::for_robot(0.2).validate().is_ok());
        let bad = CorrectParams {
            spacing_m: f64::NAN,
            ..CorrectParams::default()
        };
        assert!(matches!(
            bad.validate(),
            Err(CorrectError::InvalidParam { name: "spacing_m", .. })
        ));
        assert!(CorrectParams::for_robot(-1.0).validate().is_err());
    }
}
