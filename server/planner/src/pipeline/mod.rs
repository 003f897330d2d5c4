//! The whole planning pipeline, from a coverage space to a path with metrics:
//! decompose → pattern per region → targeted passes → region routes → visiting order → links → metrics.

mod assemble;
pub mod fleet;
pub mod footprinted;
pub use footprinted::{LaneSpace, plan_footprinted, plan_footprinted_with};
pub mod objective;
pub use objective::Objective;
mod portfolio;
pub mod prepare;
pub mod remainder;
pub mod resume;
pub mod route;
pub mod shaped;
pub use shaped::plan_shaped;
pub mod wall_steps;

use crate::decompose::{DecomposeParams, DecompositionMethod};
use crate::error::Result;
use crate::geom::Point2;
use crate::link::LinkParams;
use crate::metrics::PlanMetrics;
use crate::order::OrderMethod;
use crate::pattern::boundary::PassParams;
use crate::pattern::lanes::{LaneParams, Placement};
use crate::pattern::{PatternMethod, Task};
use crate::space::CoverageSpace;
use crate::speed::limits::SpeedLimits;

/// Reachable cells above which `auto` prepares only the undivided spiral and undivided fitted lanes, with
/// wall division and fitted lanes in reserve (the best on large generated sites: 200 m × 200 m, 400
/// obstacles: spiral 9.95 %, walls/fit 10.01 %, walls/lattice 10.42 %, bcd 13.95–20.7 % overlap), instead of
/// bcd and walls × lattice, fit and framed lanes plus the spiral and undivided lanes: every member is a full
/// preparation, and on a large site each takes seconds.
pub const LARGE_SITE_CELLS: usize = 1_000_000;

/// Overlap a plan may have and still count as economical (the acceptance bar of the planner, percent).
pub const OVERLAP_BAR_PCT: f64 = 20.0;

/// Everything a plan request can choose. `Default` is the best combination.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanParams {
    /// Decomposition strategy.
    pub decomposition: DecompositionMethod,
    /// Visiting-order solver.
    pub order: OrderMethod,
    /// In-region pattern.
    pub pattern: PatternMethod,
    /// Seed for every random choice.
    pub seed: u64,
    /// Decomposition knobs.
    pub decompose: DecomposeParams,
    /// Lane knobs.
    pub lanes: LaneParams,
    /// Transit knobs.
    pub link: LinkParams,
    /// Work bound of the visiting-order solver (moves), deterministic.
    pub order_iterations: u64,
    /// Add targeted passes for what the main pattern misses (off only for baselines).
    pub targeted_passes: bool,
    /// Targeted-pass knobs.
    pub passes: PassParams,
    /// Threads that prepare a portfolio's strategies side by side (0: one per core). The plan does not
    /// depend on it.
    pub threads: usize,
    /// What the portfolio minimises among the strategies that meet the coverage bar.
    pub objective: Objective,
    /// The robot's speed limits, for the time objective's estimate (the speed profile takes its own).
    pub limits: SpeedLimits,
}

impl Default for PlanParams {
    fn default() -> Self {
        Self {
            decomposition: DecompositionMethod::Auto,
            order: OrderMethod::default(),
            pattern: PatternMethod::Lanes,
            seed: 1,
            decompose: DecomposeParams::default(),
            lanes: LaneParams::default(),
            link: LinkParams::default(),
            order_iterations: 200_000,
            targeted_passes: true,
            passes: PassParams::default(),
            threads: 0,
            objective: Objective::Time,
            limits: SpeedLimits::default(),
        }
    }
}

/// Observes a running plan and may cancel it. All methods have no-op defaults.
pub trait PlanMonitor {
    /// Progress in [0, 1] after a stage or a region.
    fn progress(&mut self, _fraction: f64) {}
    /// Polled between stages and regions; returning true stops the plan with [`PlannerError::Cancelled`].
    fn cancelled(&self) -> bool {
        false
    }
    /// A region of the final plan is linked: its summary and its path from the end of the transit into it
    /// to its last cover waypoint (what the robot drives there). Called in visiting order while the later
    /// regions are still being linked, so a robot may start on the first region early.
    fn region_ready(&mut self, _region: &RegionSummary, _path: &[Point2]) {}
}

