//! A mission job: everything a worker needs to divide a site among a fleet and plan every part, and the pure
//! function that does it ([`shift_planner::pipeline::fleet::plan_fleet`]: division balanced by planned
//! durations). The daemon runs [`run_mission_job`] on its plan pool and feeds [`MissionOutcome`] back as an
//! event.

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use shift_planner::divide::FleetRobot;
use shift_planner::footprint::Footprint;
use shift_planner::geom::Point2;
use shift_planner::map::grid::OccupancyGrid;
use shift_planner::pipeline::fleet::{FleetParams, FleetPlan, plan_fleet_monitored};
use shift_planner::pipeline::remainder::plan_fleet_remainder;
use shift_planner::pipeline::resume::{FleetResume, Lost, Previous, ResumeParams, resume_fleet};
use shift_planner::pipeline::{NoMonitor, PlanMonitor, PlanParams, Waypoint};
use shift_planner::remainder::RemainderParams;
use shift_planner::space::RobotShape;
use shift_planner::speed::SpeedLimits;
use shift_planner::speed::attribute::AttributeMap;
use shift_proto::{MissionRequest, MissionRobot, PlanDocument};

use crate::cell_mask::CellMask;
use crate::job::{apply_overlay, attribute_map, objective};
use crate::mission::MissionPlanned;
use crate::plan_doc::{to_document, waypoint_from_doc};
use crate::request::ParsedOptions;

/// One mission to divide and plan.
#[derive(Debug, Clone)]
pub struct MissionJob {
    /// Mission id.
    pub mission_id: String,
    /// Its plans' ids, in the robots' order.
    pub plan_ids: Vec<String>,
    /// The site's grid at the time the job started.
    pub grid: Arc<OccupancyGrid>,
    /// The request as accepted.
    pub request: MissionRequest,
    /// Its parsed options.
    pub options: ParsedOptions,
    /// Live obstacle points (x, y, map frame) marked occupied where the static map is free (filled in by the
    /// daemon, as for plan jobs; each dock is kept clear).
    pub overlay: Vec<[f64; 2]>,
    /// A replan: the cells already swept (one flag per grid cell); only the rest is divided and planned, each
    /// robot from its `start` (where it is now).
    pub covered: Option<Arc<Vec<bool>>>,
    /// A replan: per robot (in the request's order), the plan it is driving and the last waypoint it reached
    /// on it (empty when a robot lost with its part unfinished left no plan at hand to hand over). When every
    /// robot has one, the job first tries to resume them
    /// ([`shift_planner::pipeline::resume`]): cheaper by far than a new division, and the robots keep the
    /// paths they were driving; it divides the remainder again when resuming would leave ground out or
    /// finish later.
    pub previous: Vec<Option<(Arc<PlanDocument>, usize)>>,
    /// A replan: the robots lost with their plans unfinished, each with the plan it was driving; resuming
    /// hands their lanes to the others ([`shift_planner::pipeline::resume::Lost`]).
    pub lost: Vec<LostPlan>,
}

/// A robot lost with its plan unfinished (see [`MissionJob::lost`]).
#[derive(Debug, Clone)]
pub struct LostPlan {
    /// The robot as the mission holds it.
    pub robot: MissionRobot,
    /// The plan it was driving.
    pub doc: Arc<PlanDocument>,
    /// The last waypoint it reached on it.
    pub reached: usize,
}

/// One robot's planned part.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedPart {
    /// Its plan document (version 1).
    pub doc: Arc<PlanDocument>,
    /// Planner remarks.
    pub warnings: Vec<String>,
}

/// How a mission job ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum MissionOutcome {
    /// Divided and planned.
    Planned {
        /// One part per robot, in the robots' order.
        parts: Vec<PlannedPart>,
        /// The division's figures.
        planned: MissionPlanned,
        /// Division remarks.
        warnings: Vec<String>,
    },
    /// Division or a part's plan failed.
    Failed {
        /// Why.
        reason: String,
    },
    /// Stopped because the daemon is shutting down; the mission goes back to the queue.
    Interrupted,
}

/// Divides and plans (see the module docs).
pub fn run_mission_job(job: &MissionJob) -> shift_planner::Result<FleetPlan> {
    run_mission_job_monitored(job, &mut NoMonitor)
}

