//! Vertical sections of the surface across the lanes, and arc length along them: how lane spacing and coverage
//! are measured ON the surface (seed 000 §IV.B) rather than on the plane.

use super::surface::TerrainSurface;

/// The horizontal axis drone lanes run along; lanes are spaced along the other one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaneAxis {
    /// Lanes run along x (spaced along y).
    X,
    /// Lanes run along y (spaced along x).
    Y,
}

impl LaneAxis {
    /// Map-frame (x, y) of along-lane coordinate `t` and across coordinate `s`, metres.
    pub fn point(self, t: f64, s: f64) -> (f64, f64) {
        match self {
            LaneAxis::X => (t, s),
            LaneAxis::Y => (s, t),
        }
    }

    /// The surface domain's `[t_min, t_max]` (along the lanes) and `[s_min, s_max]` (across), metres.
    pub fn ranges(self, surface: &TerrainSurface) -> ([f64; 2], [f64; 2]) {
        let (lo, hi) = surface.domain();
        let (x, y) = ([lo[0], hi[0]], [lo[1], hi[1]]);
        match self {
            LaneAxis::X => (x, y),
            LaneAxis::Y => (y, x),
        }
    }
}

/// A vertical section of the surface at along-lane coordinate `t`, across the whole domain: the arc length
/// along the terrain from the domain's edge, sampled every `step` metres (in plan) and linear in between.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    s0: f64,
    step: f64,
    arc: Vec<f64>,
}

impl Section {
    /// Samples the section at `t` with a plan step of at most `max_step_m` (> 0).
    pub fn new(surface: &TerrainSurface, axis: LaneAxis, t: f64, max_step_m: f64) -> Self {
        let (_, [s0, s1]) = axis.ranges(surface);
        let intervals = (((s1 - s0) / max_step_m).ceil() as usize).max(1);
        let step = (s1 - s0) / intervals as f64;
        let mut arc = Vec::with_capacity(intervals + 1);
        let height = |s: f64, prev: f64| {
            let (x, y) = axis.point(t, s);
            surface.height_at(x, y).unwrap_or(prev)
        };
        let mut z = height(s0, 0.0);
        let mut a = 0.0;
        arc.push(0.0);
        for k in 1..=intervals {
            let zk = height(s0 + k as f64 * step, z);
            a += step.hypot(zk - z);
            arc.push(a);
            z = zk;
        }
        Self { s0, step, arc }
    }

    /// Arc length of the whole section, metres.
    pub fn total(&self) -> f64 {
        self.arc[self.arc.len() - 1]
    }

    /// Arc length from the edge to across coordinate `s` (clamped to the section), metres.
    pub fn arc_at(&self, s: f64) -> f64 {
        let last = self.arc.len() - 1;
        let f = ((s - self.s0) / self.step).clamp(0.0, last as f64);
        let k = (f as usize).min(last.saturating_sub(1));
        if last == 0 {
            return 0.0;
        }
        self.arc[k] + (f - k as f64) * (self.arc[k + 1] - self.arc[k])
    }

    /// Across coordinate at arc length `a` from the edge (clamped to the section), metres.
    pub fn s_at(&self, a: f64) -> f64 {
        let last = self.arc.len() - 1;
        let a = a.clamp(0.0, self.total());
        // First sample whose arc is ≥ a.
        let k = self.arc.partition_point(|&v| v < a).clamp(1, last.max(1));
        if last == 0 {
            return self.s0;
        }
        let (a0, a1) = (self.arc[k - 1], self.arc[k]);
        let f = if a1 > a0 { (a - a0) / (a1 - a0) } else { 0.0 };
        self.s0 + (k as f64 - 1.0 + f) * self.step
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;
    use crate::map::GridGeometry;

    #[test]
    fn arc_length_on_a_ramp_is_the_plan_length_over_the_cosine() {
        let geometry = GridGeometry::new(50, 30, 0.2, Point2::origin()).expect("geometry");
        let tilt = 30f64.to_radians();
        let s = TerrainSurface::from_fn(geometry, |x, _| x * tilt.tan()).expect("surface");
        let across_x = Section::new(&s, LaneAxis::Y, 3.0, 0.05);
        let plan = 49.0 * 0.2;
        assert!((across_x.total() - plan / tilt.cos()).abs() < 1e-9);
        let across_y = Section::new(&s, LaneAxis::X, 3.0, 0.05);
        assert!((across_y.total() - 29.0 * 0.2).abs() < 1e-9);
        // Inverse and forward agree.
        for a in [0.0, 1.0, 5.5, across_x.total()] {
            assert!((across_x.arc_at(across_x.s_at(a)) - a).abs() < 1e-9);
        }
        assert!((across_x.s_at(2.0) - (0.1 + 2.0 * tilt.cos())).abs() < 1e-9);
    }
}