/// A monitor that watches nothing.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoMonitor;
impl PlanMonitor for NoMonitor {}

/// What a waypoint is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WaypointKind {
    /// Sweeping: the tool is working.
    Cover,
    /// Moving between regions (or to and from the dock).
    Transit,
}

/// One vertex of the planned path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waypoint {
    /// Position in the map frame, metres.
    pub position: Point2,
    /// What the segment *ending* at this waypoint does (the first waypoint is the dock: transit).
    pub kind: WaypointKind,
    /// Region being covered, for cover waypoints.
    pub region: Option<u32>,
}

/// One region in the output.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionSummary {
    /// Region id (labels are `0..n`).
    pub id: u32,
    /// Outer contour, simplified, map frame, metres.
    pub polygon: Vec<Point2>,
    /// Lane direction, radians (0 for spiral).
    pub angle_rad: f64,
    /// Area, m².
    pub area_m2: f64,
}

/// Where a plan's length goes, metres (for tuning and the eval table).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct PlanStats {
    /// Boustrophedon lanes (or spiral rings).
    pub pattern_m: f64,
    /// Targeted passes along walls and obstacle rims.
    pub passes_m: f64,
    /// Single visits into pockets.
    pub visits: usize,
    /// Connections inside regions (steps between lanes, links to passes).
    pub steps_m: f64,
    /// Transits between regions and to and from the dock.
    pub transit_m: f64,
}

impl PlanStats {
    /// `excursions_m`: what excursions to visits add to the main pattern's tasks (counted as passes).
    fn of(waypoints: &[Waypoint], tasks: &[Vec<Task>], excursions_m: f64) -> Self {
        use crate::pattern::TaskKind;
        let (mut cover, mut transit) = (0.0, 0.0);
        for w in waypoints.windows(2) {
            let d = (w[1].position - w[0].position).norm();
            if w[1].kind == WaypointKind::Transit {
                transit += d;
            } else {
                cover += d;
            }
        }
        let sum = |k: &[TaskKind]| -> f64 {
            tasks
                .iter()
                .flatten()
                .filter(|t| k.contains(&t.kind))
                .map(Task::length)
                .sum()
        };
        let pattern_m = sum(&[TaskKind::Lane, TaskKind::Ring, TaskKind::Frame]) - excursions_m;
        let passes_m = sum(&[TaskKind::Boundary]) + excursions_m;
        let visits = tasks.iter().flatten().filter(|t| t.kind == TaskKind::Visit).count();
        Self {
            pattern_m,
            passes_m,
            visits,
            steps_m: (cover - pattern_m - passes_m).max(0.0),
            transit_m: transit,
        }
    }
}

/// A finished plan.
#[derive(Debug, Clone)]
pub struct PlanOutput {
    /// The path from the dock back to the dock.
    pub waypoints: Vec<Waypoint>,
    /// Regions in visiting order.
    pub regions: Vec<RegionSummary>,
    /// Region label per grid cell.
    pub labels: Vec<u32>,
    /// DESIGN §6 metrics of the path.
    pub metrics: PlanMetrics,
    /// Where the length goes.
    pub stats: PlanStats,
    /// The decomposition that produced this plan (what `auto` chose).
    pub decomposition: DecompositionMethod,
    /// The pattern that produced this plan.
    pub pattern: PatternMethod,
    /// The lane placement that produced this plan (`None` for patterns without lanes).
    pub lane_placement: Option<Placement>,
    /// Remarks for the user.
    pub warnings: Vec<String>,
}

impl PlanOutput {
    /// The path's points.
    pub fn points(&self) -> Vec<Point2> {
        self.waypoints.iter().map(|w| w.position).collect()
    }
}

