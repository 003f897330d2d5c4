//! A plan job: everything a worker needs to compute one plan, and the pure function that computes it.
//! The daemon runs [`run_job`] on its bounded blocking pool and feeds the outcome back as an event.

use std::sync::Arc;

use shift_planner::PlannerError;
use shift_planner::footprint::{FOOTPRINT_FIELD, Footprint};
use shift_planner::geom::Point2;
use shift_planner::map::grid::{CellState, GridGeometry, OccupancyGrid};
use shift_planner::pipeline::{Objective, PlanMonitor, PlanOutput, PlanParams, plan_footprinted, plan_shaped};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::attribute::{AttributeBlob, AttributeMap};
use shift_planner::speed::{SpeedLimits, SpeedParams, SpeedProfile};
use shift_proto::{AttributeDoc, PlanObjective, PlanRequest};

use crate::request::{ParsedOptions, point_in_polygon};

/// One plan to compute.
#[derive(Debug, Clone)]
pub struct PlanJob {
    /// Plan id.
    pub plan_id: String,
    /// The site's grid at the time the job started.
    pub grid: Arc<OccupancyGrid>,
    /// The request as accepted.
    pub request: PlanRequest,
    /// Its parsed options.
    pub options: ParsedOptions,
    /// Live obstacle points (x, y in the map frame, metres) to mark occupied where the static map is free:
    /// the site's live map when the job started, filled in by the daemon; empty = the static map alone.
    pub overlay: Vec<[f64; 2]>,
}

/// Marks the cells holding `points` (x, y map frame, metres) occupied where `grid` says free, except within
/// `keep_clear_m` of `keep_clear_at` (the robot at its start, which another robot's sensor may have seen).
/// Points off the grid or not finite are ignored. Returns how many cells changed.
pub fn apply_overlay(grid: &mut OccupancyGrid, points: &[[f64; 2]], keep_clear_at: Point2, keep_clear_m: f64) -> usize {
    let mut changed = 0;
    for p in points {
        let q = Point2::new(p[0], p[1]);
        if !(q.x.is_finite() && q.y.is_finite()) || (q - keep_clear_at).norm() < keep_clear_m {
            continue;
        }
        let Some(c) = grid.geometry.locate(q) else { continue };
        if grid.state(c) == CellState::Free {
            grid.set(c, CellState::Occupied);
            changed += 1;
        }
    }
    changed
}

/// The planner's attribute map from wire blobs (`POST /v1/plans` `attribute`, `shiftd plan --attribute x.json`).
pub fn attribute_map(doc: &AttributeDoc, geometry: GridGeometry) -> shift_planner::Result<AttributeMap> {
    let blobs: Vec<AttributeBlob> = doc
        .blobs
        .iter()
        .map(|b| AttributeBlob {
            centre: Point2::new(b.x, b.y),
            sigma_m: b.sigma,
            amplitude: b.amplitude,
        })
        .collect();
    AttributeMap::from_blobs(geometry, &blobs)
}

/// The planner's objective for the wire's.
pub(crate) fn objective(o: PlanObjective) -> Objective {
    match o {
        PlanObjective::Time => Objective::Time,
        PlanObjective::Length => Objective::Length,
        PlanObjective::Overlap => Objective::Overlap,
        PlanObjective::Turns => Objective::Turns,
    }
}

/// A computed job: the planner's output and its smoothed, timed speed profile.
#[derive(Debug)]
pub struct JobResult {
    /// The coverage space planned in.
    pub space: CoverageSpace,
    /// The plan (regions, waypoints before smoothing).
    pub output: PlanOutput,
    /// Smoothed waypoints with speed and time, and the metrics of that path.
    pub profile: SpeedProfile,
    /// An attribute map was given (the dwell uniformity figures mean something).
    pub with_attribute: bool,
}

