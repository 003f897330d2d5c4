//! Spiral pattern: rings from the region's edge inwards, one tool width apart.
//!
//! Ring k is the contour of the region cells at least `res + k · tool_width` from the region's outside
//! (distance transform on the region's bounding box). Each ring is a closed task; the ordering stage picks
//! where each ring is entered and in which direction, which yields the inward spiral.

use super::contour::trace_from;
use super::lanes::RegionView;
use super::{Task, TaskKind};
use crate::geom::{Point2, simplify_polyline};
use crate::map::{DistanceField, GridGeometry};
use crate::space::CoverageSpace;

/// Rings of a region, outermost first.
pub fn plan_rings(space: &CoverageSpace, region: RegionView<'_>) -> Vec<Task> {
    let g = *space.geometry();
    let res = g.resolution;
    let w = space.robot.tool_width_m;
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for &i in region.cells {
        let c = g.cell(i);
        (x0, y0, x1, y1) = (x0.min(c.x), y0.min(c.y), x1.max(c.x), y1.max(c.y));
    }
    if x0 == usize::MAX {
        return Vec::new();
    }
    let (bw, bh) = (x1 - x0 + 1, y1 - y0 + 1);
    let Ok(sub) = GridGeometry::new(
        bw,
        bh,
        res,
        g.center(crate::map::Cell::new(x0, y0)) - nalgebra::Vector2::new(res / 2.0, res / 2.0),
    ) else {
        return Vec::new();
    };
    let global = |j: usize| (y0 + j / bw) * g.width + x0 + j % bw;
    let inside: Vec<bool> = (0..sub.len()).map(|j| region.labels[global(j)] == region.id).collect();
    let depth = DistanceField::compute(sub, |j| !inside[j], true);
    // Level k holds the cells at least `res + k·w` deep. A cell lies on the boundary of level k when it is in
    // it and a 4-neighbour (or the outside) is not: bucket every cell under the levels it bounds, in one pass,
    // so tracing all rings costs O(region) rather than O(levels × region).
    let level_of = |k: usize| res + k as f64 * w - 1e-9;
    let mut buckets: Vec<Vec<usize>> = Vec::new();
    for j in (0..sub.len()).filter(|&j| inside[j]) {
        let d = depth.at(j);
        let c = sub.cell(j);
        let dmin = [(0, 1), (0, -1), (1, 0), (-1, 0)]
            .iter()
            .map(|&(dx, dy)| {
                sub.offset(c, dx, dy).map_or(f64::NEG_INFINITY, |n| {
                    let i = sub.index(n);
                    if inside[i] { depth.at(i) } else { f64::NEG_INFINITY }
                })
            })
            .fold(f64::INFINITY, f64::min);
        // Levels k with dmin < level(k) <= d.
        let mut k = if dmin.is_finite() {
            ((dmin - res) / w).floor().max(-1.0) as i64 + 1
        } else {
            0
        } as usize;
        while level_of(k) <= d {
            if level_of(k) > dmin {
                if buckets.len() <= k {
                    buckets.resize(k + 1, Vec::new());
                }
                buckets[k].push(j);
            }
            k += 1;
        }
    }
    let mut visited = vec![0u32; sub.len()];
    let mut tasks = Vec::new();
    for (k, starts) in buckets.iter().enumerate() {
        let level = level_of(k);
        let mask = |j: usize| inside[j] && depth.at(j) >= level;
        for lp in trace_from(&sub, &mask, starts.iter().copied(), &mut visited, k as u32 + 1) {
            let mut pts: Vec<Point2> = lp.iter().map(|&j| sub.center_of(j)).collect();
            if pts.len() > 2 {
                pts.push(pts[0]);
            }
            // Split where a diagonal step would cut a corner too closely.
            let mut piece: Vec<Point2> = Vec::new();
            let flush = |piece: &mut Vec<Point2>, tasks: &mut Vec<Task>| {
                if !piece.is_empty() {
                    let simple = simplify_polyline(piece, 0.5 * res, &|a, b| space.segment_ok(a, b));
                    tasks.push(Task {
                        points: densify(&simple, w),
                        kind: TaskKind::Ring,
                    });
                    piece.clear();
                }
            };
            for p in pts {
                if let Some(&last) = piece.last()
                    && !space.segment_ok(last, p)
                {
                    flush(&mut piece, &mut tasks);
                }
                piece.push(p);
            }
            flush(&mut piece, &mut tasks);
        }
    }
    tasks
}

/// `points` with vertices added so that no segment is longer than `max_m` (same course): a route may enter
/// and leave a ring at any vertex, so the vertex nearest a neighbouring ring is never far from the nearest
/// point.
fn densify(points: &[Point2], max_m: f64) -> Vec<Point2> {
    let mut out = Vec::with_capacity(points.len());
    for s in points.windows(2) {
        let n = ((s[1] - s[0]).norm() / max_m).ceil().max(1.0) as usize;
        out.extend((0..n).map(|k| s[0] + (s[1] - s[0]) * (k as f64 / n as f64)));
    }
    out.extend(points.last());
    out
}
