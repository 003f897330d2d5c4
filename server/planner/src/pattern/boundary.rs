//! Targeted passes: cover what the lanes (or rings) of a region missed, without blanket boundary laps.
//!
//! After the main pattern of every region and the steps between its lanes are stamped on the coverage
//! raster, each region looks at the cover targets it is responsible for that are still uncovered —
//! typically the scallops that lane ends leave along walls across the lanes, the saw-tooth bands along walls
//! at an angle to them, and the rims of round obstacles. [`candidates`] proposes:
//! 1. stretches of the region's contour whose cells are within half a tool width of an uncovered target,
//!    extended a little at both ends, merged across short gaps and cut into pieces of bounded length;
//! 2. for uncovered targets no stretch reaches: an excursion from a lane, ring or frame segment nearby
//!    (see [`super::excursion`]), else a single visit at the target's nearest reachable cell.
//!
//! [`select`] then picks candidates greedily by new coverage per metre of extra driving: every candidate at
//! least `min_yield` as productive as a lane is taken, and beyond that the most productive ones until the
//! coverage target is met. A plan thus covers the edges wherever that is cheap, and spends extra driving on
//! the last fractions of a percent only as far as the target asks.

use std::collections::BinaryHeap;

use super::excursion::{Excursion, Hosts};
use super::lanes::RegionView;
use super::{Task, TaskKind};
use crate::geom::{Point2, simplify_polyline};
use crate::map::DistanceField;
use crate::metrics::CoverageRaster;
use crate::metrics::coverage::for_each_cell_in_capsule;
use crate::space::CoverageSpace;

/// A proposed pass with the region it serves.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Region id.
    pub region: u32,
    /// The pass (for an excursion: the segment from where it leaves its host to where it turns back).
    pub task: Task,
    /// Set when the pass is an out-and-back from a task of the main pattern (see [`super::excursion`]).
    pub excursion: Option<Excursion>,
}

impl Candidate {
    /// Driving the candidate adds: its length twice (there and back along the wall, in the worst case)
    /// plus a tool width to turn off and on the lane set; an excursion is driven from its host, out and back.
    fn cost(&self, w: f64, res: f64) -> f64 {
        match &self.excursion {
            Some(e) => e.length() + res,
            None => 2.0 * self.task.length() + w,
        }
    }
}

/// Targeted-pass knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassParams {
    /// Keep adding the most productive passes until this share of coverable cells is covered, percent.
    pub coverage_target_pct: f64,
    /// Passes at least this productive relative to a lane (new cells per metre) are always taken.
    pub min_yield: f64,
    /// Longest single contour stretch, in tool widths (longer ones are cut so selection stays granular).
    pub max_stretch_widths: f64,
}

impl Default for PassParams {
    fn default() -> Self {
        Self {
            coverage_target_pct: 99.4,
            min_yield: 0.25,
            max_stretch_widths: 8.0,
        }
    }
}

