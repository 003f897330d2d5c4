//! What the engine takes in ([`Event`]) and what it asks the daemon to do ([`Command`]).

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use shift_proto::{
    CorrectionDoc, MissionRequest, MissionView, PlanDocument, PlanEvent, PlanRequest, RegionReady, RobotView,
    SiteSummary,
};

use crate::coverage::CoverageRecord;
use crate::job::PlanJob;
use crate::mission::MissionRecord;
use crate::mission_job::{MissionJob, MissionOutcome};
use crate::plan::PlanRecord;
use crate::robots::Pose2;
use crate::site::{LoadedSite, SiteRecord};
use crate::watch::{CheckJob, CheckOutcome};

/// How a job ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum JobOutcome {
    /// Computed.
    Planned {
        /// The plan document (version 1).
        doc: Arc<PlanDocument>,
        /// Planner remarks.
        warnings: Vec<String>,
    },
    /// The planner refused or failed.
    Failed {
        /// Why.
        reason: String,
    },
    /// Stopped because the plan was cancelled.
    Cancelled,
    /// Stopped because the daemon is shutting down; the plan goes back to the queue for the next start.
    Interrupted,
}

/// Something that happened. Serialisable as recordings keep it (`{"type": "…", …}`; maps as their records,
/// parsed again when read; non-finite numbers as strings), so a recording replays through the engine.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Event {
    /// State read back from the store at start-up; in-flight plans are re-queued or failed, and robots get
    /// back the plans they were driving.
    Restore {
        /// Sites with their parsed maps.
        sites: Vec<LoadedSite>,
        /// Every plan record.
        plans: Vec<PlanRecord>,
        /// The current documents (corrections applied) of the plans that were being driven.
        #[serde(default)]
        active: Vec<Arc<PlanDocument>>,
        /// Every mission record.
        #[serde(default)]
        missions: Vec<MissionRecord>,
        /// The measured coverage rasters.
        #[serde(default)]
        coverage: Vec<CoverageRecord>,
    },
    /// A map was uploaded (already parsed off the async workers).
    MapUploaded {
        /// What to persist, with its parsed map.
        #[serde(rename = "record")]
        site: LoadedSite,
    },
    /// A client asks for a plan.
    PlanRequested {
        /// The request.
        request: PlanRequest,
    },
    /// A client cancels a plan.
    CancelRequested {
        /// Plan id.
        plan_id: String,
    },
    /// A worker reports progress (0–1).
    JobProgress {
        /// Plan id.
        plan_id: String,
        /// Fraction done.
        #[serde(with = "crate::lossless_f64")]
        progress: f64,
    },
    /// A worker linked one region of the plan it computes (in visiting order, before the job finishes).
    JobRegionReady {
        /// Plan id.
        plan_id: String,
        /// The region and its cover path.
        region: RegionReady,
    },
    /// A worker finished.
    JobFinished {
        /// Plan id.
        plan_id: String,
        /// How.
        outcome: JobOutcome,
    },
    /// A robot's liveliness token appeared (`alive`) or disappeared.
    RobotLiveliness {
        /// Robot id.
        robot: String,
        /// Token present.
        alive: bool,
    },
    /// A robot's odometry, map frame.
    RobotPose {
        /// Robot id.
        robot: String,
        /// Its pose.
        pose: Pose2,
    },
    /// A client assigns a ready plan to a robot (the daemon attaches the current document).
    AssignPlan {
        /// Plan id.
        plan_id: String,
        /// Robot id.
        robot: String,
        /// The plan's current document.
        doc: Arc<PlanDocument>,
    },
    /// New obstacle points landed in a site's live map inside the box `[min, max]` (map frame, metres).
    MapChanged {
        /// Site.
        site: String,
        /// Lower corner (x, y).
        min: [f64; 2],
        /// Upper corner (x, y).
        max: [f64; 2],
    },
    /// Robots' points reached a site's live map (the daemon says so at most about once a second per site).
    SiteFed {
        /// Site.
        site: String,
    },
    /// A path check ended.
    CheckFinished {
        /// Robot checked.
        robot: String,
        /// Plan it drove when the check started.
        plan_id: String,
        /// Version checked.
        base_version: u64,
        /// What the check found (as computed live, so a replay needs no live map).
        outcome: CheckOutcome,
        /// Time the check took, microseconds (measured by the daemon).
        compute_us: u64,
    },
    /// A client asks for a mission.
    MissionRequested {
        /// The request.
        request: MissionRequest,
    },
    /// A client cancels a mission (its plans not yet driven are cancelled; robots keep driving theirs).
    MissionCancelRequested {
        /// Mission id.
        mission_id: String,
    },
    /// A client assigns every plan of a planned mission to its robot (the daemon attaches the current
    /// documents, in the mission's plan order).
    MissionAssignRequested {
        /// Mission id.
        mission_id: String,
        /// Each plan's current document.
        docs: Vec<Arc<PlanDocument>>,
    },
    /// A client asks to replan what a mission has left (`POST /v1/missions/{id}/replan`).
    MissionReplanRequested {
        /// Mission id.
        mission_id: String,
    },
    /// A robot joins a mission (`POST /v1/missions/{id}/robots`).
    MissionRobotJoined {
        /// Mission id.
        mission_id: String,
        /// The robot.
        robot: shift_proto::MissionRobot,
    },
    /// A mission job ended.
    MissionFinished {
        /// Mission id.
        mission_id: String,
        /// How.
        outcome: MissionOutcome,
    },
    /// The daemon is stopping: start no more jobs, refuse new plans, commit the measured coverage.
    Shutdown,
}

