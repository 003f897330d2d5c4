//! HTTP API bodies (DESIGN §5.3): requests, responses, server-sent events and the error body.
//!
//! Field names are the contract: tests and fleet backends script against them. Positions are metres in the
//! map frame, speeds m/s, accelerations m/s², times seconds unless a name says otherwise.

use serde::{Deserialize, Serialize};

use crate::attribute::AttributeDoc;
use crate::correction::{CorrectionDoc, CorrectionReason};
use crate::plan::PlanMetricsDoc;

/// Error body of every non-2xx answer: `{"error": {"code", "message"}}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ErrorBody {
    /// What went wrong.
    pub error: ErrorDetail,
}

/// The inside of [`ErrorBody`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ErrorDetail {
    /// Stable machine-readable code, e.g. `invalid_request`, `not_found`, `queue_full`.
    pub code: String,
    /// Human-readable explanation: what is wrong and where.
    pub message: String,
}

/// The robot a plan is for: a disc of `radius`, or a `footprint` polygon (exactly one of the two).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Footprint radius, metres (a disc robot). 0 or absent when `footprint` is given.
    #[serde(default)]
    pub radius: f64,
    /// Footprint polygon, Nav2's `footprint` convention: `[[x, y], …]` in the robot frame (x forward, y to
    /// the left, metres, origin at the centre the robot turns about), convex, either winding, implicitly
    /// closed, the origin inside. Instead of `radius`, for robots that are not discs (sweepers and floor
    /// scrubbers are rectangles): plans then keep the polygon, at the path's heading, off every occupied cell.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub footprint: Option<Vec<[f64; 2]>>,
    /// Width of the cleaning / spraying tool, metres.
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

pub(crate) fn default_v_min() -> f64 {
    0.1
}
pub(crate) fn default_v_max() -> f64 {
    1.0
}
pub(crate) fn default_a_max() -> f64 {
    0.5
}

impl RobotSpec {
    /// A robot of `radius` and `tool_width` (metres) with the API's default speed and acceleration limits.
    pub fn new(radius: f64, tool_width: f64) -> Self {
        Self {
            radius,
            footprint: None,
            tool_width,
            v_min: default_v_min(),
            v_max: default_v_max(),
            a_max: default_a_max(),
        }
    }
}

/// Planner choices; every field optional, the defaults are the best combination.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct PlanOptions {
    /// `auto` (default), `bcd`, `walls`, `voronoi`, `grid`, `none`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decomposition: Option<String>,
    /// `two-opt`, `rrt` (default), `anneal`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order: Option<String>,
    /// `lanes` (default), `spiral`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pattern: Option<String>,
    /// Seed for every random choice (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// `POST /v1/plans`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct PlanRequest {
    /// Site whose map to plan on.
    pub site: String,
    /// Start and return point (the dock), metres, map frame.
    pub start: [f64; 2],
    /// The robot.
    pub robot: RobotSpec,
    /// Attribute map; uniform when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attribute: Option<AttributeDoc>,
    /// Only cover inside this polygon (`[[x, y], …]`, metres, map frame); the whole reachable map when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<Vec<[f64; 2]>>,
    /// Planner choices.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub options: Option<PlanOptions>,
    /// What the plan minimises among those that meet the coverage bar (default `time`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objective: Option<PlanObjective>,
    /// When the start's piece of traversable space is small (under half the largest piece, typical of a
    /// start a few centimetres off on a real map), move the start into the largest piece if one of its cells
    /// is within this many metres. Absent: the start stays, and the plan's warnings say where it leads.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub snap_start_m: Option<f64>,
}

impl PlanRequest {
    /// Most vertices a `region` polygon may have (the region mask tests every cell against every edge).
    pub const MAX_REGION_VERTICES: usize = 4096;

    /// A request for `robot` on `site` from `start` with every optional field absent (the defaults).
    pub fn new(site: impl Into<String>, start: [f64; 2], robot: RobotSpec) -> Self {
        Self {
            site: site.into(),
            start,
            robot,
            attribute: None,
            region: None,
            options: None,
            objective: None,
            snap_start_m: None,
        }
    }
}

