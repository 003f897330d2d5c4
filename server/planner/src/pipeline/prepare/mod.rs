//! The planning stages up to the visiting order: decompose → pattern per region → region routes → targeted
//! passes → region routes → tour (→ more passes, routes and tour while the driven routes fall short of the
//! coverage target). A [`Prepared`] plan knows its coverage and, from the tour's cost, its length closely
//! enough to rank it against other strategies before any link is searched ([`Prepared::estimate`]).

mod estimate;
#[cfg(test)]
mod tests;

pub use estimate::Estimate;

use std::sync::{Arc, OnceLock};

use crate::decompose::{DecomposeParams, NO_REGION, Regions, decompose};
use crate::error::{PlannerError, Result};
use crate::geom::{Point2, octile_length, pair_key, polyline_length};
use crate::link::{DistancesFrom, LinkParams, Linker, geodesic_matrix};
use crate::map::DistanceField;
use crate::metrics::CoverageRaster;
use crate::order::{DistanceMatrix, SolveBudget, Tour, TourOption, TourProblem};
use crate::pattern::boundary::{candidates, select};
use crate::pattern::contour::trace_cells;
use crate::pattern::excursion::{Hosts, splice};
use crate::pattern::frame::frame_tasks;
use crate::pattern::lanes::{LaneParams, Placement, RegionView, best_angle, plan_lanes};
use crate::pattern::ring_splice::splice_rings;
use crate::pattern::spiral::plan_rings;
use crate::pattern::{PatternMethod, Task};
use crate::space::CoverageSpace;

use super::route::{RegionRoute, RouteSearch, region_options, through_obstacle};
use super::wall_steps::WallSteps;
use super::{PlanMonitor, PlanParams};

/// A plan decided up to its visiting order; [`super::assemble::assemble`] links it into a path.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The request's parameters (with the placement this plan used).
    pub params: PlanParams,
    /// The decomposition (shared by the strategies that use it).
    pub basis: Arc<Basis>,
    /// Tasks of every region (pattern and targeted passes).
    pub tasks: Vec<Vec<Task>>,
    /// Lane angle of every region, radians.
    pub angles: Vec<f64>,
    /// Route options of every region (empty for regions with nothing to do).
    pub options: Vec<Vec<RegionRoute>>,
    /// Regions with a route, in node order of the tour problem.
    pub active: Vec<usize>,
    /// Visiting order over `active`.
    pub tour: Tour,
    /// Remarks so far.
    pub warnings: Vec<String>,
    /// Length that excursions to visits add to the main pattern's tasks, metres (targeted driving).
    pub excursions_m: f64,
    /// The links found for steps through obstacles while the routes were costed (the assembly reuses them).
    pub(crate) linked: Linked,
    /// What this plan is expected to give, before linking.
    pub estimate: Estimate,
}

/// The distance field whose sites are the reachable cells (each coverable cell is served by the region of
/// its nearest reachable cell); the same for every strategy on a space.
pub fn nearest_reachable(space: &CoverageSpace) -> DistanceField {
    DistanceField::compute(*space.geometry(), |i| space.reachable[i], false)
}

/// What every strategy with the same decomposition shares: the regions and each one's cover targets.
#[derive(Debug, Clone)]
pub struct Basis {
    /// The regions.
    pub regions: Regions,
    /// Region responsible for each coverable cell (that of its nearest reachable cell), or `NO_REGION`.
    pub target_labels: Vec<u32>,
    /// Cells of every region.
    pub cells: Vec<Vec<usize>>,
    /// Cover targets of every region.
    pub targets: Vec<Vec<usize>>,
    /// The regions' contours (traced once: the targeted passes and the region outlines read them too), for
    /// steps between lane ends that follow a wall.
    pub wall_steps: WallSteps,
    /// Sweep direction of every region (the same for every lane placement), computed by the first strategy
    /// with lanes that needs it.
    lane_angles: OnceLock<Vec<f64>>,
}

impl Basis {
    /// Decomposes `space` with `params`' decomposition and assigns the cover targets.
    pub fn new(space: &CoverageSpace, params: &PlanParams, nearest_reachable: &DistanceField) -> Self {
        let decompose_params = DecomposeParams {
            seed: params.seed,
            ..params.decompose
        };
        let regions = decompose(space, params.decomposition, &decompose_params);
        let g = space.geometry();
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
        let wall_steps = WallSteps::new(space, cells.iter().map(|c| trace_cells(g, c)).collect());
        Self {
            regions,
            target_labels,
            cells,
            targets,
            wall_steps,
            lane_angles: OnceLock::new(),
        }
    }

