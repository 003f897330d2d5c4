//! Choosing among strategies: every combination a request leaves open (the `auto` decomposition's members,
//! the lane placements when none is fixed) is prepared up to its tour, the best [`Estimate`] wins, and only
//! the winner is linked — so links are searched once, and the monitor's region-ready calls are final.
//!
//! Ranking ([`super::objective`]): plans that meet the coverage bar beat those that do not; then the
//! request's objective (default: the least estimated driving time); earlier members win ties. When speeds follow an
//! attribute map, the best few are linked and the profiled dwell decides among them ([`super::shaped`]).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock, mpsc};
use std::time::Duration;

use crate::decompose::DecompositionMethod;
use crate::error::{PlannerError, Result};
use crate::link::DistancesFrom;
use crate::pattern::PatternMethod;
use crate::pattern::lanes::{LaneParams, Placement};
use crate::space::CoverageSpace;

use super::assemble::assemble;
use super::objective::{compare_keys, rank_keys};
use super::prepare::{Basis, Prepared, nearest_reachable, prepare};
use super::{LARGE_SITE_CELLS, OVERLAP_BAR_PCT, PlanMonitor, PlanOutput, PlanParams};

/// Share of the progress bar the preparations take (the rest is linking the winner).
const PREPARE_SHARE: f64 = 0.75;

/// How often, at least, the calling thread polls its monitor for cancellation while workers prepare.
const POLL: Duration = Duration::from_millis(10);

/// See the module docs. The strategies are prepared on [`PlanParams::threads`] worker threads while the
/// calling thread relays cancellation and progress; decompositions shared by several strategies are built
/// once. Which strategy wins does not depend on the threads: every one is prepared and they are ranked in
/// member order.
pub fn plan(space: &CoverageSpace, params: &PlanParams, monitor: &mut dyn PlanMonitor) -> Result<PlanOutput> {
    let best = prepare_ranked(space, params, monitor)?
        .prepared
        .into_iter()
        .next()
        .ok_or(PlannerError::Cancelled)?;
    assemble(space, best, monitor)
}

/// Prepared strategies, best first, and the strategies held in reserve (not prepared yet).
pub struct Ranked {
    /// Best first (ties in member order).
    pub prepared: Vec<Prepared>,
    /// Strategies prepared only when those above fall short.
    reserve: Vec<PlanParams>,
}

impl Ranked {
    /// Prepares the reserve and returns it ranked (empty when there was none); `prepared` is left alone.
    pub fn prepare_reserve(
        &mut self,
        space: &CoverageSpace,
        params: &PlanParams,
        monitor: &mut dyn PlanMonitor,
    ) -> Result<Vec<Prepared>> {
        let reserve = std::mem::take(&mut self.reserve);
        if reserve.is_empty() {
            return Ok(Vec::new());
        }
        let mut more = prepare_members(space, params, &reserve, monitor)?;
        rank(&mut more, coverage_bar(params), params);
        Ok(more)
    }
}

/// Every strategy `params` leaves open, prepared up to its tour and ranked (see the module docs);
/// `monitor` sees progress 0 … 0.75. The reserve is prepared (and ranked in) only when no first-choice
/// strategy is [`economical`].
pub fn prepare_ranked(space: &CoverageSpace, params: &PlanParams, monitor: &mut dyn PlanMonitor) -> Result<Ranked> {
    let (first, reserve) = members(space, params);
    let target = coverage_bar(params);
    let mut ranked = Ranked {
        prepared: prepare_members(space, params, &first, monitor)?,
        reserve,
    };
    rank(&mut ranked.prepared, target, params);
    let short = ranked
        .prepared
        .first()
        .is_none_or(|p| !economical(p.estimate.coverage_pct, p.estimate.overlap_pct, target));
    if short {
        let more = ranked.prepare_reserve(space, params, monitor)?;
        ranked.prepared.extend(more);
        rank(&mut ranked.prepared, target, params);
    }
    Ok(ranked)
}

/// Meets the coverage bar `target_pct` with overlap within [`OVERLAP_BAR_PCT`].
pub fn economical(coverage_pct: f64, overlap_pct: f64, target_pct: f64) -> bool {
    coverage_pct + 1e-9 >= target_pct && overlap_pct <= OVERLAP_BAR_PCT
}

