//! The whole planning pipeline, from a coverage space to a path with metrics:
//! decompose → pattern per region → targeted passes → region routes → visiting order → links → metrics.

pub mod route;

use crate::decompose::{DecomposeParams, DecompositionMethod, NO_REGION, decompose};
use crate::error::{PlannerError, Result};
use crate::geom::{Point2, simplify_polyline};
use crate::link::{LinkParams, Linker, geodesic_matrix};
use crate::map::DistanceField;
use crate::metrics::{CoverageRaster, PlanMetrics, evaluate};
use crate::order::{DistanceMatrix, OrderMethod, SolveBudget, TourOption, TourProblem};
use crate::pattern::boundary::{PassParams, candidates, select};
use crate::pattern::contour::trace_cells;
use crate::pattern::frame::frame_tasks;
use crate::pattern::lanes::{LaneParams, Placement, RegionView, plan_lanes};
use crate::pattern::spiral::plan_rings;
use crate::pattern::{PatternMethod, Task};
use crate::space::CoverageSpace;
use route::{RegionRoute, region_options};

/// Largest reachable set (cells) for which `auto` also tries one spiral over the undivided space.
pub const AUTO_SPIRAL_MAX_CELLS: usize = 250_000;

/// Largest reachable set (cells) on which lanes are also tried in the framed placement (each placement is
/// a full plan; on large sites the third one costs more than it brings).
pub const FRAMED_MAX_CELLS: usize = 1_000_000;

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
}

