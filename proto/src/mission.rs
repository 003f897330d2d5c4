//! Missions (DESIGN §5.3 extended by issue 20): one request for a fleet on one site. The site is divided among
//! the robots, each part planned as an ordinary plan (`/v1/plans/{plan_id}`), and what the robots really swept
//! is measured. Field names are the contract.

use serde::{Deserialize, Serialize};

use crate::api::{PlanObjective, PlanOptions, PlanStatus, RobotSpec, default_a_max, default_v_max, default_v_min};
use crate::attribute::AttributeDoc;

/// One robot of `POST /v1/missions`: its id (as in its Zenoh keys), dock and shape.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct MissionRobot {
    /// Robot id.
    pub id: String,
    /// Start and return point (the dock), metres, map frame.
    pub start: [f64; 2],
    /// Footprint radius, metres (a disc robot). 0 or absent when `footprint` is given.
    #[serde(default)]
    pub radius: f64,
    /// Footprint polygon instead of `radius` (a robot that is not a disc), as in a plan request's `robot`:
    /// `[[x, y], …]` in the robot frame, Nav2's convention, convex.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub footprint: Option<Vec<[f64; 2]>>,
    /// Tool width, metres.
    pub tool_width: f64,
    /// Slowest cover speed, m/s.
    #[serde(default = "default_v_min")]
    pub v_min: f64,
    /// Fastest speed, m/s.
    #[serde(default = "default_v_max")]
    pub v_max: f64,
    /// Largest tangential acceleration, m/s².
    #[serde(default = "default_a_max")]
    pub a_max: f64,
}

impl MissionRobot {
    /// A robot `id` at `start` with the API's default speed limits.
    pub fn new(id: impl Into<String>, start: [f64; 2], radius: f64, tool_width: f64) -> Self {
        Self {
            id: id.into(),
            start,
            radius,
            footprint: None,
            tool_width,
            v_min: default_v_min(),
            v_max: default_v_max(),
            a_max: default_a_max(),
        }
    }

    /// The radius of the disc it never leaves: its `radius`, or its footprint's farthest vertex from the
    /// origin, metres.
    pub fn outer_radius(&self) -> f64 {
        match &self.footprint {
            Some(poly) => poly.iter().map(|v| v[0].hypot(v[1])).fold(0.0, f64::max),
            None => self.radius,
        }
    }

    /// Its shape and limits as a plan request names them.
    pub fn spec(&self) -> RobotSpec {
        RobotSpec {
            radius: self.radius,
            footprint: self.footprint.clone(),
            tool_width: self.tool_width,
            v_min: self.v_min,
            v_max: self.v_max,
            a_max: self.a_max,
        }
    }
}

/// `POST /v1/missions`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct MissionRequest {
    /// Site to cover.
    pub site: String,
    /// The fleet, at least one robot, ids unique.
    pub robots: Vec<MissionRobot>,
    /// Attribute map (one for the whole fleet); uniform when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attribute: Option<AttributeDoc>,
    /// Planner choices for every part.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub options: Option<PlanOptions>,
    /// What every part's plan minimises (default `time`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objective: Option<PlanObjective>,
}

impl MissionRequest {
    /// Most robots one mission may hold.
    pub const MAX_ROBOTS: usize = 64;
}

/// Lifecycle of a mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "lowercase")]
pub enum MissionStatus {
    /// Accepted and persisted, waiting for a worker.
    Queued,
    /// Being divided and planned.
    Planning,
    /// Every part planned; not yet driven.
    Ready,
    /// Robots drive its plans.
    Active,
    /// Every plan was driven to its end.
    Done,
    /// Could not be divided or planned; `error` says why.
    Failed,
    /// Cancelled by a client.
    Cancelled,
}

impl MissionStatus {
    /// Lower-case name as on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Queued => "queued",
            Self::Planning => "planning",
            Self::Ready => "ready",
            Self::Active => "active",
            Self::Done => "done",
            Self::Failed => "failed",
            Self::Cancelled => "cancelled",
        }
    }

    /// True when nothing will change it any more.
    pub fn is_settled(self) -> bool {
        matches!(self, Self::Done | Self::Failed | Self::Cancelled)
    }
}

/// `202 Accepted` answer to `POST /v1/missions`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct MissionAccepted {
    /// The new mission's id (`m-…`).
    pub mission_id: String,
    /// Always `queued`.
    pub status: MissionStatus,
}

/// One robot's plan within a mission.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct MissionPlanView {
    /// Robot id.
    pub robot: String,
    /// Its plan (an ordinary plan: `/v1/plans/{plan_id}`).
    pub plan_id: String,
    /// The plan's status.
    pub status: PlanStatus,
    /// The plan's current version (0 until planned).
    pub version: u64,
    /// Planned duration, seconds (once planned).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planned_duration_s: Option<f64>,
    /// Coverable area of its part, m² (once divided).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area_m2: Option<f64>,
    /// Fraction of its path driven, 0–1.
    pub driven_fraction: f64,
}

/// Planned and measured coverage of a mission, percent of the coverable area of its site (the fleet's union).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct MissionCoverage {
    /// Covered by the union of the planned paths (once planned).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planned_pct: Option<f64>,
    /// Swept by the robots' tools along their odometry since the mission's plans were assigned.
    pub measured_pct: f64,
    /// Area planned by two robots or more (the seams between parts), percent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seam_pct: Option<f64>,
}

/// `GET /v1/missions/{id}` (and the `mission` event of its SSE stream).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct MissionView {
    /// Mission id.
    pub mission_id: String,
    /// Site.
    pub site: String,
    /// Lifecycle state.
    pub status: MissionStatus,
    /// Planning progress while planning, then the fraction of the planned work driven (by planned time), 0–1.
    pub progress: f64,
    /// One plan per robot, in the request's order.
    pub plans: Vec<MissionPlanView>,
    /// Planned and measured coverage.
    pub coverage: MissionCoverage,
    /// Seconds until the last robot is expected to finish (its planned time left); absent until planned.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eta_s: Option<f64>,
    /// Why it failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Remarks of division and planning.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Accepted at, milliseconds since the Unix epoch.
    pub created_ms: u64,
    /// Last change, milliseconds since the Unix epoch.
    pub updated_ms: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn issue_request_parses_with_defaults_and_refuses_unknown_fields() {
        let text = r#"{"site": "warehouse", "robots": [{"id": "r1", "start": [1, 2], "radius": 0.25,
            "tool_width": 0.5}, {"id": "r2", "start": [3, 4], "radius": 0.25, "tool_width": 0.5, "v_max": 0.8}]}"#;
        let r: MissionRequest = serde_json::from_str(text).expect("parses");
        assert_eq!(r.robots.len(), 2);
        assert_eq!(r.robots[0].spec(), RobotSpec::new(0.25, 0.5));
        assert_eq!(r.robots[1].v_max, 0.8);
        let bad = r#"{"site": "s", "robots": [{"id": "r1", "start": [1, 2], "radius": 0.2, "tool_width": 0.4,
            "speed": 1}]}"#;
        assert!(serde_json::from_str::<MissionRequest>(bad).is_err());
        assert_eq!(
            serde_json::to_string(&MissionStatus::Active).expect("ser"),
            "\"active\""
        );
    }
}