impl Event {
    /// The event's name, for metrics and logs.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Restore { .. } => "restore",
            Self::MapUploaded { .. } => "map_uploaded",
            Self::PlanRequested { .. } => "plan_requested",
            Self::CancelRequested { .. } => "cancel_requested",
            Self::JobProgress { .. } => "job_progress",
            Self::JobRegionReady { .. } => "job_region_ready",
            Self::JobFinished { .. } => "job_finished",
            Self::RobotLiveliness { .. } => "robot_liveliness",
            Self::RobotPose { .. } => "robot_pose",
            Self::AssignPlan { .. } => "assign_plan",
            Self::MapChanged { .. } => "map_changed",
            Self::SiteFed { .. } => "site_fed",
            Self::CheckFinished { .. } => "check_finished",
            Self::MissionRequested { .. } => "mission_requested",
            Self::MissionCancelRequested { .. } => "mission_cancel_requested",
            Self::MissionAssignRequested { .. } => "mission_assign_requested",
            Self::MissionFinished { .. } => "mission_finished",
            Self::MissionReplanRequested { .. } => "mission_replan_requested",
            Self::MissionRobotJoined { .. } => "mission_robot_joined",
            Self::Shutdown => "shutdown",
        }
    }

    /// A client's request (an HTTP call waits for its answer): when the store cannot commit what it decided,
    /// the request is undone and refused. Everything else is a fact the fleet already lived through; what it
    /// decided stands, and its durable part waits for the store.
    pub fn is_request(&self) -> bool {
        matches!(
            self,
            Self::MapUploaded { .. }
                | Self::PlanRequested { .. }
                | Self::CancelRequested { .. }
                | Self::AssignPlan { .. }
                | Self::MissionRequested { .. }
                | Self::MissionCancelRequested { .. }
                | Self::MissionAssignRequested { .. }
                | Self::MissionReplanRequested { .. }
                | Self::MissionRobotJoined { .. }
        )
    }
}

/// Something the daemon must do, in the order given.
#[derive(Debug, Clone)]
pub enum Command {
    /// Persist a site (before acknowledging the upload).
    StoreSite(SiteRecord),
    /// The read model's site summary changed.
    SiteChanged(SiteSummary),
    /// A site's static map is (now) this one: its clearance field tells the live map which points are known
    /// obstacles seen again.
    SiteStatic {
        /// Site.
        site: String,
        /// Distance to the static map's non-free cells, metres.
        clearance: Arc<shift_planner::map::DistanceField>,
        /// The thresholded map itself (what `GET /v1/sites/{site}/map` answers).
        grid: Arc<shift_planner::map::OccupancyGrid>,
        /// A terrain site's ground: the live map measures the obstacle height band over it.
        ground: Option<Arc<shift_planner::terrain::TerrainSurface>>,
    },
    /// Persist a plan record (a status change) and update the read model.
    StorePlan(PlanRecord),
    /// Update the read model only (progress, not worth a disk write).
    UpdatePlan(PlanRecord),
    /// Persist a computed plan document.
    StoreResult {
        /// Plan id.
        plan_id: String,
        /// The document.
        doc: Arc<PlanDocument>,
    },
    /// Run this job on the worker pool.
    StartJob(PlanJob),
    /// Run this mission job on the worker pool; answer with [`Event::MissionFinished`].
    StartMission(Box<MissionJob>),
    /// Persist a plan's new document (a replan: the whole path replaced at the next version) with its record, the
    /// corrections of earlier versions dropped (the document is now the base), and show both; the plan's
    /// subscribers and its robot hear of it by the commands that follow.
    ReplacePlanDoc {
        /// The plan's record at the new version.
        record: PlanRecord,
        /// The document.
        doc: Arc<PlanDocument>,
    },
    /// Persist a mission record (before acknowledging a request about it).
    StoreMission(MissionRecord),
    /// The read model's mission view changed (also sent to the mission's event subscribers).
    MissionChanged(MissionView),
    /// Persist a measured coverage raster (at intervals while robots sweep, and when the daemon stops).
    StoreCoverage(Arc<CoverageRecord>),
    /// The read model's copy of a site's measured coverage raster (at most about once a second).
    CoverageChanged(Arc<CoverageRecord>),
    /// Raise the cancel flag of a running job.
    CancelJob {
        /// Plan id.
        plan_id: String,
    },
    /// Send to event subscribers.
    Publish(PlanEvent),
    /// Deliver a plan to a robot (its plan key, the ROS Path key; the queryable serves it from now on).
    PublishPlan {
        /// Robot id.
        robot: String,
        /// The plan.
        doc: Arc<PlanDocument>,
    },
    /// The read model's robot view changed.
    RobotChanged(RobotView),
    /// Forget a settled plan beyond `retain_plans`: its record, document, corrections and history, in the store
    /// and the read model.
    ForgetPlan {
        /// Plan id.
        plan_id: String,
    },
    /// Check this robot's path (off the engine thread, with the site's live map); answer with
    /// [`Event::CheckFinished`].
    StartCheck(Box<CheckJob>),
    /// Persist a correction together with the plan record it bumps (one transaction), then show `doc` (the
    /// corrected current version) in the read model.
    StoreCorrection {
        /// The plan's record at the new version.
        record: PlanRecord,
        /// The correction.
        correction: Arc<CorrectionDoc>,
        /// The current document after it.
        doc: Arc<PlanDocument>,
    },
    /// Send a correction to its robot (its corrections key; the plan queryable serves the new version).
    PublishCorrection(Arc<CorrectionDoc>),
    /// From now on `robot`'s clouds and scans feed `site` (the site of the plan it drives), or the default site
    /// of unassigned robots with `None`.
    FeedSite {
        /// Robot id.
        robot: String,
        /// Its plan's site.
        site: Option<String>,
    },
}