/// Candidate passes, excursions from `hosts` (the region's main-pattern tasks) and visits for one region's
/// still-uncovered targets (nothing is stamped). `nearest_reachable` is the distance field whose sites are
/// the reachable cells.
pub fn candidates(
    space: &CoverageSpace,
    (region, contours): (RegionView<'_>, &[Vec<usize>]),
    (raster, hosts): (&CoverageRaster, &Hosts),
    nearest_reachable: &DistanceField,
    params: &PassParams,
) -> Vec<Candidate> {
    let g = *space.geometry();
    let res = g.resolution;
    let half = space.robot.tool_width_m / 2.0;
    let need = |i: usize| region.target_labels[i] == region.id && !raster.is_covered(i);
    if !region.targets.iter().any(|&i| need(i)) {
        return Vec::new();
    }
    let mut out = Vec::new();
    let rc = (half / res).ceil() as isize;
    // Uncovered targets within reach of a contour vertex.
    let reach_of = |i: usize, f: &mut dyn FnMut(usize)| {
        let c = g.cell(i);
        let p = g.center(c);
        for dy in -rc..=rc {
            for dx in -rc..=rc {
                if let Some(n) = g.offset(c, dx, dy) {
                    let j = g.index(n);
                    if need(j) && (g.center(n) - p).norm() <= half + 1e-9 {
                        f(j);
                    }
                }
            }
        }
    };
    let mut reached = std::collections::HashSet::new();
    let extend = rc.max(1) as usize;
    let merge_gap = (2 * rc).max(2) as usize;
    let max_len = ((params.max_stretch_widths * 2.0 * half) / res).ceil().max(4.0) as usize;
    for lp in contours {
        let n = lp.len();
        if n < 2 {
            continue;
        }
        let flags: Vec<bool> = lp
            .iter()
            .map(|&i| {
                let mut any = false;
                reach_of(i, &mut |j| {
                    any = true;
                    reached.insert(j);
                });
                any
            })
            .collect();
        if !flags.iter().any(|&f| f) {
            continue;
        }
        let mut keep = vec![false; n];
        for k in (0..n).filter(|&k| flags[k]) {
            for e in 0..=2 * extend.min(n) {
                keep[(k + n + e - extend.min(n)) % n] = true;
            }
        }
        close_gaps(&mut keep, merge_gap);
        for run in cyclic_runs(&keep) {
            for chunk in run.chunks(max_len) {
                let pts: Vec<Point2> = chunk.iter().map(|&k| g.center_of(lp[k])).collect();
                for piece in split_unsafe_steps(space, &pts) {
                    let simple = simplify_polyline(&piece, 0.5 * res, &|a, b| space.segment_ok(a, b));
                    out.push(Candidate {
                        region: region.id,
                        task: Task {
                            points: simple,
                            kind: TaskKind::Boundary,
                        },
                        excursion: None,
                    });
                }
            }
        }
    }
    // The targets no stretch reaches: an excursion where a host is near (one per cell it would turn back
    // in), else a visit. (Excursions for every uncovered target were tried: greedy selection then prefers
    // many small excursions along a wall band to one stretch along it, and the plans get longer.)
    let mut ends = std::collections::HashSet::new();
    for &t in region.targets {
        if !need(t) || reached.contains(&t) {
            continue;
        }
        if let Some(e) = hosts.excursion_to(space, g.center_of(t)) {
            if g.locate(e.end).is_some_and(|c| ends.insert(g.index(c))) {
                out.push(Candidate {
                    region: region.id,
                    task: Task {
                        points: vec![e.at, e.end],
                        kind: TaskKind::Boundary,
                    },
                    excursion: Some(e),
                });
            }
            continue;
        }
        let Some(r) = nearest_reachable.nearest_site_index(t) else {
            continue;
        };
        let p = g.center_of(r);
        out.push(Candidate {
            region: region.id,
            task: Task {
                points: vec![p],
                kind: TaskKind::Visit,
            },
            excursion: None,
        });
    }
    out
}

/// A candidate's (possibly stale) yield and its index: a max-heap entry, the higher index first among equal
/// yields.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ranked(f64, usize);

impl Eq for Ranked {}

impl PartialOrd for Ranked {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ranked {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

/// Greedy selection of candidates (see the module docs); stamps the chosen ones on `raster`.
pub fn select(
    space: &CoverageSpace,
    pool: Vec<Candidate>,
    raster: &mut CoverageRaster,
    params: &PassParams,
) -> Vec<Candidate> {
    let g = *space.geometry();
    let res = g.resolution;
    let w = space.robot.tool_width_m;
    let total = space.coverable_count().max(1);
    let mut covered = (0..g.len())
        .filter(|&i| space.coverable[i] && raster.is_covered(i))
        .count();
    // A lane covers w / res² new cells per metre; see [`Candidate::cost`].
    let lane_yield = w / (res * res);
    // Cells a candidate would newly cover, counted once even where its segments' capsules overlap: a
    // per-cell stamp (one allocation for the whole selection) instead of a set per evaluation.
    let mut stamp_of = vec![0u32; g.len()];
    let mut stamp = 0u32;
    let mut gain = |raster: &CoverageRaster, t: &Task| -> usize {
        stamp += 1;
        let mut count = 0;
        let pts = &t.points;
        let segs = if pts.len() == 1 {
            vec![(pts[0], pts[0])]
        } else {
            pts.windows(2).map(|s| (s[0], s[1])).collect()
        };
        for (a, b) in segs {
            for_each_cell_in_capsule(&g, a, b, w / 2.0 + 1e-9, |i| {
                if space.coverable[i] && !raster.is_covered(i) && stamp_of[i] != stamp {
                    stamp_of[i] = stamp;
                    count += 1;
                }
            });
        }
        count
    };
    let mut chosen = Vec::new();
    // Lazy greedy: yields only fall as coverage grows, so a stale upper bound that still tops the heap after
    // a refresh is the true best.
    let mut heap: BinaryHeap<Ranked> = pool
        .iter()
        .enumerate()
        .map(|(k, c)| Ranked(gain(raster, &c.task) as f64 / c.cost(w, res), k))
        .filter(|r| r.0 > 0.0)
        .collect();
    let mut pool: Vec<Option<Candidate>> = pool.into_iter().map(Some).collect();
    while let Some(Ranked(stale, k)) = heap.pop() {
        let Some(candidate) = pool[k].as_ref() else {
            continue;
        };
        let cells = gain(raster, &candidate.task);
        let fresh = cells as f64 / candidate.cost(w, res);
        if fresh + 1e-12 < stale {
            if fresh > 0.0 {
                heap.push(Ranked(fresh, k));
            }
            continue;
        }
        let pct = covered as f64 / total as f64 * 100.0;
        if fresh < params.min_yield * lane_yield && pct >= params.coverage_target_pct {
            break;
        }
        if let Some(c) = pool[k].take() {
            raster.stamp_polyline(&c.task.points);
            covered += cells;
            chosen.push(c);
        }
    }
    chosen
}

/// Sets `keep` over every run of `false` (cyclic) no longer than `gap` that lies between kept vertices.
pub(crate) fn close_gaps(keep: &mut [bool], gap: usize) {
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
pub(crate) fn cyclic_runs(keep: &[bool]) -> Vec<Vec<usize>> {
    let n = keep.len();
    if keep.iter().all(|&k| k) {
        let mut all: Vec<usize> = (0..n).collect();
        all.push(0);
        return vec![all];
    }
    let Some(start) = (0..n).find(|&k| !keep[k]) else {
        return Vec::new();
    };
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
pub(crate) fn split_unsafe_steps(space: &CoverageSpace, pts: &[Point2]) -> Vec<Vec<Point2>> {
    let mut out = Vec::new();
    let mut cur: Vec<Point2> = Vec::new();
    for &p in pts {
        if let Some(&last) = cur.last()
            && !space.segment_ok(last, p)
        {
            out.push(std::mem::take(&mut cur));
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
        assert_eq!(
            keep,
            vec![true, true, true, true, false, false, false, false, true, true]
        );
        let runs = cyclic_runs(&keep);
        assert_eq!(runs, vec![vec![8, 9, 0, 1, 2, 3]]);
        assert_eq!(cyclic_runs(&[true, true]), vec![vec![0, 1, 0]]);
        assert!(cyclic_runs(&[false, false]).is_empty());
    }
}
