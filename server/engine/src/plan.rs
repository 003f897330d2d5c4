//! The record the engine keeps (and the store persists) per plan.

use serde::{Deserialize, Serialize};
use shift_proto::{PlanMetricsDoc, PlanRequest, PlanStatus, PlanStatusResponse, ProgressJump, WatchHealth};

/// Progress jumps a record keeps.
pub const MAX_JUMPS: usize = 16;

/// One plan's state. Every status change is persisted as a whole record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanRecord {
    /// Plan id (`p-…`).
    pub plan_id: String,
    /// Acceptance order; ids and queue order come from it.
    pub seq: u64,
    /// The request as accepted.
    pub request: PlanRequest,
    /// Lifecycle state.
    pub status: PlanStatus,
    /// Fraction computed, 0–1.
    pub progress: f64,
    /// Current version (0 until computed, 1 when ready, +1 per correction).
    pub version: u64,
    /// Regions whose cover paths are ready.
    pub regions_ready: u32,
    /// Figures of merit once ready.
    pub metrics: Option<PlanMetricsDoc>,
    /// Why it failed.
    pub error: Option<String>,
    /// Planner remarks and lifecycle notes (e.g. "re-queued after a restart").
    pub warnings: Vec<String>,
    /// Robot it is assigned to.
    #[serde(default)]
    pub robot: Option<String>,
    /// Fraction of its length that robot has driven, 0–1.
    #[serde(default)]
    pub driven_fraction: f64,
    /// Stretches corrections left out (blocked), each `[[x, y], …]`, metres, map frame.
    #[serde(default)]
    pub missed: Vec<Vec<[f64; 2]>>,
    /// Whether its path is watched against fresh points while a robot drives it.
    #[serde(default)]
    pub watch: Option<WatchHealth>,
    /// Progress found away from where the robot was expected, the latest [`MAX_JUMPS`] kept.
    #[serde(default)]
    pub progress_jumps: Vec<ProgressJump>,
    /// The mission it is a part of (its robot's share of the mission's site).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mission: Option<String>,
    /// How many times a worker started it.
    pub attempts: u32,
    /// Accepted at, milliseconds since the Unix epoch.
    pub created_ms: u64,
    /// Last change, milliseconds since the Unix epoch.
    pub updated_ms: u64,
}

impl PlanRecord {
    /// A plan just accepted: queued, nothing computed.
    pub fn queued(plan_id: String, seq: u64, request: PlanRequest, now_ms: u64) -> Self {
        Self {
            plan_id,
            seq,
            request,
            status: PlanStatus::Queued,
            progress: 0.0,
            version: 0,
            regions_ready: 0,
            metrics: None,
            error: None,
            warnings: Vec::new(),
            robot: None,
            driven_fraction: 0.0,
            missed: Vec::new(),
            watch: None,
            progress_jumps: Vec::new(),
            mission: None,
            attempts: 0,
            created_ms: now_ms,
            updated_ms: now_ms,
        }
    }

    /// The `GET /v1/plans/{id}` body.
    pub fn to_response(&self) -> PlanStatusResponse {
        PlanStatusResponse {
            plan_id: self.plan_id.clone(),
            site: self.request.site.clone(),
            status: self.status,
            progress: self.progress,
            version: self.version,
            regions_ready: self.regions_ready,
            metrics: self.metrics,
            error: self.error.clone(),
            warnings: self.warnings.clone(),
            robot: self.robot.clone(),
            driven_fraction: self.robot.as_ref().map(|_| self.driven_fraction),
            missed: self.missed.clone(),
            corrections: self.version.saturating_sub(1),
            watch: self.watch,
            progress_jumps: self.progress_jumps.clone(),
            mission: self.mission.clone(),
            created_ms: self.created_ms,
            updated_ms: self.updated_ms,
        }
    }
}