/// Computes the plan and its speed profile (RFICP with the request's attribute blobs; uniform without). A
/// robot given by a footprint polygon is planned with [`plan_footprinted`] (its metrics count footprint
/// collisions).
/// With a region polygon, cells whose centre lies outside it are treated as unknown (neither covered nor
/// driven through), so the whole plan stays inside the polygon. The job's live overlay marks free cells
/// occupied ([`apply_overlay`]; points within two robot radii plus a cell of the start are left out, so a
/// robot seen by another robot does not block its own start).
pub fn run_job(job: &PlanJob, monitor: &mut dyn PlanMonitor) -> shift_planner::Result<JobResult> {
    let mut grid = match &job.request.region {
        None => (*job.grid).clone(),
        Some(poly) => {
            let mut g = (*job.grid).clone();
            for i in 0..g.cells.len() {
                if !point_in_polygon(g.geometry.center_of(i), poly) {
                    g.cells[i] = CellState::Unknown;
                }
            }
            g
        }
    };
    let r = &job.request.robot;
    // A footprint polygon plans in the space of its inscribed planning radius (planner::pipeline::footprinted);
    // the robot is never wider than its circumscribed disc.
    let footprint = r.footprint.as_deref().map(Footprint::new).transpose()?;
    let res = grid.geometry.resolution;
    let (radius_m, outer_m) = match &footprint {
        Some(f) => (f.planning_radius_m(res), f.circumscribed_radius_m()),
        None => (r.radius, r.radius),
    };
    let robot = RobotShape {
        radius_m,
        tool_width_m: r.tool_width,
    };
    let start = Point2::new(job.request.start[0], job.request.start[1]);
    if !job.overlay.is_empty() {
        let keep_clear_m = 2.0 * outer_m + res;
        apply_overlay(&mut grid, &job.overlay, start, keep_clear_m);
    }
    let space = match CoverageSpace::with_start_snap(grid, robot, start, job.request.snap_start_m) {
        Err(PlannerError::NoTraversableSpace { .. }) if footprint.is_some() => {
            return Err(PlannerError::InvalidParam {
                name: FOOTPRINT_FIELD,
                reason: format!(
                    "the robot fits nowhere on this map: not even its inscribed disc (radius {:.3} m, plus half a \
                     cell) clears the walls",
                    footprint.as_ref().map_or(0.0, Footprint::inscribed_radius_m)
                ),
            });
        }
        other => other?,
    };
    let limits = SpeedLimits::new(r.v_min, r.v_max, r.a_max);
    let params = PlanParams {
        decomposition: job.options.decomposition,
        order: job.options.order,
        pattern: job.options.pattern,
        seed: job.options.seed,
        objective: objective(job.request.objective.unwrap_or_default()),
        limits,
        ..PlanParams::default()
    };
    let attribute = match &job.request.attribute {
        Some(a) => Some(attribute_map(a, space.grid.geometry)?),
        None => None,
    };
    let speed = SpeedParams::new(limits, r.tool_width);
    let (output, profile) = match &footprint {
        Some(f) => plan_footprinted(&space, f, &params, attribute.as_ref(), &speed, monitor)?,
        None => plan_shaped(&space, &params, attribute.as_ref(), &speed, monitor)?,
    };
    if monitor.cancelled() {
        return Err(shift_planner::PlannerError::Cancelled);
    }
    Ok(JobResult {
        space,
        output,
        profile,
        with_attribute: attribute.is_some(),
    })
}

#[cfg(test)]
mod tests {
    use shift_planner::map::grid::GridGeometry;
    use shift_planner::pipeline::NoMonitor;
    use shift_proto::RobotSpec;

    use super::*;
    use crate::request::validate;