/// Sorts `prepared` best first by `params`' objective ([`rank_keys`]); a stable sort, so equal estimates keep
/// member order.
fn rank(prepared: &mut Vec<Prepared>, target: f64, params: &PlanParams) {
    let estimates: Vec<_> = prepared.iter().map(|p| p.estimate).collect();
    let keys = rank_keys(&estimates, target, params.objective);
    let mut order: Vec<usize> = (0..prepared.len()).collect();
    order.sort_by(|&a, &b| compare_keys(&keys[a], &keys[b]));
    let mut slots: Vec<Option<Prepared>> = std::mem::take(prepared).into_iter().map(Some).collect();
    prepared.extend(order.into_iter().filter_map(|k| slots[k].take()));
}

/// `members` prepared side by side, in member order.
fn prepare_members(
    space: &CoverageSpace,
    params: &PlanParams,
    members: &[PlanParams],
    monitor: &mut dyn PlanMonitor,
) -> Result<Vec<Prepared>> {
    let n = members.len();
    let threads = match params.threads {
        0 => std::thread::available_parallelism().map_or(1, |t| t.get()),
        t => t,
    }
    .clamp(1, n.max(1));
    // The dock's distances over the whole grid, for a strategy with a single region (its only transits),
    // computed on a spare core while the strategies lay out their patterns.
    let dock = OnceLock::new();
    let single = members.iter().any(|m| m.decomposition == DecompositionMethod::Single);
    let prepared = std::thread::scope(|scope| {
        if single {
            scope.spawn(|| dock.get_or_init(|| DistancesFrom::new(space, space.start)));
        }
        let nearest = nearest_reachable(space);
        // One basis per distinct decomposition, in first-use order.
        let mut kinds: Vec<DecompositionMethod> = Vec::new();
        for m in members {
            if !kinds.contains(&m.decomposition) {
                kinds.push(m.decomposition);
            }
        }
        let cancel = AtomicBool::new(false);
        let bases: Vec<Option<Arc<Basis>>> = run_parallel(threads, kinds.len(), monitor, &cancel, (0.0, 0.1), |k| {
            let member = members.iter().find(|m| m.decomposition == kinds[k])?;
            (!cancel.load(Ordering::Relaxed)).then(|| Arc::new(Basis::new(space, member, &nearest)))
        })
        .into_iter()
        .map(Option::flatten)
        .collect();
        let basis_of = |m: &PlanParams| {
            kinds
                .iter()
                .position(|&d| d == m.decomposition)
                .and_then(|k| bases[k].clone())
        };
        let prepared = run_parallel(threads, n, monitor, &cancel, (0.1, PREPARE_SHARE), |k| {
            let basis = basis_of(&members[k]).ok_or(PlannerError::Cancelled)?;
            prepare(space, &members[k], (basis, &nearest, &dock), &mut Relay(&cancel))
        });
        if monitor.cancelled() || cancel.load(Ordering::Relaxed) {
            return Err(PlannerError::Cancelled);
        }
        Ok(prepared)
    })?;
    prepared
        .into_iter()
        .map(|p| p.ok_or(PlannerError::Cancelled)?)
        .collect()
}

/// The coverage a plan must reach to count as complete (DESIGN §6 bar, or the request's lower target).
pub fn coverage_bar(params: &PlanParams) -> f64 {
    params.passes.coverage_target_pct.min(99.0)
}

