//! The last stage: a [`Prepared`] plan's regions linked in tour order into one path from the dock back to the
//! dock, with its metrics. Each region is announced to the monitor as soon as its cover path is linked.

use crate::error::{PlannerError, Result};
use crate::geom::{Point2, simplify_polyline};
use crate::link::{LinkParams, Linker};
use crate::metrics::evaluate;
use crate::pattern::PatternMethod;
use crate::space::CoverageSpace;

use super::prepare::Prepared;
use super::{PlanMonitor, PlanOutput, PlanStats, RegionSummary, Waypoint, WaypointKind};

/// Links `prepared` into the final path; `monitor` sees progress 0.75 … 1.0 and one
/// [`PlanMonitor::region_ready`] per region, in visiting order.
pub fn assemble(space: &CoverageSpace, prepared: Prepared, monitor: &mut dyn PlanMonitor) -> Result<PlanOutput> {
    let Prepared {
        params,
        basis,
        tasks,
        angles,
        options,
        active,
        tour,
        mut warnings,
        excursions_m,
        linked,
        ..
    } = prepared;
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
    let total = tour.order.len().max(1);
    for (n, (&k, &o)) in tour.order.iter().zip(&tour.options).enumerate() {
        let id = active[k];
        let route = &options[id][o];
        if !path.transit_to(space, route.entry, &mut linker, &mut warnings) {
            continue;
        }
        let first = path.waypoints.len() - 1;
        for leg in &route.legs {
            let pts = leg.points(&tasks[id]);
            // A step along a wall, or round an obstacle as found while costing the route, else straight or
            // linked now.
            let from = path.last();
            let known = basis.wall_steps.along(space, from, pts[0]).or_else(|| {
                (!space.segment_ok(from, pts[0]))
                    .then(|| linked.get(from, pts[0]))
                    .flatten()
            });
            for &p in known.iter().flat_map(|step| &step[1..]) {
                path.push(p, WaypointKind::Cover, Some(id as u32));
            }
            if path.cover_to(space, pts[0], id as u32, &mut step_linker, &mut warnings) {
                for &p in &pts[1..] {
                    path.push(p, WaypointKind::Cover, Some(id as u32));
                }
            }
        }
        let s = summary(space, (&basis.cells[id], basis.wall_steps.contours(id)), id, angles[id]);
        let region_path: Vec<Point2> = path.waypoints[first..].iter().map(|w| w.position).collect();
        monitor.region_ready(&s, &region_path);
        summaries.push(s);
        if monitor.cancelled() {
            return Err(PlannerError::Cancelled);
        }
        monitor.progress(0.75 + 0.25 * (n + 1) as f64 / total as f64);
    }
    path.transit_to(space, space.start, &mut linker, &mut warnings);
    let waypoints = path.waypoints;
    let pts: Vec<Point2> = waypoints.iter().map(|w| w.position).collect();
    let metrics = evaluate(space, &pts);
    let stats = PlanStats::of(&waypoints, &tasks, excursions_m);
    monitor.progress(1.0);
    Ok(PlanOutput {
        waypoints,
        regions: summaries,
        labels: basis.regions.labels.clone(),
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

fn summary(
    space: &CoverageSpace,
    (cells, contours): (&[usize], &[Vec<usize>]),
    id: usize,
    angle: f64,
) -> RegionSummary {
    let g = space.geometry();
    let area_m2 = cells.len() as f64 * g.resolution * g.resolution;
    let outer = contours.first().cloned().unwrap_or_default();
    let pts: Vec<Point2> = outer.iter().map(|&i| g.center_of(i)).collect();
    let polygon = simplify_polyline(&pts, g.resolution, &|_, _| true);
    RegionSummary {
        id: id as u32,
        polygon,
        angle_rad: angle,
        area_m2,
    }
}
