//! Targeted passes: cover what the lanes (or rings) of a region missed, without blanket boundary laps.
//!
//! After the main pattern of every region is stamped on the coverage raster, each region looks at the cover
//! targets it is responsible for that are still uncovered — typically the saw-tooth bands along walls that
//! are not parallel to its lanes, and the rims of round obstacles. It then:
//! 1. walks its contour (the region's boundary loops) and keeps only the stretches whose cells are within
//!    half a tool width of an uncovered target, extended a little at both ends and merged across short gaps
//!    (driving on along the wall beats leaving and coming back);
//! 2. covers anything still left (pockets the contour does not reach) by single visits at the reachable cell
//!    nearest to it.

use super::contour::trace_loops;
use super::lanes::RegionView;
use super::{Task, TaskKind};
use crate::geom::{Point2, simplify_polyline};
use crate::map::DistanceField;
use crate::metrics::CoverageRaster;
use crate::space::CoverageSpace;

/// Passes and visits that cover the region's still-uncovered targets; stamps them on `raster`.
/// `nearest_reachable` is the distance field whose sites are the reachable cells.
pub fn targeted_passes(
    space: &CoverageSpace,
    region: RegionView<'_>,
    raster: &mut CoverageRaster,
    nearest_reachable: &DistanceField,
) -> Vec<Task> {
    let g = *space.geometry();
    let res = g.resolution;
    let half = space.robot.tool_width_m / 2.0;
    let need = |raster: &CoverageRaster, i: usize| region.target_labels[i] == region.id && !raster.is_covered(i);
    if !region.targets.iter().any(|&i| need(raster, i)) {
        return Vec::new();
    }
    let mut tasks = Vec::new();
    // 1. Contour stretches.
    let mut mask = vec![false; g.len()];
    for &i in region.cells {
        mask[i] = true;
    }
    let rc = (half / res).ceil() as isize;
    let useful = |raster: &CoverageRaster, i: usize| -> bool {
        let c = g.cell(i);
        let p = g.center(c);
        for dy in -rc..=rc {
            for dx in -rc..=rc {
                if let Some(n) = g.offset(c, dx, dy) {
                    let j = g.index(n);
                    if need(raster, j) && (g.center(n) - p).norm() <= half + 1e-9 {
                        return true;
                    }
                }
            }
        }
        false
    };
    let extend = rc.max(1) as usize;
    let merge_gap = (4 * rc).max(2) as usize;
    for lp in trace_loops(&g, &mask) {
        let n = lp.len();
        if n < 2 {
            continue;
        }
        let flags: Vec<bool> = lp.iter().map(|&i| useful(raster, i)).collect();
        if !flags.iter().any(|&f| f) {
            continue;
        }
        // Grow each useful vertex by `extend` on both sides (cyclically), then close gaps up to `merge_gap`.
        let mut keep = vec![false; n];
        for k in (0..n).filter(|&k| flags[k]) {
            for e in 0..=2 * extend {
                keep[(k + n + e - extend.min(n)) % n] = true;
            }
        }
        close_gaps(&mut keep, merge_gap);
        for run in cyclic_runs(&keep) {
            let pts: Vec<Point2> = run.iter().map(|&k| g.center_of(lp[k])).collect();
            for piece in split_unsafe_steps(space, &pts) {
                let simple = simplify_polyline(&piece, 0.5 * res, &|a, b| space.segment_ok(a, b));
                raster.stamp_polyline(&simple);
                tasks.push(Task { points: simple, kind: TaskKind::Boundary });
            }
        }
    }
    // 2. Visits for whatever is left.
    for &t in region.targets {
        if !need(raster, t) {
            continue;
        }
        let Some(r) = nearest_reachable.nearest_site_index(t) else { continue };
        let p = g.center_of(r);
        raster.stamp_segment(p, p);
        tasks.push(Task { points: vec![p], kind: TaskKind::Visit });
    }
    tasks
}

/// Sets `keep` over every run of `false` (cyclic) no longer than `gap` that lies between kept vertices.
fn close_gaps(keep: &mut [bool], gap: usize) {
    let n = keep.len();
    if keep.iter().all(|&k| k) || !keep.iter().any(|&k| k) {
        return;
    }
    let Some(start) = (0..n).find(|&k| keep[k]) else { return };
    let mut k = 0;
    while k < n {
        let i = (start + k) % n;
        if keep[i] {
            k += 1;
            continue;
        }
        let mut len = 0;
        while len < n && !keep[(start + k + len) % n] {
            len += 1;
        }
        if len <= gap {
            for j in 0..len {
                keep[(start + k + j) % n] = true;
            }
        }
        k += len;
    }
}

/// Maximal runs of kept vertices along a closed loop, as vertex index lists in loop order. A fully kept loop
/// comes back closed (its first vertex repeated at the end).
fn cyclic_runs(keep: &[bool]) -> Vec<Vec<usize>> {
    let n = keep.len();
    if keep.iter().all(|&k| k) {
        let mut all: Vec<usize> = (0..n).collect();
        all.push(0);
        return vec![all];
    }
    let Some(start) = (0..n).find(|&k| !keep[k]) else { return Vec::new() };
    let mut runs = Vec::new();
    let mut cur: Vec<usize> = Vec::new();
    for k in 1..=n {
        let i = (start + k) % n;
        if keep[i] {
            cur.push(i);
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

/// Splits a chain of cell centres wherever a step between neighbours would lose clearance.
fn split_unsafe_steps(space: &CoverageSpace, pts: &[Point2]) -> Vec<Vec<Point2>> {
    let mut out = Vec::new();
    let mut cur: Vec<Point2> = Vec::new();
    for &p in pts {
        if let Some(&last) = cur.last() {
            if !space.segment_ok(last, p) {
                out.push(std::mem::take(&mut cur));
            }
        }
        cur.push(p);
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_and_runs() {
        let mut keep = vec![true, false, false, true, false, false, false, false, true, true];
        close_gaps(&mut keep, 2);
        assert_eq!(keep, vec![true, true, true, true, false, false, false, false, true, true]);
        let runs = cyclic_runs(&keep);
        assert_eq!(runs, vec![vec![8, 9, 0, 1, 2, 3]]);
        assert_eq!(cyclic_runs(&[true, true]), vec![vec![0, 1, 0]]);
        assert!(cyclic_runs(&[false, false]).is_empty());
    }
}