/// Plans a full coverage of `space` from and back to its start with the strategy `params` asks for; where
/// it leaves choices open (`auto` decomposition, no fixed lane placement) every candidate strategy is
/// prepared and the best one is linked (see [`portfolio`]).
pub fn plan(space: &CoverageSpace, params: &PlanParams, monitor: &mut dyn PlanMonitor) -> Result<PlanOutput> {
    portfolio::plan(space, params, monitor)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::tests::random_space;
    use crate::error::PlannerError;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]
        /// Lanes, passes and links never leave traversable space; plans start and end at the dock, cover what
        /// they can reach, and are reproducible.
        #[test]
        fn plans_on_random_rooms_are_collision_free(seed in any::<u64>(), obstacles in 0usize..10, d in 0usize..4) {
            let Some(space) = random_space(seed, 50, 40, obstacles) else { return Ok(()) };
            let params = PlanParams { decomposition: DecompositionMethod::ALL[d], seed, ..PlanParams::default() };
            let out = plan(&space, &params, &mut NoMonitor).expect("plan");
            let pts = out.points();
            prop_assert_eq!(pts.first(), Some(&space.start));
            prop_assert_eq!(pts.last(), Some(&space.start));
            for w in pts.windows(2) {
                prop_assert!(space.segment_ok(w[0], w[1]), "segment {:?} leaves traversable space", w);
            }
            prop_assert_eq!(out.metrics.collisions, 0);
            prop_assert!(out.metrics.coverage_pct >= 99.0, "{:?}", out.metrics);
            let again = plan(&space, &params, &mut NoMonitor).expect("plan");
            prop_assert_eq!(again.points(), pts);
        }
    }

    #[test]
    fn cancellation_stops_the_plan() {
        struct Cancel;
        impl PlanMonitor for Cancel {
            fn cancelled(&self) -> bool {
                true
            }
        }
        let space = random_space(3, 40, 30, 3).expect("space");
        assert_eq!(
            plan(&space, &PlanParams::default(), &mut Cancel).err(),
            Some(PlannerError::Cancelled)
        );
    }

    /// Records what a plan reports.
    #[derive(Default)]
    struct Recorder {
        progress: Vec<f64>,
        regions: Vec<(u32, Vec<Point2>)>,
    }

    impl PlanMonitor for Recorder {
        fn progress(&mut self, fraction: f64) {
            self.progress.push(fraction);
        }
        fn region_ready(&mut self, region: &RegionSummary, path: &[Point2]) {
            self.regions.push((region.id, path.to_vec()));
        }
    }

    #[test]
    fn regions_stream_in_visiting_order_as_pieces_of_the_final_path() {
        for seed in [2_u64, 5, 9] {
            let Some(space) = random_space(seed, 60, 45, 6) else {
                continue;
            };
            let mut rec = Recorder::default();
            let out = plan(&space, &PlanParams::default(), &mut rec).expect("plan");
            // Only the winner streams: one call per region of the output, in its order.
            let ids: Vec<u32> = rec.regions.iter().map(|(id, _)| *id).collect();
            let want: Vec<u32> = out.regions.iter().map(|r| r.id).collect();
            assert_eq!(ids, want, "seed {seed}");
            let pts = out.points();
            let mut from = 0;
            for (id, path) in &rec.regions {
                assert!(path.len() >= 2, "region {id} streamed an empty path");
                // Each streamed path is a contiguous piece of the final path, after the previous one.
                let at = (from..pts.len())
                    .find(|&k| pts[k..].starts_with(path))
                    .unwrap_or_else(|| panic!("region {id}'s path is not in the plan after waypoint {from}"));
                from = at + path.len() - 1;
            }
            assert!(
                rec.progress.windows(2).all(|w| w[1] >= w[0] - 1e-12),
                "{:?}",
                rec.progress
            );
            assert_eq!(rec.progress.last(), Some(&1.0));
        }
    }
}
