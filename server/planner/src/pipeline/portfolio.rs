//! Choosing among strategies: every combination a request leaves open (the `auto` decomposition's members,
//! the lane placements when none is fixed) is prepared up to its tour, the best [`Estimate`] wins, and only
//! the winner is linked — so links are searched once, and the monitor's region-ready calls are final.
//!
//! Ranking: plans that meet the coverage bar beat those that do not; then the least estimated overlap
//! (DESIGN §6: for equal coverage, the shortest path); earlier members win ties.

use crate::decompose::DecompositionMethod;
use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use crate::pattern::PatternMethod;
use crate::pattern::lanes::{LaneParams, Placement};
use crate::space::CoverageSpace;

use super::assemble::assemble;
use super::prepare::{Estimate, Prepared, prepare};
use super::{AUTO_SPIRAL_MAX_CELLS, FRAMED_MAX_CELLS, PlanMonitor, PlanOutput, PlanParams, RegionSummary};

/// Share of the progress bar the preparations take (the rest is linking the winner).
const PREPARE_SHARE: f64 = 0.75;

/// See the module docs.
pub fn plan(space: &CoverageSpace, params: &PlanParams, monitor: &mut dyn PlanMonitor) -> Result<PlanOutput> {
    let members = members(space, params);
    let n = members.len();
    let target = params.passes.coverage_target_pct.min(99.0);
    let mut best: Option<Prepared> = None;
    for (k, member) in members.iter().enumerate() {
        let mut scaled = Scaled {
            inner: &mut *monitor,
            lo: PREPARE_SHARE * k as f64 / n as f64,
            span: 1.0 / n as f64,
        };
        let candidate = prepare(space, member, &mut scaled)?;
        if best
            .as_ref()
            .is_none_or(|b| better(&candidate.estimate, &b.estimate, target))
        {
            best = Some(candidate);
        }
    }
    let best = best.ok_or(PlannerError::Cancelled)?;
    assemble(space, best, monitor)
}

/// The strategies `params` leaves open, in tie-breaking order.
pub fn members(space: &CoverageSpace, params: &PlanParams) -> Vec<PlanParams> {
    let reachable = space.reachable_count();
    let mut strategies: Vec<(DecompositionMethod, PatternMethod)> = if params.decomposition == DecompositionMethod::Auto
    {
        let mut s = vec![
            (DecompositionMethod::Bcd, params.pattern),
            (DecompositionMethod::Walls, params.pattern),
        ];
        // The undivided spiral's routing and pass selection grow faster than linearly with the area (one
        // region holding every ring); on large sites it costs minutes, so it only joins below this size.
        if reachable <= AUTO_SPIRAL_MAX_CELLS {
            s.push((DecompositionMethod::Single, PatternMethod::Spiral));
        }
        s
    } else {
        vec![(params.decomposition, params.pattern)]
    };
    let placements: &[Placement] = if reachable <= FRAMED_MAX_CELLS {
        &[Placement::Lattice, Placement::Fit, Placement::Framed]
    } else {
        &[Placement::Lattice, Placement::Fit]
    };
    let mut out = Vec::new();
    for (decomposition, pattern) in strategies.drain(..) {
        let base = PlanParams {
            decomposition,
            pattern,
            ..params.clone()
        };
        if pattern != PatternMethod::Lanes || params.lanes.placement.is_some() {
            out.push(base);
            continue;
        }
        for &p in placements {
            out.push(PlanParams {
                lanes: LaneParams {
                    placement: Some(p),
                    ..params.lanes
                },
                ..base.clone()
            });
        }
    }
    out
}

/// True when `a` ranks strictly above `b` (see the module docs).
fn better(a: &Estimate, b: &Estimate, target_pct: f64) -> bool {
    match (a.good(target_pct), b.good(target_pct)) {
        (true, false) => true,
        (false, true) => false,
        (true, true) => a.overlap_pct + 1e-9 < b.overlap_pct,
        // Neither meets the bar: more coverage first.
        (false, false) => a.coverage_pct > b.coverage_pct + 1e-9,
    }
}

/// Maps a member's preparation progress (0 … [`PREPARE_SHARE`]) into its slice of the bar.
struct Scaled<'a> {
    inner: &'a mut dyn PlanMonitor,
    lo: f64,
    span: f64,
}

impl PlanMonitor for Scaled<'_> {
    fn progress(&mut self, fraction: f64) {
        self.inner.progress(self.lo + self.span * fraction);
    }
    fn cancelled(&self) -> bool {
        self.inner.cancelled()
    }
    fn region_ready(&mut self, _region: &RegionSummary, _path: &[Point2]) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::tests::random_space;

    #[test]
    fn members_cover_every_open_choice_once() {
        let space = random_space(4, 50, 40, 4).expect("space");
        let auto = members(&space, &PlanParams::default());
        let names: Vec<(DecompositionMethod, PatternMethod, Option<Placement>)> = auto
            .iter()
            .map(|m| (m.decomposition, m.pattern, m.lanes.placement))
            .collect();
        let mut want = Vec::new();
        for d in [DecompositionMethod::Bcd, DecompositionMethod::Walls] {
            for p in [Placement::Lattice, Placement::Fit, Placement::Framed] {
                want.push((d, PatternMethod::Lanes, Some(p)));
            }
        }
        want.push((DecompositionMethod::Single, PatternMethod::Spiral, None));
        assert_eq!(names, want);
        // Everything fixed: exactly the request.
        let fixed = PlanParams {
            decomposition: DecompositionMethod::Grid,
            lanes: LaneParams {
                placement: Some(Placement::Fit),
                ..LaneParams::default()
            },
            ..PlanParams::default()
        };
        assert_eq!(members(&space, &fixed), vec![fixed]);
    }

    #[test]
    fn ranking_puts_the_coverage_bar_before_overlap() {
        let e = |coverage_pct: f64, overlap_pct: f64| Estimate {
            coverage_pct,
            length_m: 1.0,
            overlap_pct,
        };
        assert!(better(&e(99.5, 30.0), &e(98.0, 5.0), 99.0));
        assert!(!better(&e(98.0, 5.0), &e(99.5, 30.0), 99.0));
        assert!(better(&e(99.2, 10.0), &e(99.9, 12.0), 99.0));
        assert!(
            !better(&e(99.2, 10.0), &e(99.2, 10.0), 99.0),
            "ties keep the earlier member"
        );
        assert!(
            better(&e(97.0, 50.0), &e(96.0, 5.0), 99.0),
            "below the bar: more coverage first"
        );
    }
}
