//! The record the engine keeps (and the store persists) per mission, the check of a mission request, and the
//! mission's view built from its plans.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use shift_planner::geom::Point2;
use shift_planner::map::grid::{CellState, OccupancyGrid};
use shift_proto::{
    MissionCoverage, MissionPlanView, MissionRequest, MissionStatus, MissionView, PlanRequest, PlanStatus,
};

use crate::cell_mask::CellMask;
use crate::coverage::Raster;
use crate::error::{EngineError, Result};
use crate::plan::PlanRecord;
use crate::request::{ParsedOptions, validate};

/// One mission's state. Every change is persisted as a whole record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionRecord {
    /// Mission id (`m-…`).
    pub mission_id: String,
    /// Acceptance order (shared with plans: ids and queue order come from it).
    pub seq: u64,
    /// The request as accepted.
    pub request: MissionRequest,
    /// Lifecycle state.
    pub status: MissionStatus,
    /// Planning progress, 0–1.
    pub progress: f64,
    /// One plan per robot, in the request's order.
    pub plan_ids: Vec<String>,
    /// What the division found, once planned.
    #[serde(default)]
    pub planned: Option<MissionPlanned>,
    /// Why it failed.
    #[serde(default)]
    pub error: Option<String>,
    /// Remarks of division and planning.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// How many times a worker started it.
    pub attempts: u32,
    /// Robots whose parts were divided among the others (lost while driving); they take a share again when
    /// they come back.
    #[serde(default)]
    pub dropped: Vec<String>,
    /// A replan of what is left, waiting for a worker or running.
    #[serde(default)]
    pub replan: Option<ReplanOrder>,
    /// Replans done.
    #[serde(default)]
    pub replans: u32,
    /// Accepted at, milliseconds since the Unix epoch.
    pub created_ms: u64,
    /// Last change, milliseconds since the Unix epoch.
    pub updated_ms: u64,
}

/// Why and for whom a mission's remainder is replanned.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplanOrder {
    /// Why (`requested`, `robot r2 lost`, `robot r2 came back`, `the daemon restarted`).
    pub reason: String,
    /// Its job runs; the ids of the robots it plans for, in the mission's order.
    #[serde(default)]
    pub running: Option<Vec<String>>,
    /// Asked again while it ran: run once more when it ends (the fleet changed under it).
    #[serde(default)]
    pub again: bool,
}

/// The division's and the plans' figures together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionPlanned {
    /// The cells some robot of the fleet can cover (what measured coverage counts against).
    pub coverable: CellMask,
    /// Coverable area of each robot's part, m², in the robots' order.
    pub areas_m2: Vec<f64>,
    /// Coverable cells covered by the union of the planned paths, percent.
    pub planned_pct: f64,
    /// Coverable area planned by two robots or more, percent.
    pub seam_pct: f64,
}

impl MissionRecord {
    /// The plan request each robot's part is planned with (the site, its dock and shape, the mission's
    /// attribute map, options and objective).
    pub fn plan_request(request: &MissionRequest, i: usize) -> Option<PlanRequest> {
        let r = request.robots.get(i)?;
        Some(PlanRequest {
            attribute: request.attribute.clone(),
            options: request.options.clone(),
            objective: request.objective,
            ..PlanRequest::new(request.site.clone(), r.start, r.spec())
        })
    }

    /// The `GET /v1/missions/{id}` body: its plans as `plans` holds them now, `measured_pct` swept.
    pub fn to_view(&self, plans: &HashMap<String, PlanRecord>, measured_pct: f64) -> MissionView {
        let mut views = Vec::with_capacity(self.plan_ids.len());
        let (mut total_s, mut driven_s, mut eta_s) = (0.0, 0.0, None::<f64>);
        for (i, plan_id) in self.plan_ids.iter().enumerate() {
            let robot = self.request.robots.get(i).map(|r| r.id.clone()).unwrap_or_default();
            let rec = plans.get(plan_id);
            let status = rec.map_or(PlanStatus::Cancelled, |r| r.status);
            let duration = rec.and_then(|r| r.metrics).map(|m| m.duration_s);
            let driven = match status {
                PlanStatus::Done => 1.0,
                _ => rec.map_or(0.0, |r| r.driven_fraction),
            };
            if let Some(d) = duration {
                total_s += d;
                driven_s += d * driven;
                let left = match status {
                    PlanStatus::Ready | PlanStatus::Active => d * (1.0 - driven),
                    _ => 0.0,
                };
                eta_s = Some(eta_s.unwrap_or(0.0).max(left));
            }
            views.push(MissionPlanView {
                robot,
                plan_id: plan_id.clone(),
                status,
                version: rec.map_or(0, |r| r.version),
                planned_duration_s: duration,
                area_m2: self.planned.as_ref().and_then(|p| p.areas_m2.get(i).copied()),
                driven_fraction: driven,
            });
        }
        let progress = match self.status {
            MissionStatus::Queued | MissionStatus::Planning => self.progress,
            _ if total_s > 0.0 => driven_s / total_s,
            _ => 0.0,
        };
        MissionView {
            mission_id: self.mission_id.clone(),
            site: self.request.site.clone(),
            status: self.status,
            progress,
            plans: views,
            coverage: MissionCoverage {
                planned_pct: self.planned.as_ref().map(|p| p.planned_pct),
                measured_pct,
                seam_pct: self.planned.as_ref().map(|p| p.seam_pct),
            },
            eta_s,
            error: self.error.clone(),
            warnings: self.warnings.clone(),
            created_ms: self.created_ms,
            updated_ms: self.updated_ms,
        }
    }