    /// The sweep direction of region `id` for `lanes` (fixed, or the shared best one).
    fn lane_angle(&self, space: &CoverageSpace, id: usize, lanes: &LaneParams) -> f64 {
        lanes.fixed_angle_rad.unwrap_or_else(|| {
            self.lane_angles
                .get_or_init(|| {
                    (0..self.regions.count)
                        .map(|k| best_angle(space, self.view(k), lanes))
                        .collect()
                })
                .get(id)
                .copied()
                .unwrap_or(0.0)
        })
    }

    fn view(&self, id: usize) -> RegionView<'_> {
        RegionView {
            id: id as u32,
            labels: &self.regions.labels,
            target_labels: &self.target_labels,
            cells: &self.cells[id],
            targets: &self.targets[id],
        }
    }
}

/// Runs the stages after the decomposition up to the tour, on `basis` (built for `params`' decomposition);
/// `monitor` sees progress 0.1 … 0.75 and may cancel between stages.
pub fn prepare(
    space: &CoverageSpace,
    params: &PlanParams,
    (basis, nearest_reachable, dock): (Arc<Basis>, &DistanceField, &OnceLock<DistancesFrom>),
    monitor: &mut dyn PlanMonitor,
) -> Result<Prepared> {
    let check = |m: &dyn PlanMonitor| {
        if m.cancelled() {
            Err(PlannerError::Cancelled)
        } else {
            Ok(())
        }
    };
    let g = *space.geometry();
    check(monitor)?;
    monitor.progress(0.1);
    let regions = &basis.regions;
    let view = |id: usize| basis.view(id);
    let fixed = |id: usize| LaneParams {
        fixed_angle_rad: Some(basis.lane_angle(space, id, &params.lanes)),
        ..params.lanes
    };

    // Main pattern per region, stamped so that the targeted passes see what every region already covers.
    let mut raster = CoverageRaster::new(g, space.robot.tool_width_m / 2.0);
    let mut tasks: Vec<Vec<Task>> = Vec::with_capacity(regions.count);
    let mut angles = Vec::with_capacity(regions.count);
    for id in 0..regions.count {
        let (angle, t) = match params.pattern {
            PatternMethod::Lanes if params.lanes.placement == Some(Placement::Framed) => {
                let (angle, mut t) = plan_lanes(space, view(id), &fixed(id));
                t.extend(frame_tasks(space, view(id)));
                (angle, t)
            }
            PatternMethod::Lanes => plan_lanes(space, view(id), &fixed(id)),
            PatternMethod::Spiral => (0.0, splice_rings(space, plan_rings(space, view(id)))),
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
    let linked = Linked::default();
    let walls = (space, &basis.wall_steps, &linked);
    let mut options: Vec<Vec<RegionRoute>> = vec![Vec::new(); regions.count];
    route_regions(
        walls,
        &params.link,
        (&tasks, &angles),
        params.seed,
        monitor,
        &mut options,
        0..regions.count,
    );
    for (id, opts) in options.iter().enumerate() {
        if let Some(route) = opts.first() {
            stamp_route(walls, &mut raster, route, &tasks[id], false);
        }
    }
    check(monitor)?;
    monitor.progress(0.45);
    let reroute =
        |options: &mut Vec<Vec<RegionRoute>>, tasks: &[Vec<Task>], redo: Vec<usize>, monitor: &dyn PlanMonitor| {
            route_regions(
                walls,
                &params.link,
                (tasks, &angles),
                params.seed,
                monitor,
                options,
                redo.into_iter(),
            )
        };
    let mut excursions_m = 0.0;
    if params.targeted_passes {
        let redo = add_passes(
            space,
            (&basis, nearest_reachable),
            params,
            &mut tasks,
            &mut raster,
            &mut excursions_m,
        );
        reroute(&mut options, &tasks, redo, monitor);
    }
    check(monitor)?;
    monitor.progress(0.6);
    let (mut active, mut tour) = visit_order(space, params, &options, dock, monitor);
    check(monitor)?;
    // The raster holds the steps of each region's first route; the tour may drive others, whose steps along
    // the walls cover other nooks. What the driven routes leave below the coverage target gets more passes
    // (and new routes and order), a bounded number of times.
    let mut driven = driven_raster(walls, (&tasks, &options), (&active, &tour));
    let mut estimate = Estimate::of(walls, params, &driven, (&tasks, &options), (&active, &tour));
    for _ in 0..TOP_UPS {
        let short = params.passes.coverage_target_pct - TOP_UP_TOLERANCE_PCT;
        if !params.targeted_passes || estimate.coverage_pct + 1e-9 >= short {
            break;
        }
        let redo = add_passes(
            space,
            (&basis, nearest_reachable),
            params,
            &mut tasks,
            &mut driven,
            &mut excursions_m,
        );
        if redo.is_empty() {
            break;
        }
        reroute(&mut options, &tasks, redo, monitor);
        (active, tour) = visit_order(space, params, &options, dock, monitor);
        check(monitor)?;
        driven = driven_raster(walls, (&tasks, &options), (&active, &tour));
        estimate = Estimate::of(walls, params, &driven, (&tasks, &options), (&active, &tour));
    }
    monitor.progress(0.75);
    Ok(Prepared {
        params: params.clone(),
        basis,
        tasks,
        angles,
        options,
        active,
        tour,
        warnings: space.warnings.clone(),
        excursions_m,
        linked,
        estimate,
    })
}

/// Rounds of extra passes for what the driven routes leave below the coverage target.
const TOP_UPS: usize = 2;

/// The driven routes get extra passes only when they fall this far (percentage points) below the coverage
/// target: a new visiting order for a hair's breadth is not worth its time (the target keeps a margin
/// above the coverage bar).
const TOP_UP_TOLERANCE_PCT: f64 = 0.2;

/// Targeted passes for what `raster` shows uncovered, added to `tasks` (excursions spliced into their
/// hosts, their length added to `excursions_m`) and stamped on `raster`. Returns the regions that changed.
fn add_passes(
    space: &CoverageSpace,
    (basis, nearest_reachable): (&Basis, &DistanceField),
    params: &PlanParams,
    tasks: &mut [Vec<Task>],
    raster: &mut CoverageRaster,
    excursions_m: &mut f64,
) -> Vec<usize> {
    let count = basis.regions.count;
    let mut pool = Vec::new();
    for (id, region_tasks) in tasks.iter().enumerate() {
        let hosts = Hosts::new(space, region_tasks);
        pool.extend(candidates(
            space,
            (basis.view(id), basis.wall_steps.contours(id)),
            (raster, &hosts),
            nearest_reachable,
            &params.passes,
        ));
    }
    let chosen = select(space, pool, raster, &params.passes);
    let mut touched = vec![false; count];
    let mut excursions = vec![Vec::new(); count];
    for c in chosen {
        let id = c.region as usize;
        touched[id] = true;
        match c.excursion {
            Some(e) => excursions[id].push(e),
            None => tasks[id].push(c.task),
        }
    }
    for (id, list) in excursions.into_iter().enumerate() {
        *excursions_m += splice(space, &mut tasks[id], list);
    }
    (0..count).filter(|&id| touched[id]).collect()
}

/// The regions with a route and their visiting order, with joint entry choice, on geodesic distances.
fn visit_order(
    space: &CoverageSpace,
    params: &PlanParams,
    options: &[Vec<RegionRoute>],
    dock: &OnceLock<DistancesFrom>,
    monitor: &dyn PlanMonitor,
) -> (Vec<usize>, Tour) {
    let active: Vec<usize> = (0..options.len()).filter(|&id| !options[id].is_empty()).collect();
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
    let n = points.len();
    let dist = if active.len() == 1 {
        // One region: only the transits from and back to the dock count (straight distances between the
        // region's own ends are never used), read off the dock's distances — computed once per plan, on a
        // spare core while the patterns were being laid out.
        let from_dock = dock.get_or_init(|| DistancesFrom::new(space, space.start));
        let d: Vec<f64> = points
            .iter()
            .map(|&p| from_dock.to(space, p).unwrap_or(f64::INFINITY))
            .collect();
        DistanceMatrix::from_fn(n, |i, j| match (i, j) {
            _ if i == j => 0.0,
            (0, k) | (k, 0) => d[k],
            _ => (points[i] - points[j]).norm(),
        })
    } else {
        let geo = geodesic_matrix(space, &points);
        DistanceMatrix::from_fn(n, |i, j| geo[i * n + j])
    };
    let problem = TourProblem {
        dist,
        depot: 0,
        nodes,
        closed: true,
    };
    let stop_flag = || monitor.cancelled();
    let tour = params.order.orderer().solve(
        &problem,
        params.seed,
        &SolveBudget {
            max_iterations: params.order_iterations,
            stop: Some(&stop_flag),
        },
    );
    (active, tour)
}

/// Coverage of the tasks and of the steps of the routes `tour` drives.
fn driven_raster(
    walls: (&CoverageSpace, &WallSteps, &Linked),
    (tasks, options): (&[Vec<Task>], &[Vec<RegionRoute>]),
    (active, tour): (&[usize], &Tour),
) -> CoverageRaster {
    let space = walls.0;
    let mut driven = CoverageRaster::new(*space.geometry(), space.robot.tool_width_m / 2.0);
    for (&k, &o) in tour.order.iter().zip(&tour.options) {
        let id = active[k];
        stamp_route(walls, &mut driven, &options[id][o], &tasks[id], true);
    }
    driven
}

/// Stamps the steps between the legs of `route` on `raster` — along the wall where they follow it, else
/// straight (steps that need a link are left to the assembly) — and with `legs` the legs too.
fn stamp_route(
    (space, walls, linked): (&CoverageSpace, &WallSteps, &Linked),
    raster: &mut CoverageRaster,
    route: &RegionRoute,
    tasks: &[Task],
    legs: bool,
) {
    let mut prev: Option<Point2> = None;
    for leg in &route.legs {
        let pts = leg.points(tasks);
        if let (Some(a), Some(&b)) = (prev, pts.first()) {
            if let Some(step) = walls.along(space, a, b) {
                raster.stamp_polyline(&step);
            } else if space.segment_ok(a, b) {
                raster.stamp_segment(a, b);
            } else if let Some(path) = linked.get(a, b) {
                raster.stamp_polyline(&path);
            }
        }
        if legs {
            raster.stamp_polyline(&pts);
        }
        prev = pts.last().copied();
    }
}

/// The links found for steps through obstacles while costing routes (either direction), so that the
/// coverage estimate can stamp them too.
#[derive(Debug, Default, Clone)]
pub(crate) struct Linked(std::cell::RefCell<std::collections::HashMap<[u64; 4], Vec<Point2>>>);

impl Linked {
    fn keep(&self, a: Point2, b: Point2, path: Vec<Point2>) {
        self.0.borrow_mut().insert(pair_key(a, b), path);
    }

    pub(crate) fn get(&self, a: Point2, b: Point2) -> Option<Vec<Point2>> {
        let map = self.0.borrow();
        map.get(&pair_key(a, b))
            .cloned()
            .or_else(|| map.get(&pair_key(b, a)).map(|p| p.iter().rev().copied().collect()))
    }
}

/// Slack of the first, bounded search for a way round an obstacle between two tasks, in tool widths.
const ROUND_WIDTHS: f64 = 6.0;

/// Computes the route options of the regions in `ids` (regions without tasks get none): searched on
/// straight-line distances, costed with the steps that follow a wall along it and the way round every step
/// that runs through an obstacle.
fn route_regions(
    (space, walls, linked): (&CoverageSpace, &WallSteps, &Linked),
    link: &LinkParams,
    (tasks, angles): (&[Vec<Task>], &[f64]),
    seed: u64,
    monitor: &dyn PlanMonitor,
    options: &mut [Vec<RegionRoute>],
    ids: impl Iterator<Item = usize>,
) {
    let stop_flag = || monitor.cancelled();
    let slack_m = ROUND_WIDTHS * space.robot.tool_width_m;
    // Steps take the shortest way (the assembly links them with the same parameters).
    let linker = std::cell::RefCell::new(Linker::new(space, &LinkParams { alpha: 0.0, ..*link }));
    // Steps that only graze the clearance (lane ends along a ragged wall) are linked with centimetres more
    // and keep their straight length. A step through an obstacle gets a short bounded search first (a way
    // round a pillar); only without one is the map searched (a wall between two rooms of one region). No
    // way at all costs infinity.
    let exact = |a: Point2, b: Point2| -> Option<f64> {
        if let Some(step) = walls.along(space, a, b) {
            return Some(polyline_length(&step));
        }
        if !through_obstacle(space, a, b) {
            return None;
        }
        let mut l = linker.borrow_mut();
        // The bound is over the grid's own length of the open way (8-connected moves are up to 8 % longer
        // than the straight line, a 50 m step at 22° by 4 m) and the two cells' snapping.
        let bound = octile_length(a, b) + 2.0 * std::f64::consts::SQRT_2 * space.geometry().resolution + slack_m;
        let path = l.link_within(a, b, bound).or_else(|| l.link(a, b));
        Some(path.map_or(f64::INFINITY, |p| {
            let len = polyline_length(&p);
            linked.keep(a, b, p);
            len
        }))
    };
    for id in ids {
        options[id] = if tasks[id].is_empty() {
            Vec::new()
        } else {
            let search = RouteSearch {
                seed,
                iterations: (tasks[id].len() as u64).pow(2).clamp(1_000, 200_000),
                stop: Some(&stop_flag),
                exact: Some(&exact),
            };
            region_options(&tasks[id], angles[id], &search)
        };
    }
}