impl Default for PlanParams {
    fn default() -> Self {
        Self {
            decomposition: DecompositionMethod::Auto,
            order: OrderMethod::TwoOpt,
            pattern: PatternMethod::Lanes,
            seed: 1,
            decompose: DecomposeParams::default(),
            lanes: LaneParams::default(),
            link: LinkParams::default(),
            order_iterations: 200_000,
            targeted_passes: true,
            passes: PassParams::default(),
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
    fn of(waypoints: &[Waypoint], tasks: &[Vec<Task>]) -> Self {
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
        let pattern_m = sum(&[TaskKind::Lane, TaskKind::Ring, TaskKind::Frame]);
        let passes_m = sum(&[TaskKind::Boundary]);
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

/// Plans a full coverage of `space` from and back to its start. Without a fixed lane placement, plans with
/// the map-wide lane lattice, with per-region fitted lanes and (up to [`FRAMED_MAX_CELLS`] reachable cells)
/// with framed lanes (see [`Placement`]) and keeps the shortest plan that meets the coverage target (the
/// lattice wins ties).
pub fn plan(space: &CoverageSpace, params: &PlanParams, monitor: &mut dyn PlanMonitor) -> Result<PlanOutput> {
    if params.decomposition == DecompositionMethod::Auto {
        // The undivided spiral's routing and pass selection grow faster than linearly with the area (one
        // region holding every ring); on large sites it costs minutes, so it only joins below this size.
        let spiral = space.reachable_count() <= AUTO_SPIRAL_MAX_CELLS;
        return auto(space, params, monitor, spiral);
    }
    if params.lanes.placement.is_some() || params.pattern != PatternMethod::Lanes {
        return plan_once(space, params, monitor);
    }
    let with = |p: Placement| PlanParams {
        lanes: LaneParams {
            placement: Some(p),
            ..params.lanes
        },
        ..params.clone()
    };
    let good = |o: &PlanOutput| {
        o.metrics.collisions == 0 && o.metrics.coverage_pct + 1e-9 >= params.passes.coverage_target_pct.min(99.0)
    };
    // The first placement that meets the bar with the shortest path wins (earlier ones win ties).
    let mut best = plan_once(space, &with(Placement::Lattice), monitor)?;
    let placements: &[Placement] = if space.reachable_count() <= FRAMED_MAX_CELLS {
        &[Placement::Fit, Placement::Framed]
    } else {
        &[Placement::Fit]
    };
    for &p in placements {
        let out = plan_once(space, &with(p), monitor)?;
        let better = match (good(&best), good(&out)) {
            (true, true) => out.metrics.length_m + 1e-9 < best.metrics.length_m,
            (false, true) => true,
            _ => false,
        };
        if better {
            best = out;
        }
    }
    Ok(best)
}

/// The `auto` portfolio on `space`: bcd and walls in the requested pattern, and the undivided spiral when
/// `spiral`; keeps the plan with the least overlap that meets the bar.
fn auto(space: &CoverageSpace, params: &PlanParams, monitor: &mut dyn PlanMonitor, spiral: bool) -> Result<PlanOutput> {
    let mut best: Option<PlanOutput> = None;
    let mut portfolio = vec![
        (DecompositionMethod::Bcd, params.pattern),
        (DecompositionMethod::Walls, params.pattern),
    ];
    if spiral {
        portfolio.push((DecompositionMethod::Single, PatternMethod::Spiral));
    }
    for (d, pattern) in portfolio {
        let member = PlanParams {
            decomposition: d,
            pattern,
            ..params.clone()
        };
        let out = plan(space, &member, monitor)?;
        let better = best.as_ref().is_none_or(|b| {
            let ok = |o: &PlanOutput| o.metrics.collisions == 0 && o.metrics.coverage_pct >= 99.0;
            (ok(&out), -out.metrics.overlap_pct) > (ok(b), -b.metrics.overlap_pct)
        });
        if better {
            best = Some(out);
        }
    }
    best.ok_or(PlannerError::Cancelled)
}

fn plan_once(space: &CoverageSpace, params: &PlanParams, monitor: &mut dyn PlanMonitor) -> Result<PlanOutput> {
    let check = |m: &dyn PlanMonitor| {
        if m.cancelled() {
            Err(PlannerError::Cancelled)
        } else {
            Ok(())
        }
    };
    let g = *space.geometry();
    let mut warnings = space.warnings.clone();
    let decompose_params = DecomposeParams {
        seed: params.seed,
        ..params.decompose
    };
    let regions = decompose(space, params.decomposition, &decompose_params);
    check(monitor)?;
    monitor.progress(0.1);

    // Cover targets: each coverable cell belongs to the region of its nearest reachable cell.
    let nearest_reachable = DistanceField::compute(g, |i| space.reachable[i], false);
    let target_labels: Vec<u32> = (0..g.len())
        .map(|i| {
            if !space.coverable[i] {
                return NO_REGION;
            }
            nearest_reachable
                .nearest_site_index(i)
                .map_or(NO_REGION, |r| regions.labels[r])
        })
        .collect();
    let cells = regions.cells();
    let mut targets = vec![Vec::new(); regions.count];
    for (i, &l) in target_labels.iter().enumerate() {
        if l != NO_REGION {
            targets[l as usize].push(i);
        }
    }
    let view = |id: usize| RegionView {
        id: id as u32,
        labels: &regions.labels,
        target_labels: &target_labels,
        cells: &cells[id],
        targets: &targets[id],
    };

    // Main pattern per region, stamped so that the targeted passes see what every region already covers.
    let mut raster = CoverageRaster::new(g, space.robot.tool_width_m / 2.0);
    let mut tasks: Vec<Vec<Task>> = Vec::with_capacity(regions.count);
    let mut angles = Vec::with_capacity(regions.count);
    for id in 0..regions.count {
        let (angle, t) = match params.pattern {
            PatternMethod::Lanes if params.lanes.placement == Some(Placement::Framed) => {
                let (angle, mut t) = plan_lanes(space, view(id), &params.lanes);
                t.extend(frame_tasks(space, view(id)));
                (angle, t)
            }
            PatternMethod::Lanes => plan_lanes(space, view(id), &params.lanes),
            PatternMethod::Spiral => (0.0, plan_rings(space, view(id))),
        };
        for task in &t {
            raster.stamp_polyline(&task.points);
        }
        tasks.push(t);
        angles.push(angle);
        check(monitor)?;
    }
    monitor.progress(0.3);

    // Routes inside each region, from each corner; the steps between legs cover too, so stamp them before
    // looking for what is still missing.
    let mut options: Vec<Vec<RegionRoute>> = vec![Vec::new(); regions.count];
    route_regions(&tasks, &angles, params.seed, monitor, &mut options, 0..regions.count);
    for (id, opts) in options.iter().enumerate() {
        let Some(route) = opts.first() else { continue };
        let mut prev: Option<Point2> = None;
        for leg in &route.legs {
            let pts = leg.points(&tasks[id]);
            if let (Some(a), Some(&b)) = (prev, pts.first())
                && space.segment_ok(a, b)
            {
                raster.stamp_segment(a, b);
            }
            prev = pts.last().copied();
        }
    }
    check(monitor)?;
    monitor.progress(0.45);
    if params.targeted_passes {
        let mut pool = Vec::new();
        for id in 0..regions.count {
            pool.extend(candidates(space, view(id), &raster, &nearest_reachable, &params.passes));
        }
        let chosen = select(space, pool, &mut raster, &params.passes);
        let mut touched = vec![false; regions.count];
        for c in chosen {
            touched[c.region as usize] = true;
            tasks[c.region as usize].push(c.task);
        }
        let redo: Vec<usize> = (0..regions.count).filter(|&id| touched[id]).collect();
        route_regions(&tasks, &angles, params.seed, monitor, &mut options, redo.into_iter());
    }
    check(monitor)?;
    monitor.progress(0.6);
    let active: Vec<usize> = (0..regions.count).filter(|&id| !options[id].is_empty()).collect();

    // Visiting order over regions with joint entry choice, on geodesic distances.
    let mut points = vec![space.start];
    let mut nodes = Vec::with_capacity(active.len());
    for &id in &active {
        let mut node = Vec::new();
        for r in &options[id] {
            let e = points.len();
            points.push(r.entry);
            points.push(r.exit);
            node.push(TourOption {
                entry: e,
                exit: e + 1,
                cost: r.cost,
                reverse: 0,
            });
        }
        for (j, o) in node.iter_mut().enumerate() {
            o.reverse = j ^ 1; // region_options pushes (route, reversed route) pairs
        }
        nodes.push(node);
    }
    let geo = geodesic_matrix(space, &points);
    let n = points.len();
    let dist = DistanceMatrix::from_fn(n, |i, j| geo[i * n + j]);
    let problem = TourProblem {
        dist,
        depot: 0,
        nodes,
        closed: true,
    };
    let tour = {
        let stop_flag = || monitor.cancelled();
        params.order.orderer().solve(
            &problem,
            params.seed,
            &SolveBudget {
                max_iterations: params.order_iterations,
                stop: Some(&stop_flag),
            },
        )
    };
    check(monitor)?;
    monitor.progress(0.75);

    // Assemble: dock → region routes with links → dock.
    let mut path = Path::new(space.start);
    let mut linker = Linker::new(space, &params.link);
    // Steps inside a region sweep as they go: they take the shortest way (no potential field), which also
    // hugs the walls whose band they help to cover.
    let mut step_linker = Linker::new(
        space,
        &LinkParams {
            alpha: 0.0,
            ..params.link
        },
    );
    let mut summaries = Vec::with_capacity(active.len());
    for (&k, &o) in tour.order.iter().zip(&tour.options) {
        let id = active[k];
        let route = &options[id][o];
        if !path.transit_to(space, route.entry, &mut linker, &mut warnings) {
            continue;
        }
        for leg in &route.legs {
            let pts = leg.points(&tasks[id]);
            if path.cover_to(space, pts[0], id as u32, &mut step_linker, &mut warnings) {
                for &p in &pts[1..] {
                    path.push(p, WaypointKind::Cover, Some(id as u32));
                }
            }
        }
        summaries.push(summary(space, &cells[id], id, angles[id]));
        check(monitor)?;
    }
    path.transit_to(space, space.start, &mut linker, &mut warnings);
    let waypoints = path.waypoints;
    let pts: Vec<Point2> = waypoints.iter().map(|w| w.position).collect();
    let metrics = evaluate(space, &pts);
    let stats = PlanStats::of(&waypoints, &tasks);
    monitor.progress(1.0);
    Ok(PlanOutput {
        waypoints,
        regions: summaries,
        labels: regions.labels,
        metrics,
        stats,
        warnings,
        decomposition: params.decomposition,
        pattern: params.pattern,
        lane_placement: (params.pattern == PatternMethod::Lanes)
            .then_some(params.lanes.placement)
            .flatten(),
    })
}

/// Computes the route options of the regions in `ids` (regions without tasks get none).
fn route_regions(
    tasks: &[Vec<Task>],
    angles: &[f64],
    seed: u64,
    monitor: &dyn PlanMonitor,
    options: &mut [Vec<RegionRoute>],
    ids: impl Iterator<Item = usize>,
) {
    let stop_flag = || monitor.cancelled();
    for id in ids {
        options[id] = if tasks[id].is_empty() {
            Vec::new()
        } else {
            let budget = (tasks[id].len() as u64).pow(2).clamp(1_000, 200_000);
            region_options(&tasks[id], angles[id], seed, budget, Some(&stop_flag))
        };
    }
}

/// The path under construction.
struct Path {
    waypoints: Vec<Waypoint>,
}

impl Path {
    fn new(start: Point2) -> Self {
        Self {
            waypoints: vec![Waypoint {
                position: start,
                kind: WaypointKind::Transit,
                region: None,
            }],
        }
    }

    fn last(&self) -> Point2 {
        self.waypoints.last().map_or(Point2::origin(), |w| w.position)
    }

    fn push(&mut self, p: Point2, kind: WaypointKind, region: Option<u32>) {
        if (p - self.last()).norm() > 1e-9 {
            self.waypoints.push(Waypoint {
                position: p,
                kind,
                region,
            });
        }
    }

    /// Moves to `to` between regions; false (with a warning) when no link exists.
    fn transit_to(
        &mut self,
        space: &CoverageSpace,
        to: Point2,
        linker: &mut Linker<'_>,
        warnings: &mut Vec<String>,
    ) -> bool {
        self.connect(space, to, WaypointKind::Transit, None, linker, warnings)
    }

    /// Moves to `to` inside region `id`: straight when clear, else linked; false when no link exists.
    fn cover_to(
        &mut self,
        space: &CoverageSpace,
        to: Point2,
        id: u32,
        linker: &mut Linker<'_>,
        warnings: &mut Vec<String>,
    ) -> bool {
        self.connect(space, to, WaypointKind::Cover, Some(id), linker, warnings)
    }

    fn connect(
        &mut self,
        space: &CoverageSpace,
        to: Point2,
        kind: WaypointKind,
        region: Option<u32>,
        linker: &mut Linker<'_>,
        warnings: &mut Vec<String>,
    ) -> bool {
        let from = self.last();
        if (to - from).norm() < 1e-9 {
            return true;
        }
        if kind == WaypointKind::Cover && space.segment_ok(from, to) {
            self.push(to, kind, region);
            return true;
        }
        match linker.link(from, to) {
            Some(pts) => {
                for p in pts.into_iter().skip(1) {
                    self.push(p, kind, region);
                }
                true
            }
            None => {
                warnings.push(format!(
                    "no collision-free link from ({:.2}, {:.2}) to ({:.2}, {:.2}); that stretch is skipped",
                    from.x, from.y, to.x, to.y
                ));
                false
            }
        }
    }
}

fn summary(space: &CoverageSpace, cells: &[usize], id: usize, angle: f64) -> RegionSummary {
    let g = space.geometry();
    let area_m2 = cells.len() as f64 * g.resolution * g.resolution;
    let outer = trace_cells(g, cells).into_iter().next().unwrap_or_default();
    let pts: Vec<Point2> = outer.iter().map(|&i| g.center_of(i)).collect();
    let polygon = simplify_polyline(&pts, g.resolution, &|_, _| true);
    RegionSummary {
        id: id as u32,
        polygon,
        angle_rad: angle,
        area_m2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::tests::random_space;
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
}
