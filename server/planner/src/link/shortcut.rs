//! Line-of-sight shortcutting that keeps clearance.
//!
//! A grid path is a chain of cell centres. We replace runs of it by straight segments, greedily jumping from
//! the current vertex to the farthest later vertex whose segment is `segment_ok` **and** keeps, at every
//! sample, a clearance of at least `min(radius + preferred, the smallest clearance of the replaced
//! sub-path)`. So a shortcut never brings the path closer to walls than the preferred distance, or than the
//! grid path itself already came in that stretch.
//!
//! Testing every later vertex from every vertex is quadratic in the path length (thousands of cells for a
//! long link), so the farthest visible vertex is found in two passes:
//! 1. on the cell chain, a galloping search (try 2, 4, 8, … vertices ahead, then bisect between the last
//!    success and the first failure) — O(log n) segment checks per kept vertex;
//! 2. on the few vertices pass 1 kept, the exact farthest-visible rule (scanning from the farthest
//!    candidate down, at most [`LOOKAHEAD`] ahead).
//!
//! Clearance is sampled exactly where `CoverageSpace::segment_ok` samples (every quarter cell, both ends
//! included), so a segment that passes here passes `segment_ok`.

use crate::geom::Point2;
use crate::space::CoverageSpace;

/// How many kept vertices ahead pass 2 looks (bounds its cost on paths that stay winding after pass 1).
pub const LOOKAHEAD: usize = 32;

/// Tolerance of the radius test, as in `CoverageSpace::point_ok`.
const RADIUS_TOL: f64 = 1e-9;

/// The sample points of segment `a`–`b`, exactly as `CoverageSpace::segment_ok` takes them.
#[inline]
fn samples(space: &CoverageSpace, a: Point2, b: Point2) -> impl Iterator<Item = Point2> {
    let len = (b - a).norm();
    let step = space.geometry().resolution * 0.25;
    let n = (len / step).ceil().max(1.0) as usize;
    (0..=n).map(move |k| a + (b - a) * (k as f64 / n as f64))
}

/// True when segment `a`–`b` passes `segment_ok` and every sample has clearance ≥ `need` metres.
pub(crate) fn segment_keeps(space: &CoverageSpace, a: Point2, b: Point2, need: f64) -> bool {
    let g = space.geometry();
    let threshold = need.max(space.robot.radius_m - RADIUS_TOL);
    samples(space, a, b).all(|p| {
        let Some(c) = g.locate(p) else { return false };
        let i = g.index(c);
        space.reachable[i] && space.has_clearance(p, threshold)
    })
}

/// Smallest clearance over the samples of segment `a`–`b`, but never more than `cap` (samples that are
/// certainly above `cap` are not evaluated exactly).
fn segment_min_clearance_capped(space: &CoverageSpace, a: Point2, b: Point2, cap: f64) -> f64 {
    let g = space.geometry();
    samples(space, a, b).fold(cap, |m, p| match g.locate(p) {
        Some(_) if space.clearance_lower_bound(p) >= m => m,
        _ => m.min(space.clearance_at(p)),
    })
}

/// Smallest clearance (distance to the nearest non-free cell centre, metres) over the points where
/// `segment_ok` samples segment `a`–`b`.
pub fn segment_min_clearance(space: &CoverageSpace, a: Point2, b: Point2) -> f64 {
    samples(space, a, b)
        .map(|p| space.clearance_at(p))
        .fold(f64::INFINITY, f64::min)
}

/// Smallest sampled clearance along a polyline, metres (∞ for fewer than two points).
pub fn path_min_clearance(space: &CoverageSpace, path: &[Point2]) -> f64 {
    path.windows(2)
        .map(|w| segment_min_clearance(space, w[0], w[1]))
        .fold(f64::INFINITY, f64::min)
}