/// What a plan minimises (DESIGN §6), subject to the coverage bar.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "lowercase")]
pub enum PlanObjective {
    /// The time the plan takes to drive under the robot's speed and acceleration limits (`duration_s`).
    #[default]
    Time,
    /// Path length.
    Length,
    /// Overlap.
    Overlap,
    /// Heading changes of 30° or more.
    Turns,
}

/// Lifecycle of a plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "lowercase")]
pub enum PlanStatus {
    /// Accepted and persisted, waiting for a worker.
    Queued,
    /// A worker is computing it.
    Planning,
    /// Computed; the path is available.
    Ready,
    /// Assigned to a robot that is driving it.
    Active,
    /// The robot finished it.
    Done,
    /// Could not be computed; `error` says why.
    Failed,
    /// Cancelled by a client before it finished.
    Cancelled,
}

impl PlanStatus {
    /// True when nothing will change the plan's computation any more.
    pub fn is_final(self) -> bool {
        matches!(
            self,
            Self::Ready | Self::Active | Self::Done | Self::Failed | Self::Cancelled
        )
    }

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

    /// Every status, for exporting gauges.
    pub const ALL: [PlanStatus; 7] = [
        Self::Queued,
        Self::Planning,
        Self::Ready,
        Self::Active,
        Self::Done,
        Self::Failed,
        Self::Cancelled,
    ];
}

/// `202 Accepted` answer to `POST /v1/plans`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct PlanAccepted {
    /// The new plan's id.
    pub plan_id: String,
    /// Always `queued`.
    pub status: PlanStatus,
}

/// A region whose cover path is computed (the robot may start on it while the rest compute).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct RegionReady {
    /// Region id (as in the final plan's `regions`).
    pub region: u32,
    /// Outer contour, metres, map frame.
    pub polygon: Vec<[f64; 2]>,
    /// The region's cover path `[[x, y], …]`, metres, map frame, before it is linked into the tour.
    pub path: Vec<[f64; 2]>,
}

/// `GET /v1/plans/{id}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct PlanStatusResponse {
    /// Plan id.
    pub plan_id: String,
    /// Site it plans on.
    pub site: String,
    /// Lifecycle state.
    pub status: PlanStatus,
    /// Fraction of the computation done, 0–1.
    pub progress: f64,
    /// Current version (1 when computed; corrections increment it).
    pub version: u64,
    /// Regions whose cover paths are computed so far.
    pub regions_ready: u32,
    /// Figures of merit once ready.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<PlanMetricsDoc>,
    /// Why the plan failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Remarks from the planner (e.g. a start snapped out of an obstacle).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Robot driving it (once assigned).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<String>,
    /// Fraction of the path's length the robot has driven, 0–1 (once assigned).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub driven_fraction: Option<f64>,
    /// Stretches of the path that corrections had to leave out (blocked), each `[[x, y], …]`, metres, map
    /// frame: their cells are missed until a later revisit.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub missed: Vec<Vec<[f64; 2]>>,
    /// Corrections applied so far (the version minus one once computed).
    #[serde(default)]
    pub corrections: u64,
    /// While a robot drives it: whether its path is watched against fresh obstacle points (`watching`) or the
    /// site's live map got no points for `zenoh.robot_timeout_s` while the robot is alive (`blind`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub watch: Option<WatchHealth>,
    /// Where progress was found elsewhere on the path than where the robot was expected (it joined late, was
    /// carried, relocalised, or went back), the latest last.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub progress_jumps: Vec<ProgressJump>,
    /// The mission it is a part of (`/v1/missions/{id}`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mission: Option<String>,
    /// When the request was accepted, milliseconds since the Unix epoch.
    pub created_ms: u64,
    /// Last status change, milliseconds since the Unix epoch.
    pub updated_ms: u64,
}

/// Whether an assigned plan's path is watched against fresh obstacle points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "lowercase")]
pub enum WatchHealth {
    /// Points reach the site's live map.
    Watching,
    /// No points reached the site's live map for `zenoh.robot_timeout_s` while the robot is alive: new
    /// obstacles on its path cannot be seen.
    Blind,
    /// The path is blocked up to its end, so the only correction would end the plan where the robot is; it is
    /// held for `watch.end_hold_s` in case the blockage moves on (a person, a cart). The robot should wait
    /// before the blockage; the plan goes on (`watching`) when it clears, or ends when the hold runs out.
    Blocked,
}