/// [`run_mission_job`] watched by `monitor`: a cancel stops the division's planning rounds and the part being
/// planned, with [`shift_planner::PlannerError::Cancelled`].
pub fn run_mission_job_monitored(job: &MissionJob, monitor: &mut dyn PlanMonitor) -> shift_planner::Result<FleetPlan> {
    let mut grid = (*job.grid).clone();
    let res = grid.geometry.resolution;
    let robots: Vec<FleetRobot> = (job.request.robots.iter())
        .map(|r| fleet_robot(r, res))
        .collect::<shift_planner::Result<_>>()?;
    if !job.overlay.is_empty() {
        // The live overlay must not block any dock (another robot standing there was seen by its neighbours).
        let mut keep: Vec<[f64; 2]> = job.overlay.clone();
        for r in &robots {
            let outer = r
                .footprint
                .as_ref()
                .map_or(r.shape.radius_m, Footprint::circumscribed_radius_m);
            let clear = 2.0 * outer + grid.geometry.resolution;
            keep.retain(|p| (Point2::new(p[0], p[1]) - r.start).norm() >= clear);
        }
        apply_overlay(&mut grid, &keep, Point2::origin(), 0.0);
    }
    let params = PlanParams {
        decomposition: job.options.decomposition,
        order: job.options.order,
        pattern: job.options.pattern,
        seed: job.options.seed,
        objective: objective(job.request.objective.unwrap_or_default()),
        ..PlanParams::default()
    };
    let attribute = match &job.request.attribute {
        Some(a) => Some(attribute_map(a, grid.geometry)?),
        None => None,
    };
    match &job.covered {
        None => plan_fleet_monitored(
            &grid,
            &robots,
            &params,
            attribute.as_ref(),
            &FleetParams::default(),
            monitor,
        ),
        Some(covered) => {
            let why = match resume(job, &grid, &robots, covered, attribute.as_ref())? {
                FleetResume::Resumed(resumed) => return Ok(resumed.fleet),
                FleetResume::Refused(why) => why,
            };
            let mut fleet = plan_fleet_remainder(
                &grid,
                &robots,
                covered,
                (&params, &RemainderParams::default()),
                attribute.as_ref(),
                &FleetParams::default(),
                monitor,
            )?
            .fleet;
            fleet.division.warnings.push(why);
            Ok(fleet)
        }
    }
}

/// The planner's view of a mission robot; a footprint plans in the space of its inscribed planning radius (as
/// a single plan does) on a grid of `resolution` metres.
fn fleet_robot(r: &MissionRobot, resolution: f64) -> shift_planner::Result<FleetRobot> {
    let footprint = r.footprint.as_deref().map(Footprint::new).transpose()?;
    Ok(FleetRobot {
        start: Point2::new(r.start[0], r.start[1]),
        shape: RobotShape {
            radius_m: footprint.as_ref().map_or(r.radius, |f| f.planning_radius_m(resolution)),
            tool_width_m: r.tool_width,
        },
        limits: SpeedLimits::new(r.v_min, r.v_max, r.a_max),
        footprint,
    })
}

/// The robots' plans resumed (see [`MissionJob::previous`]), the lost robots' lanes handed over
/// ([`MissionJob::lost`]), or why the remainder is to be divided.
fn resume(
    job: &MissionJob,
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    covered: &[bool],
    attribute: Option<&AttributeMap>,
) -> shift_planner::Result<FleetResume> {
    if job.previous.len() != robots.len() || job.previous.iter().any(Option::is_none) {
        return Ok(FleetResume::Refused(
            "not resumed: the fleet changed (a robot lost with its plan not at hand, or one without a plan of the mission)"
                .into(),
        ));
    }
    let paths: Vec<(Vec<Waypoint>, usize)> = (job.previous.iter().flatten())
        .map(|(doc, reached)| (doc.waypoints.iter().map(waypoint_from_doc).collect(), *reached))
        .collect();
    let previous: Vec<Previous<'_>> = (paths.iter().zip(robots))
        .map(|((path, reached), r)| Previous {
            path,
            reached: *reached,
            from: r.start,
        })
        .collect();
    let lost_robots: Vec<FleetRobot> = (job.lost.iter())
        .map(|l| fleet_robot(&l.robot, grid.geometry.resolution))
        .collect::<shift_planner::Result<_>>()?;
    let lost_paths: Vec<Vec<Waypoint>> = (job.lost.iter())
        .map(|l| l.doc.waypoints.iter().map(waypoint_from_doc).collect())
        .collect();
    let lost: Vec<Lost<'_>> = (job.lost.iter().zip(&lost_robots).zip(&lost_paths))
        .filter(|(_, path)| !path.is_empty())
        .map(|((l, robot), path)| {
            let at = l.reached.min(path.len() - 1);
            Lost {
                robot,
                previous: Previous {
                    path,
                    reached: at,
                    // Its lanes are handed over from where it was on its plan (its last pose may be off it).
                    from: path[at].position,
                },
            }
        })
        .collect();
    resume_fleet(
        grid,
        robots,
        (&previous, &lost),
        covered,
        &RemainderParams::default(),
        attribute,
        &ResumeParams::default(),
    )
}

/// The outcome of a computed mission: a plan document per part (`compute_ms` is the whole job's time).
pub fn planned_outcome(job: &MissionJob, fleet: &FleetPlan, compute_ms: f64) -> MissionOutcome {
    let with_attribute = job.request.attribute.is_some();
    let parts = (fleet.division.parts.iter().zip(&fleet.plans).zip(&job.plan_ids))
        .enumerate()
        .map(|(k, ((part, (output, profile)), plan_id))| {
            let mut doc = to_document(plan_id, (&part.space, output), profile, with_attribute, compute_ms);
            // A resumed plan sweeps the regions of the plan it resumes.
            if output.regions.is_empty()
                && let Some(Some((previous, _))) = job.previous.get(k)
            {
                doc.regions = previous.regions.clone();
            }
            PlannedPart {
                doc: Arc::new(doc),
                warnings: output.warnings.clone(),
            }
        })
        .collect();
    MissionOutcome::Planned {
        parts,
        planned: MissionPlanned {
            coverable: CellMask::encode(&fleet.division.coverable),
            areas_m2: fleet.division.parts.iter().map(|p| p.owned_area_m2).collect(),
            planned_pct: fleet.metrics.union_coverage_pct,
            seam_pct: fleet.metrics.seam_overlap_pct,
        },
        warnings: fleet.division.warnings.clone(),
    }
}