/// Runs `job(0..count)` on up to `threads` scoped threads while the calling thread waits on their
/// reports: it raises `cancel` when `monitor` asks (polled at least every [`POLL`]), and reports progress
/// from `lo` to `hi` as jobs finish. Results come back in job order. A panicking job ends the wait (its
/// sender drops; the scope then re-raises the panic).
fn run_parallel<T: Send>(
    threads: usize,
    count: usize,
    monitor: &mut dyn PlanMonitor,
    cancel: &AtomicBool,
    (lo, hi): (f64, f64),
    job: impl Fn(usize) -> T + Sync,
) -> Vec<Option<T>> {
    let mut slots: Vec<Option<T>> = (0..count).map(|_| None).collect();
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel::<(usize, T)>();
    std::thread::scope(|scope| {
        for _ in 0..threads.clamp(1, count.max(1)) {
            let tx = tx.clone();
            let (next, job) = (&next, &job);
            scope.spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= count || tx.send((k, job(k))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let mut done = 0;
        while done < count {
            if monitor.cancelled() {
                cancel.store(true, Ordering::Relaxed);
            }
            match rx.recv_timeout(POLL) {
                Ok((k, out)) => {
                    slots[k] = Some(out);
                    done += 1;
                    monitor.progress(lo + (hi - lo) * done as f64 / count as f64);
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
    });
    slots
}

/// The strategies `params` leaves open, in tie-breaking order: those prepared first (bcd and walls, a
/// spiral and a sweep in the requested pattern over the undivided space), and those held in reserve. Above
/// [`LARGE_SITE_CELLS`] reachable cells only the undivided spiral and fitted lanes over the undivided space
/// come first (every member is a full preparation, and on a large site each takes seconds); walls with
/// fitted lanes stay in reserve.
pub fn members(space: &CoverageSpace, params: &PlanParams) -> (Vec<PlanParams>, Vec<PlanParams>) {
    let large = space.reachable_count() > LARGE_SITE_CELLS;
    let spiral = (DecompositionMethod::Single, PatternMethod::Spiral);
    let (first, reserve): (Vec<(DecompositionMethod, PatternMethod)>, Vec<_>) = match (params.decomposition, large) {
        (DecompositionMethod::Auto, true) => (
            vec![spiral, (DecompositionMethod::Single, params.pattern)],
            vec![(DecompositionMethod::Walls, params.pattern)],
        ),
        (DecompositionMethod::Auto, false) => (
            vec![
                (DecompositionMethod::Bcd, params.pattern),
                (DecompositionMethod::Walls, params.pattern),
                spiral,
                // One sweep over the undivided space in the requested pattern: lanes there are the plan a
                // person would draw on open ground and in halls with a few obstacles, and under the time
                // objective often the fastest (long lanes, few turns); among rooms its long steps lose to
                // the divided plans. (With the spiral pattern it is the spiral above.)
                (DecompositionMethod::Single, params.pattern),
            ],
            Vec::new(),
        ),
        (d, _) => (vec![(d, params.pattern)], Vec::new()),
    };
    let mut first = first;
    first.dedup();
    let placements: &[Placement] = if large {
        &[Placement::Fit]
    } else {
        &[Placement::Lattice, Placement::Fit, Placement::Framed]
    };
    let expand = |strategies: Vec<(DecompositionMethod, PatternMethod)>| {
        let mut out = Vec::new();
        for (decomposition, pattern) in strategies {
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
    };
    (expand(first), expand(reserve))
}

/// A worker's monitor: cancelled when the calling thread raised the flag; progress is reported per job.
struct Relay<'a>(&'a AtomicBool);

impl PlanMonitor for Relay<'_> {
    fn cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::tests::random_space;

    #[test]
    fn members_cover_every_open_choice_once() {
        let space = random_space(4, 50, 40, 4).expect("space");
        let (auto, reserve) = members(&space, &PlanParams::default());
        assert!(reserve.is_empty());
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
        for p in [Placement::Lattice, Placement::Fit, Placement::Framed] {
            want.push((DecompositionMethod::Single, PatternMethod::Lanes, Some(p)));
        }
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
        assert_eq!(members(&space, &fixed), (vec![fixed], Vec::new()));
    }

    #[test]
    fn large_sites_prepare_the_spiral_and_undivided_lanes_with_walls_in_reserve() {
        use crate::geom::Point2;
        use crate::map::{CellState, GridGeometry, OccupancyGrid};
        use crate::space::RobotShape;
        let g = GridGeometry::new(1100, 1000, 0.1, Point2::origin()).expect("valid");
        let robot = RobotShape {
            radius_m: 0.3,
            tool_width_m: 0.6,
        };
        let space =
            CoverageSpace::new(OccupancyGrid::filled(g, CellState::Free), robot, Point2::new(5.0, 5.0)).expect("space");
        assert!(space.reachable_count() > LARGE_SITE_CELLS);
        let (first, reserve) = members(&space, &PlanParams::default());
        let names = |m: &[PlanParams]| -> Vec<_> {
            m.iter()
                .map(|m| (m.decomposition, m.pattern, m.lanes.placement))
                .collect()
        };
        assert_eq!(
            names(&first),
            vec![
                (DecompositionMethod::Single, PatternMethod::Spiral, None),
                (DecompositionMethod::Single, PatternMethod::Lanes, Some(Placement::Fit))
            ]
        );
        assert_eq!(
            names(&reserve),
            vec![(DecompositionMethod::Walls, PatternMethod::Lanes, Some(Placement::Fit))]
        );
    }

    #[test]
    fn the_plan_does_not_depend_on_the_threads() {
        let space = random_space(11, 60, 45, 5).expect("space");
        let with = |threads| {
            let params = PlanParams {
                threads,
                ..PlanParams::default()
            };
            super::plan(&space, &params, &mut crate::pipeline::NoMonitor).expect("plan")
        };
        let one = with(1);
        for threads in [2, 5] {
            let other = with(threads);
            assert_eq!(other.points(), one.points(), "{threads} threads");
            assert_eq!(other.decomposition, one.decomposition);
        }
    }
}