/// Progress found away from where the robot was expected along its plan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ProgressJump {
    /// Metres along the path before.
    pub from_m: f64,
    /// Metres along the path after.
    pub to_m: f64,
    /// The robot went back over driven ground.
    pub backwards: bool,
    /// When, milliseconds since the Unix epoch.
    pub at_ms: u64,
}

/// `POST /v1/plans/{id}/assign`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct AssignRequest {
    /// Robot id (as in its Zenoh keys).
    pub robot: String,
}

/// A robot's last pose, map frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct PoseView {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians, counter-clockwise from +x.
    pub yaw: f64,
    /// Stamp of the odometry it came from, nanoseconds (robot clock).
    pub stamp_ns: i64,
}

/// `GET /v1/robots/{id}` (and the items of `GET /v1/robots`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct RobotView {
    /// Robot id.
    pub robot: String,
    /// Its liveliness token is present (false = lost).
    pub alive: bool,
    /// Last message or liveliness change, milliseconds since the Unix epoch.
    pub last_seen_ms: u64,
    /// Last pose.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<PoseView>,
    /// Plan it drives.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plan_id: Option<String>,
    /// Fraction of that plan's length driven, 0–1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub driven_fraction: Option<f64>,
    /// Metres of that plan driven.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub driven_m: Option<f64>,
    /// The last correction sent to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_correction: Option<LastCorrection>,
    /// The site its clouds and scans feed: the site of the plan it drives, else the default site of unassigned
    /// robots (`zenoh.site`); absent when its points go nowhere.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub site: Option<String>,
    /// What became of its sensor data (filled by the daemon's ingest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensors: Option<RobotSensorsView>,
}

/// A robot's sensor data as the daemon's ingest saw it.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct RobotSensorsView {
    /// Clouds and scans placed in a site's live map.
    pub placed: u64,
    /// Points in them.
    pub points: u64,
    /// Messages waiting for the odometry that places them.
    pub waiting: usize,
    /// Messages dropped, by reason (`unrouted`, `malformed`, `no_pose`, `too_old`, `future`, `wait_full`,
    /// `queue_full`, `no_map`; `frame` for odometry in a frame the daemon cannot place).
    pub dropped: std::collections::BTreeMap<String, u64>,
    /// Why the last one was dropped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_drop: Option<String>,
}

/// The last correction a robot received (`GET /v1/robots/{id}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct LastCorrection {
    /// Plan id.
    pub plan_id: String,
    /// Plan version it produced.
    pub version: u64,
    /// Why.
    pub reason: CorrectionReason,
    /// When it was sent, milliseconds since the Unix epoch.
    pub at_ms: u64,
    /// Server-side check time, microseconds.
    pub compute_us: u64,
}

/// One point of `GET /v1/plans/{id}/speed-profile`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SpeedSample {
    /// Arc length from the start, metres.
    pub s: f64,
    /// Speed, m/s.
    pub v: f64,
    /// Time from the start, seconds.
    pub t: f64,
}

/// `GET /v1/plans/{id}/speed-profile`: one sample per waypoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SpeedProfileResponse {
    /// Plan id.
    pub plan_id: String,
    /// Version the samples belong to.
    pub version: u64,
    /// Per waypoint: arc length, speed, time.
    pub samples: Vec<SpeedSample>,
}

/// `GET /v1/sites/{site}` and the 201 answer to a map upload.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SiteSummary {
    /// Site name.
    pub site: String,
    /// Columns.
    pub width: u64,
    /// Rows.
    pub height: u64,
    /// Metres per cell.
    pub resolution: f64,
    /// Map-frame position of cell (0, 0)'s outer corner, metres.
    pub origin: [f64; 2],
    /// Free cells.
    pub free_cells: u64,
    /// Points in the live ikd-tree (0 until robots stream clouds).
    pub points_in_tree: u64,
    /// Clouds ingested per second over the last 10 s.
    #[serde(default)]
    pub updates_per_s: f64,
    /// Clouds dropped (queue overflow, malformed payloads, no pose to transform with).
    #[serde(default)]
    pub dropped_clouds: u64,
    /// Last map change, milliseconds since the Unix epoch.
    pub updated_ms: u64,
    /// Remarks from reading the map.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// For a site uploaded as a field: its map frame as a PROJ string (a transverse Mercator on WGS84 centred on
    /// `origin_wgs84`, metres).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crs: Option<String>,
    /// For a site uploaded as a field: the map frame's (0, 0), `[lon, lat]` degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin_wgs84: Option<[f64; 2]>,
}