    #[test]
    fn region_polygon_confines_the_plan() {
        let g = GridGeometry::new(60, 40, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let grid = Arc::new(OccupancyGrid::filled(g, CellState::Free));
        let poly = vec![[0.5, 0.5], [3.0, 0.5], [3.0, 3.5], [0.5, 3.5]];
        let request = PlanRequest {
            site: "s".into(),
            start: [1.0, 1.0],
            robot: RobotSpec {
                radius: 0.1,
                footprint: None,
                tool_width: 0.2,
                v_min: 0.1,
                v_max: 1.0,
                a_max: 0.5,
            },
            attribute: None,
            region: Some(poly.clone()),
            options: None,
            objective: None,
            snap_start_m: None,
        };
        let options = validate(&request, &grid).expect("valid");
        let job = PlanJob {
            plan_id: "p-1".into(),
            grid,
            request,
            options,
            overlay: Vec::new(),
        };
        let res = run_job(&job, &mut NoMonitor).expect("plans");
        let m = res.profile.metrics;
        assert!(m.coverage_pct >= 99.0, "{m:?}");
        assert_eq!(m.collisions, 0);
        for w in &res.profile.waypoints {
            let p = w.waypoint.position;
            assert!(point_in_polygon(p, &poly), "{p:?} leaves the region");
            assert!(
                w.speed_mps >= 0.1 - 1e-9 && w.speed_mps <= 1.0 + 1e-9,
                "{}",
                w.speed_mps
            );
        }
    }

    fn open_request(start: [f64; 2]) -> PlanRequest {
        PlanRequest {
            site: "s".into(),
            start,
            robot: RobotSpec {
                radius: 0.1,
                footprint: None,
                tool_width: 0.2,
                v_min: 0.1,
                v_max: 1.0,
                a_max: 0.5,
            },
            attribute: None,
            region: None,
            options: None,
            objective: None,
            snap_start_m: None,
        }
    }

    #[test]
    fn live_overlay_obstacle_is_avoided() {
        // 4 m × 3 m open room; a 0.6 m × 0.6 m obstacle seen by a robot in the middle (5 cm points).
        let g = GridGeometry::new(40, 30, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let grid = Arc::new(OccupancyGrid::filled(g, CellState::Free));
        let mut overlay = Vec::new();
        for i in 0..12 {
            for j in 0..12 {
                overlay.push([1.725 + i as f64 * 0.05, 1.225 + j as f64 * 0.05]);
            }
        }
        overlay.push([f64::NAN, 1.0]); // ignored
        overlay.push([50.0, 1.0]); // off the grid: ignored
        overlay.push([0.52, 0.5]); // next to the start: the robot itself, left out
        let request = open_request([0.5, 0.5]);
        let options = validate(&request, &grid).expect("valid");
        let mut job = PlanJob {
            plan_id: "p-1".into(),
            grid: grid.clone(),
            request,
            options,
            overlay: Vec::new(),
        };
        let near_block = |p: Point2| p.x > 1.7 && p.x < 2.3 && p.y > 1.2 && p.y < 1.8;
        let bare = run_job(&job, &mut NoMonitor).expect("plans without the overlay");
        assert!(
            bare.profile.waypoints.iter().any(|w| near_block(w.waypoint.position)),
            "without the overlay the plan sweeps the block's area"
        );
        job.overlay = overlay;
        let res = run_job(&job, &mut NoMonitor).expect("plans with the overlay");
        let mut overlaid = (*grid).clone();
        let changed = apply_overlay(&mut overlaid, &job.overlay, Point2::new(0.5, 0.5), 0.3);
        assert_eq!(changed, 36, "6 × 6 cells of 0.1 m");
        assert_eq!(
            res.space.grid.cells, overlaid.cells,
            "the job planned on the overlaid grid"
        );
        let m = res.profile.metrics;
        assert_eq!(m.collisions, 0, "{m:?}");
        assert!(m.coverage_pct >= 99.0, "{m:?}");
        // Every path point keeps the robot radius from every overlaid cell centre (1.75–2.25, 1.25–1.75).
        for w in &res.profile.waypoints {
            let p = w.waypoint.position;
            let dx = (p.x - 2.0).abs() - 0.25;
            let dy = (p.y - 1.5).abs() - 0.25;
            let d = dx.max(0.0).hypot(dy.max(0.0));
            assert!(d >= 0.1 - 1e-6, "{p:?} is {d} m from the obstacle");
        }
    }

    /// A rectangular robot (a footprint, no radius) plans through a doorway only it passes lengthwise; the
    /// document it becomes has no footprint collision, counted again here.
    #[test]
    fn a_footprint_request_plans_through_the_job() {
        let rooms = shift_planner::testing::two_rooms((4.0, 4.0), 0.2, 1.0, 0.0, 0.05).expect("scene");
        let grid = Arc::new(rooms.grid.clone());
        let rect = vec![[0.6, 0.4], [-0.6, 0.4], [-0.6, -0.4], [0.6, -0.4]];
        let request = PlanRequest {
            robot: RobotSpec {
                radius: 0.0,
                footprint: Some(rect.clone()),
                tool_width: 0.8,
                ..RobotSpec::new(0.0, 0.8)
            },
            ..open_request([rooms.start.x, rooms.start.y])
        };
        let options = validate(&request, &grid).expect("valid");
        let job = PlanJob {
            plan_id: "p-1".into(),
            grid,
            request,
            options,
            overlay: Vec::new(),
        };
        let res = run_job(&job, &mut NoMonitor).expect("plans");
        let doc = crate::plan_doc::to_document("p-1", (&res.space, &res.output), &res.profile, false, 1.0);
        assert_eq!(doc.metrics.collisions, 0, "{:?}", doc.metrics);
        let fp = Footprint::new(&rect).expect("valid");
        let check =
            shift_planner::footprint::FootprintCheck::new(&res.space.grid, &res.space.clearance, &fp).expect("check");
        let path: Vec<Point2> = doc.waypoints.iter().map(|w| Point2::new(w.x, w.y)).collect();
        assert_eq!(check.count_collisions(&path), 0);
        assert!(
            path.iter().any(|&p| rooms.in_far_room(p)),
            "the plan reaches the far room"
        );
        assert!(doc.metrics.coverage_pct > 60.0, "{:?}", doc.metrics);
    }
}