    /// The status its plans give a planned mission (the plans of dropped robots aside): `done` when every plan
    /// was driven to its end, `failed` when all are settled and some were not driven (cancelled or failed; a
    /// replan of the remainder picks up) or no robot is left,
    /// `active` while any is driven or some are done, else `ready`.
    pub fn status_from_plans(&self, plans: &HashMap<String, PlanRecord>) -> MissionStatus {
        let statuses: Vec<PlanStatus> = (self.plan_ids.iter().zip(&self.request.robots))
            .filter(|(_, r)| !self.dropped.contains(&r.id))
            .map(|(id, _)| plans.get(id).map_or(PlanStatus::Cancelled, |r| r.status))
            .collect();
        let settled = |s: &PlanStatus| matches!(s, PlanStatus::Done | PlanStatus::Failed | PlanStatus::Cancelled);
        if statuses.is_empty() {
            MissionStatus::Failed
        } else if statuses.iter().all(|s| *s == PlanStatus::Done) {
            MissionStatus::Done
        } else if statuses.iter().all(settled) {
            MissionStatus::Failed
        } else if statuses
            .iter()
            .any(|s| matches!(s, PlanStatus::Active | PlanStatus::Done))
        {
            MissionStatus::Active
        } else {
            MissionStatus::Ready
        }
    }
}

/// What the engine holds of a mission besides its record.
#[derive(Debug, Clone)]
pub(crate) struct MissionState {
    pub(crate) record: MissionRecord,
    /// Its measured raster (once planned), counting the mission's coverable cells.
    pub(crate) raster: Option<Arc<Raster>>,
    /// When its view was last pushed.
    pub(crate) view_ms: u64,
    /// Its plans changed since.
    pub(crate) dirty: bool,
}

fn invalid(msg: String) -> EngineError {
    EngineError::InvalidRequest(msg)
}

