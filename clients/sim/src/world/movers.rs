//! Moving obstacles: discs walking a straight line back and forth, turning back early rather than walking into
//! a robot (as people do when a robot is in their way).

use shift_planner::geom::Point2;

use super::file::MoverSpec;
use super::shapes::Solid;

/// Gap a mover keeps to robots, metres.
const KEEP_CLEAR_M: f64 = 0.1;

/// One moving disc.
#[derive(Debug, Clone)]
pub struct Mover {
    spec: MoverSpec,
    /// Position along the walk, metres from `from`.
    s: f64,
    /// +1 towards `to`, −1 towards `from`.
    dir: f64,
    /// Its shape, at its current place.
    pub solid: Solid,
}

impl Mover {
    /// A mover at the `from` end, walking towards `to`.
    pub fn new(spec: MoverSpec) -> Self {
        let from = Point2::new(spec.from[0], spec.from[1]);
        Self {
            spec,
            s: 0.0,
            dir: 1.0,
            solid: Solid::disc(from, spec.r),
        }
    }

    fn length(&self) -> f64 {
        (Point2::new(self.spec.to[0], self.spec.to[1]) - Point2::new(self.spec.from[0], self.spec.from[1])).norm()
    }

    fn at(&self, s: f64) -> Point2 {
        let from = Point2::new(self.spec.from[0], self.spec.from[1]);
        let to = Point2::new(self.spec.to[0], self.spec.to[1]);
        let len = self.length();
        if len <= f64::EPSILON {
            from
        } else {
            from + (to - from) * (s / len)
        }
    }

    /// Its centre.
    pub fn centre(&self) -> Point2 {
        self.at(self.s)
    }

    /// Its radius.
    pub fn radius(&self) -> f64 {
        self.spec.r
    }

    /// Walks for `dt` seconds; turns back at the ends, and instead of stepping closer than [`KEEP_CLEAR_M`] to
    /// a robot (`(centre, radius)`).
    pub fn step(&mut self, dt: f64, robots: &[(Point2, f64)]) {
        let len = self.length();
        let mut next = self.s + self.dir * self.spec.speed * dt;
        if next > len || next < 0.0 {
            self.dir = -self.dir;
            next = next.clamp(0.0, len);
        }
        let p = self.at(next);
        let here = self.centre();
        let blocked = robots.iter().any(|&(c, r)| {
            let gap = self.spec.r + r + KEEP_CLEAR_M;
            (p - c).norm() < gap && (p - c).norm() < (here - c).norm()
        });
        if blocked {
            self.dir = -self.dir;
            return;
        }
        self.s = next;
        self.solid.move_to(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> MoverSpec {
        MoverSpec {
            r: 0.3,
            from: [0.0, 0.0],
            to: [2.0, 0.0],
            speed: 1.0,
        }
    }

    #[test]
    fn it_walks_back_and_forth() {
        let mut m = Mover::new(spec());
        for _ in 0..15 {
            m.step(0.1, &[]);
        }
        // 1.5 m walked: at the far end after 2 m, so still going out at 1.5.
        assert!((m.centre().x - 1.5).abs() < 1e-9, "{:?}", m.centre());
        for _ in 0..10 {
            m.step(0.1, &[]);
        }
        // 2.5 m walked: turned at 2.0, back at 1.5 (the turn clamps one step to the end).
        assert!(m.centre().x < 2.0 && m.centre().x >= 1.4, "{:?}", m.centre());
    }

    #[test]
    fn it_turns_back_rather_than_walk_into_a_robot() {
        let mut m = Mover::new(spec());
        let robot = [(Point2::new(1.0, 0.0), 0.25)];
        for _ in 0..40 {
            m.step(0.05, &robot);
            assert!((m.centre() - robot[0].0).norm() >= 0.3 + 0.25 + KEEP_CLEAR_M - 0.05 - 1e-9);
        }
    }
}
