//! Positions on a polyline path: [`PathPos`] (segment and fraction) and arc length, in both directions.
//! The straight segments between consecutive waypoints are the path; waypoints may be far apart.

use crate::geom::Point2;

/// A point on segment `seg` of a path (between `path[seg]` and `path[seg + 1]`), at fraction `t` ∈ [0, 1]
/// of the segment's length from `path[seg]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPos {
    /// Segment index (0 ≤ seg < path.len() − 1).
    pub seg: usize,
    /// Fraction along the segment, in [0, 1].
    pub t: f64,
}

impl PathPos {
    /// Position at fraction `t` of segment `seg`.
    pub const fn new(seg: usize, t: f64) -> Self {
        Self { seg, t }
    }
}

/// Arclen-length table of a path: `s[i]` is the length (metres) from `path[0]` to `path[i]`.
#[derive(Debug, Clone)]
pub(crate) struct Arclen<'p> {
    pub(crate) path: &'p [Point2],
    pub(crate) s: Vec<f64>,
}

impl<'p> Arclen<'p> {
    pub(crate) fn new(path: &'p [Point2]) -> Self {
        let mut s = Vec::with_capacity(path.len());
        let mut acc = 0.0;
        for (i, p) in path.iter().enumerate() {
            if i > 0 {
                acc += (p - path[i - 1]).norm();
            }
            s.push(acc);
        }
        Self { path, s }
    }

    /// Total length, metres.
    pub(crate) fn total(&self) -> f64 {
        self.s.last().copied().unwrap_or(0.0)
    }

    /// Number of segments.
    pub(crate) fn segments(&self) -> usize {
        self.path.len().saturating_sub(1)
    }

    /// Arclen length of a position, metres.
    pub(crate) fn s_of(&self, pos: PathPos) -> f64 {
        let k = pos.seg.min(self.segments().saturating_sub(1));
        let len = self.s.get(k + 1).copied().unwrap_or(0.0) - self.s.get(k).copied().unwrap_or(0.0);
        self.s.get(k).copied().unwrap_or(0.0) + pos.t.clamp(0.0, 1.0) * len
    }

    /// Position at arc length `s` (clamped to the path). Ties at a waypoint go to the later segment, except at
    /// the very end.
    pub(crate) fn pos_at(&self, s: f64) -> PathPos {
        let n = self.segments();
        if n == 0 {
            return PathPos::new(0, 0.0);
        }
        let s = s.clamp(0.0, self.total());
        // Last segment k with s[k] <= s.
        let k = self.s.partition_point(|&v| v <= s).saturating_sub(1).min(n - 1);
        let len = self.s[k + 1] - self.s[k];
        let t = if len > 0.0 {
            ((s - self.s[k]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        PathPos::new(k, t)
    }

    /// Map-frame point of a position.
    pub(crate) fn point(&self, pos: PathPos) -> Point2 {
        let k = pos.seg.min(self.segments().saturating_sub(1));
        match (self.path.get(k), self.path.get(k + 1)) {
            (Some(a), Some(b)) => a + (b - a) * pos.t.clamp(0.0, 1.0),
            (Some(a), None) => *a,
            _ => Point2::origin(),
        }
    }

    /// Map-frame point at arc length `s`.
    pub(crate) fn point_at(&self, s: f64) -> Point2 {
        self.point(self.pos_at(s))
    }

    /// The original polyline between arc lengths `s0 ≤ s1`: both end points and every waypoint strictly
    /// between.
    pub(crate) fn slice(&self, s0: f64, s1: f64) -> Vec<Point2> {
        let mut out = vec![self.point_at(s0)];
        for (i, &si) in self.s.iter().enumerate() {
            if si > s0 && si < s1 {
                out.push(self.path[i]);
            }
        }
        if s1 > s0 {
            out.push(self.point_at(s1));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let path = [Point2::new(0.0, 0.0), Point2::new(10.0, 0.0), Point2::new(10.0, 5.0)];
        let arc = Arclen::new(&path);
        assert_eq!(arc.total(), 15.0);
        let p = arc.pos_at(12.5);
        assert_eq!(p.seg, 1);
        assert!((p.t - 0.5).abs() < 1e-12);
        assert!((arc.s_of(p) - 12.5).abs() < 1e-12);
        assert_eq!(arc.point_at(10.0), Point2::new(10.0, 0.0));
        assert_eq!(arc.pos_at(15.0), PathPos::new(1, 1.0));
        assert_eq!(arc.slice(5.0, 12.0).len(), 3);
    }
}