/// Shortcuts `path` (map frame, metres; consecutive points `segment_ok`), keeping its first and last points.
/// Every new segment is `segment_ok` and keeps a sampled clearance of at least
/// `min(radius + preferred_clearance_m, smallest clearance of the part of path it replaces)`.
pub fn shortcut(space: &CoverageSpace, path: &[Point2], preferred_clearance_m: f64) -> Vec<Point2> {
    if path.len() <= 2 {
        return path.to_vec();
    }
    let need = space.robot.radius_m + preferred_clearance_m.max(0.0);
    // Clearance of each original segment, capped at `need` (all that the rule ever asks for).
    let seg_min: Vec<f64> = path
        .windows(2)
        .map(|w| segment_min_clearance_capped(space, w[0], w[1], need))
        .collect();
    let visible = |i: usize, j: usize| -> bool {
        let replaced = seg_min[i..j].iter().copied().fold(need, f64::min);
        segment_keeps(space, path[i], path[j], replaced)
    };
    let last = path.len() - 1;

    // Pass 1: galloping search along the chain.
    let mut kept = vec![0usize];
    let mut i = 0;
    while i < last {
        let mut good = i + 1;
        let mut ahead = 2;
        let mut bad = None;
        while good < last {
            let j = (i + ahead).min(last);
            if visible(i, j) {
                good = j;
                ahead *= 2;
            } else {
                bad = Some(j);
                break;
            }
        }
        if let Some(mut hi) = bad {
            while hi - good > 1 {
                let mid = good + (hi - good) / 2;
                if visible(i, mid) {
                    good = mid;
                } else {
                    hi = mid;
                }
            }
        }
        kept.push(good);
        i = good;
    }

    // Pass 2: farthest visible among the kept vertices.
    let mut out = vec![path[0]];
    let mut k = 0;
    while k < kept.len() - 1 {
        let far = (k + LOOKAHEAD).min(kept.len() - 1);
        let next = (k + 2..=far)
            .rev()
            .find(|&m| visible(kept[k], kept[m]))
            .unwrap_or(k + 1);
        out.push(path[kept[next]]);
        k = next;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{Rng, random_point, random_space};
    use super::super::{LinkParams, Linker};
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn keeps_clearance_rule_on_a_corridor() {
        // A wall along y = 1 m; a path hugging it at 0.35 m and one far away: shortcutting across must not
        // come closer than radius + preferred.
        let g = crate::map::GridGeometry::new(60, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = crate::map::OccupancyGrid::filled(g, crate::map::CellState::Free);
        grid.fill_rect(2.0, 0.0, 4.0, 1.0, crate::map::CellState::Occupied);
        let robot = crate::space::RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        };
        let s = CoverageSpace::new(grid, robot, Point2::new(0.5, 0.5)).expect("space");
        // Around the block at a distance of ~1 m.
        let path = vec![
            Point2::new(0.55, 0.55),
            Point2::new(1.05, 2.05),
            Point2::new(3.05, 2.25),
            Point2::new(4.95, 2.05),
            Point2::new(5.45, 0.55),
        ];
        for w in path.windows(2) {
            assert!(s.segment_ok(w[0], w[1]));
        }
        let out = shortcut(&s, &path, 0.5);
        assert_eq!(out[0], path[0]);
        assert_eq!(out[out.len() - 1], path[4]);
        assert!(path_min_clearance(&s, &out) >= (0.65f64).min(path_min_clearance(&s, &path)) - 1e-9);
        // The middle vertex can go (the straight 1 m-away segment keeps 0.65 m).
        assert!(out.len() < path.len(), "{out:?}");
    }

    #[test]
    fn short_paths_pass_through() {
        let s = random_space(7, 20, 20, 0, 0.1).expect("space");
        let p = vec![Point2::new(0.0, 3.0), Point2::new(0.3, 3.2)];
        assert_eq!(shortcut(&s, &p, 0.1), p);
        assert_eq!(path_min_clearance(&s, &p[..1]), f64::INFINITY);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        #[test]
        fn never_lowers_clearance_below_the_rule(
            seed in any::<u64>(), w in 12usize..48, h in 12usize..48, obstacles in 0usize..14,
            radius in 0.08f64..0.26, pref in 0.0f64..0.5,
        ) {
            let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
            let mut rng = Rng::new(seed ^ 0x5151);
            let (a, b) = (random_point(&s, &mut rng), random_point(&s, &mut rng));
            let Some(grid) = Linker::new(&s, &LinkParams::default()).grid_path(a, b) else { return Ok(()) };
            let out = shortcut(&s, &grid.points, pref);
            prop_assert_eq!(out[0], a);
            prop_assert_eq!(*out.last().expect("non-empty"), b);
            // Every new segment keeps min(need, clearance of what it replaced); in particular the whole path
            // keeps min(need, the original's minimum).
            let need = radius + pref;
            let orig = path_min_clearance(&s, &grid.points);
            prop_assert!(path_min_clearance(&s, &out) >= need.min(orig) - 1e-9);
            let mut j = 0;
            for seg in out.windows(2) {
                prop_assert!(s.segment_ok(seg[0], seg[1]));
                // Locate the replaced stretch of the original.
                let start = j;
                while grid.points[j] != seg[1] { j += 1; }
                let replaced = path_min_clearance(&s, &grid.points[start..=j]);
                prop_assert!(segment_min_clearance(&s, seg[0], seg[1]) >= need.min(replaced) - 1e-9);
            }
            prop_assert!(crate::geom::polyline_length(&out) <= crate::geom::polyline_length(&grid.points) + 1e-9);
        }
    }
}
