//! A plan job: everything a worker needs to compute one plan, and the pure function that computes it.
//! The daemon runs [`run_job`] on its bounded blocking pool and feeds the outcome back as an event.

use std::sync::Arc;

use shift_planner::geom::Point2;
use shift_planner::map::grid::{CellState, GridGeometry, OccupancyGrid};
use shift_planner::pipeline::{PlanMonitor, PlanOutput, PlanParams, plan};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::attribute::{AttributeBlob, AttributeMap};
use shift_planner::speed::{SpeedLimits, SpeedParams, SpeedProfile, profile_path};
use shift_proto::{AttributeDoc, PlanRequest};

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

/// Computes the plan and its speed profile (RFICP with the request's attribute blobs; uniform without).
/// With a region polygon, cells whose centre lies outside it are treated as unknown (neither covered nor
/// driven through), so the whole plan stays inside the polygon.
pub fn run_job(job: &PlanJob, monitor: &mut dyn PlanMonitor) -> shift_planner::Result<JobResult> {
    let grid = match &job.request.region {
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
    let robot = RobotShape {
        radius_m: r.radius,
        tool_width_m: r.tool_width,
    };
    let start = Point2::new(job.request.start[0], job.request.start[1]);
    let space = CoverageSpace::new(grid, robot, start)?;
    let params = PlanParams {
        decomposition: job.options.decomposition,
        order: job.options.order,
        pattern: job.options.pattern,
        seed: job.options.seed,
        ..PlanParams::default()
    };
    let output = plan(&space, &params, monitor)?;
    if monitor.cancelled() {
        return Err(shift_planner::PlannerError::Cancelled);
    }
    let attribute = match &job.request.attribute {
        Some(a) => Some(attribute_map(a, space.grid.geometry)?),
        None => None,
    };
    let limits = SpeedLimits::new(r.v_min, r.v_max, r.a_max);
    let speed = SpeedParams::new(limits, r.tool_width);
    let profile = profile_path(&space, &output.waypoints, attribute.as_ref(), &speed)?;
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
                tool_width: 0.2,
                v_min: 0.1,
                v_max: 1.0,
                a_max: 0.5,
            },
            attribute: None,
            region: Some(poly.clone()),
            options: None,
        };
        let options = validate(&request, &grid).expect("valid");
        let job = PlanJob {
            plan_id: "p-1".into(),
            grid,
            request,
            options,
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
}