/// Checks a mission request against its site's map: at least one robot and at most
/// [`MissionRequest::MAX_ROBOTS`], ids valid and unique, every robot's plan request valid (the fields named
/// `robots[i].…`), every dock on a free cell of the map and not inside another robot's footprint at its dock,
/// and enough free area for the fleet (each robot at least four times its footprint). Returns the options
/// every part is planned with.
pub fn validate_mission(req: &MissionRequest, grid: &OccupancyGrid) -> Result<ParsedOptions> {
    crate::site::validate_name("site", &req.site)?;
    if req.robots.is_empty() {
        return Err(invalid("robots must name at least one robot".into()));
    }
    if req.robots.len() > MissionRequest::MAX_ROBOTS {
        return Err(invalid(format!(
            "robots holds {} robots; at most {} are accepted",
            req.robots.len(),
            MissionRequest::MAX_ROBOTS
        )));
    }
    let mut ids = HashSet::new();
    let mut options = None;
    let g = &grid.geometry;
    let mut footprints = 0.0;
    for (i, r) in req.robots.iter().enumerate() {
        crate::site::validate_name("robot", &r.id).map_err(|e| invalid(format!("robots[{i}].id: {e}")))?;
        if !ids.insert(r.id.as_str()) {
            return Err(invalid(format!("robots[{i}].id {:?} is named twice", r.id)));
        }
        let plan = MissionRecord::plan_request(req, i).ok_or_else(|| invalid(format!("robots[{i}] is missing")))?;
        let parsed = validate(&plan, grid).map_err(|e| match e {
            EngineError::InvalidRequest(m) => {
                let m = m.replacen("robot.", "", 1);
                invalid(format!("robots[{i}] ({}): {m}", r.id))
            }
            other => other,
        })?;
        options.get_or_insert(parsed);
        let start = Point2::new(r.start[0], r.start[1]);
        match g.locate(start).map(|c| grid.state(c)) {
            Some(CellState::Free) => {}
            state => {
                let what = match state {
                    Some(CellState::Occupied) => "an occupied cell",
                    _ => "an unknown cell",
                };
                return Err(invalid(format!(
                    "robots[{i}].start ({}, {}) lies on {what} of the map; a dock must be on free floor",
                    r.start[0], r.start[1]
                )));
            }
        }
        for (j, o) in req.robots.iter().enumerate().take(i) {
            let d = (r.start[0] - o.start[0]).hypot(r.start[1] - o.start[1]);
            let (ri, rj) = (r.outer_radius(), o.outer_radius());
            if d < ri + rj {
                return Err(invalid(format!(
                    "robots[{i}].start is {d:.3} m from robots[{j}].start, closer than their radii ({ri} + {rj} m)"
                )));
            }
        }
        footprints += 4.0 * std::f64::consts::PI * r.outer_radius().powi(2);
    }
    let free_m2 = grid.cells.iter().filter(|&&c| c == CellState::Free).count() as f64 * g.resolution * g.resolution;
    if footprints > free_m2 {
        return Err(invalid(format!(
            "robots: {} robots need at least {footprints:.1} m² of free floor (four footprints each); the map has \
             {free_m2:.1} m²",
            req.robots.len()
        )));
    }
    options.ok_or_else(|| invalid("robots must name at least one robot".into()))
}

#[cfg(test)]
mod tests {
    use shift_planner::map::grid::GridGeometry;
    use shift_proto::MissionRobot;

    use super::*;

    fn room() -> OccupancyGrid {
        let g = GridGeometry::new(60, 40, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        for c in 0..60 {
            grid.cells[c] = CellState::Occupied;
        }
        grid
    }

    fn request(robots: Vec<MissionRobot>) -> MissionRequest {
        MissionRequest {
            site: "room".into(),
            robots,
            attribute: None,
            options: None,
            objective: None,
        }
    }

    fn error_of(req: &MissionRequest) -> String {
        validate_mission(req, &room()).expect_err("refused").to_string()
    }

    #[test]
    fn bad_fleets_are_refused_naming_the_field() {
        let ok = MissionRobot::new("r1", [1.0, 1.0], 0.2, 0.4);
        assert!(validate_mission(&request(vec![ok.clone()]), &room()).is_ok());
        assert!(error_of(&request(vec![])).contains("robots must name"));
        let dup = request(vec![ok.clone(), MissionRobot::new("r1", [4.0, 2.0], 0.2, 0.4)]);
        assert!(error_of(&dup).contains("robots[1].id \"r1\" is named twice"));
        let bad_id = request(vec![MissionRobot::new("r 1", [1.0, 1.0], 0.2, 0.4)]);
        assert!(error_of(&bad_id).contains("robots[0].id"), "{}", error_of(&bad_id));
        let outside = request(vec![ok.clone(), MissionRobot::new("r2", [40.0, 1.0], 0.2, 0.4)]);
        let e = error_of(&outside);
        assert!(e.contains("robots[1] (r2)") && e.contains("outside the map"), "{e}");
        let in_wall = request(vec![MissionRobot::new("r2", [1.0, 0.05], 0.2, 0.4)]);
        assert!(error_of(&in_wall).contains("robots[0].start (1, 0.05) lies on an occupied cell"));
        let nan = request(vec![MissionRobot::new("r2", [1.0, 1.0], f64::NAN, 0.4)]);
        let e = error_of(&nan);
        assert!(e.contains("robots[0] (r2): radius must be a finite number"), "{e}");
        let stacked = request(vec![ok.clone(), MissionRobot::new("r2", [1.2, 1.0], 0.2, 0.4)]);
        assert!(error_of(&stacked).contains("robots[1].start is 0.200 m from robots[0].start"));
        let crowd: Vec<MissionRobot> = (0..40)
            .map(|k| {
                MissionRobot::new(
                    format!("r{k}"),
                    [0.3 + (k % 10) as f64 * 0.55, 0.5 + (k / 10) as f64 * 0.9],
                    0.25,
                    0.5,
                )
            })
            .collect();
        let e = error_of(&request(crowd));
        assert!(e.contains("40 robots need at least"), "{e}");
    }
}
