//! A prepared plan's expected metrics, before any link is searched: coverage of what its routes drive, its
//! length from the tour's cost, its turns, and the time it takes to drive under the robot's limits.
//!
//! The time is that of a sketch of the final path — the tour's routes in order (legs, and the steps between
//! them along a wall, straight, or round an obstacle as already linked), with straight transits — under
//! [`drive_time`], plus the part of the tour's geodesic transit length the straight transits leave out,
//! driven at v_max. Links only bend transits round what a straight line cuts, so the sketch ranks
//! strategies the way their final plans rank.

use crate::geom::{Point2, polyline_length};
use crate::metrics::{CoverageRaster, count_turns, coverage_of};
use crate::order::Tour;
use crate::pattern::Task;
use crate::pipeline::{PlanParams, Waypoint, WaypointKind};
use crate::smooth::SmoothParams;
use crate::space::CoverageSpace;
use crate::speed::estimate::drive_time;

use super::super::route::RegionRoute;
use super::super::wall_steps::WallSteps;
use super::Linked;

/// A prepared plan's expected metrics (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Share of coverable cells covered, percent.
    pub coverage_pct: f64,
    /// Expected path length, metres.
    pub length_m: f64,
    /// (length × tool width − covered area) / covered area, percent (DESIGN §6).
    pub overlap_pct: f64,
    /// Expected time to drive the plan, seconds, under [`PlanParams::limits`].
    pub duration_s: f64,
    /// Expected heading changes of 30° or more (DESIGN §6).
    pub turns: usize,
}

impl Estimate {
    /// Meets the coverage bar of DESIGN §6 (a prepared plan never collides: every piece is checked).
    pub fn good(&self, target_pct: f64) -> bool {
        self.coverage_pct + 1e-9 >= target_pct
    }

    /// The estimate of the routes `tour` drives, whose coverage `driven` holds.
    pub(super) fn of(
        walls: (&CoverageSpace, &WallSteps, &Linked),
        params: &PlanParams,
        driven: &CoverageRaster,
        (tasks, options): (&[Vec<Task>], &[Vec<RegionRoute>]),
        (active, tour): (&[usize], &Tour),
    ) -> Self {
        let space = walls.0;
        let length_m = tour.cost;
        let c = coverage_of(space, driven, length_m);
        let path = sketch(walls, (tasks, options), (active, tour));
        let points: Vec<Point2> = path.iter().map(|w| w.position).collect();
        let w = space.robot.tool_width_m;
        let limits = params.limits;
        let unsketched_m = (length_m - polyline_length(&points)).max(0.0);
        let duration_s = if length_m.is_finite() {
            drive_time(&path, &limits, &SmoothParams::for_tool(w), w / 4.0) + unsketched_m / limits.v_max_mps
        } else {
            f64::INFINITY
        };
        Self {
            coverage_pct: c.coverage_pct,
            length_m,
            overlap_pct: c.overlap_pct,
            duration_s,
            turns: count_turns(&points),
        }
    }
}

/// The path the tour drives as far as it is known before linking (see the module docs): from the dock
/// through every route in order and back, transits straight.
fn sketch(
    (space, walls, linked): (&CoverageSpace, &WallSteps, &Linked),
    (tasks, options): (&[Vec<Task>], &[Vec<RegionRoute>]),
    (active, tour): (&[usize], &Tour),
) -> Vec<Waypoint> {
    let at = |position: Point2, kind: WaypointKind| Waypoint {
        position,
        kind,
        region: None,
    };
    let mut path = vec![at(space.start, WaypointKind::Transit)];
    for (&k, &o) in tour.order.iter().zip(&tour.options) {
        let id = active[k];
        let Some(route) = options.get(id).and_then(|r| r.get(o)) else {
            continue;
        };
        let mut prev: Option<Point2> = None;
        for (j, leg) in route.legs.iter().enumerate() {
            let pts = leg.points(&tasks[id]);
            if let (Some(a), Some(&b)) = (prev, pts.first()) {
                let step = walls.along(space, a, b).or_else(|| linked.get(a, b));
                if let Some(step) = step {
                    path.extend(step.iter().map(|&p| at(p, WaypointKind::Cover)));
                }
            }
            let kind = |i: usize| {
                if i == 0 && j == 0 {
                    WaypointKind::Transit
                } else {
                    WaypointKind::Cover
                }
            };
            path.extend(pts.iter().enumerate().map(|(i, &p)| at(p, kind(i))));
            prev = pts.last().copied();
        }
    }
    path.push(at(space.start, WaypointKind::Transit));
    path
}