/// Server-sent event of `GET /v1/plans/{id}/events`; the SSE `event:` name is [`PlanEvent::name`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(tag = "type", rename_all = "kebab-case")]
// The status variant is the large one and also the common one (every change, the first event on connect);
// boxing it would allocate per event and change a public wire type that clients match on.
#[allow(clippy::large_enum_variant)]
pub enum PlanEvent {
    /// The plan's status changed (also sent first, on connect).
    Status(PlanStatusResponse),
    /// Computation advanced.
    Progress {
        /// Plan id.
        plan_id: String,
        /// 0–1.
        progress: f64,
    },
    /// A region's cover path is ready.
    RegionReady {
        /// Plan id.
        plan_id: String,
        /// The region.
        region: RegionReady,
    },
    /// A correction replaced a stretch of the plan (the robot got it on its corrections key).
    Correction(CorrectionDoc),
}

impl PlanEvent {
    /// The plan this event is about.
    pub fn plan_id(&self) -> &str {
        match self {
            Self::Status(s) => &s.plan_id,
            Self::Progress { plan_id, .. } | Self::RegionReady { plan_id, .. } => plan_id,
            Self::Correction(c) => &c.plan_id,
        }
    }

    /// SSE event name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Status(_) => "status",
            Self::Progress { .. } => "progress",
            Self::RegionReady { .. } => "region-ready",
            Self::Correction(_) => "correction",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn design_plan_request_parses_with_defaults() {
        let text = r#"{"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}}"#;
        let r: PlanRequest = serde_json::from_str(text).expect("parses");
        assert_eq!(r.robot.v_min, 0.1);
        assert_eq!(r.robot.v_max, 1.0);
        assert_eq!(r.robot.a_max, 0.5);
        assert!(r.options.is_none());
        let full = r#"{"site": "demo", "start": [1, 2], "robot": {"radius": 0.15, "tool_width": 0.3,
            "v_min": 0.2, "v_max": 0.8, "a_max": 0.4}, "attribute": {"blobs": [{"x": 1, "y": 1, "sigma": 0.5,
            "amplitude": 0.9}]}, "region": [[0,0],[4,0],[4,4]], "options": {"decomposition": "bcd",
            "order": "rrt", "pattern": "lanes", "seed": 7}}"#;
        let r: PlanRequest = serde_json::from_str(full).expect("parses");
        assert_eq!(r.options.as_ref().and_then(|o| o.seed), Some(7));
        assert_eq!(r.attribute.as_ref().map(|a| a.blobs.len()), Some(1));
    }

    #[test]
    fn a_footprint_alone_describes_the_robot() {
        let text = r#"{"site": "s", "start": [1, 1], "robot": {"tool_width": 0.8,
            "footprint": [[0.6, 0.4], [-0.6, 0.4], [-0.6, -0.4], [0.6, -0.4]]}}"#;
        let r: PlanRequest = serde_json::from_str(text).expect("parses");
        assert_eq!(r.robot.radius, 0.0);
        assert_eq!(r.robot.footprint.as_ref().map(Vec::len), Some(4));
        let back: PlanRequest = serde_json::from_value(serde_json::to_value(&r).expect("ser")).expect("de");
        assert_eq!(back, r);
        // A disc robot's request does not name a footprint on the wire.
        let disc = serde_json::to_value(RobotSpec::new(0.15, 0.3)).expect("ser");
        assert!(disc.get("footprint").is_none() && disc["radius"] == 0.15);
    }

    #[test]
    fn unknown_fields_are_rejected() {
        let text = r#"{"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}, "x": 1}"#;
        assert!(serde_json::from_str::<PlanRequest>(text).is_err());
    }

    #[test]
    fn events_are_tagged() {
        let e = PlanEvent::Progress {
            plan_id: "p-1".into(),
            progress: 0.5,
        };
        let v = serde_json::to_value(&e).expect("ser");
        assert_eq!(v["type"], "progress");
        assert_eq!(e.name(), "progress");
        assert_eq!(
            serde_json::to_string(&PlanStatus::Cancelled).expect("ser"),
            "\"cancelled\""
        );
    }
}
