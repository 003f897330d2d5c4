//! The engine's error type: every way an event can be refused. The daemon maps each variant to one HTTP status.

use shift_proto::{MissionStatus, PlanStatus};
use thiserror::Error;

/// Why the engine refused an event.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EngineError {
    /// The request is malformed or out of range (HTTP 400).
    #[error("{0}")]
    InvalidRequest(String),
    /// The map could not be read (HTTP 400).
    #[error("map: {0}")]
    Map(#[from] shift_planner::PlannerError),
    /// No site of that name (HTTP 404).
    #[error("unknown site {0:?}")]
    UnknownSite(String),
    /// No plan of that id (HTTP 404).
    #[error("unknown plan {0:?}")]
    UnknownPlan(String),
    /// The action does not apply to the plan's current status (HTTP 409).
    #[error("plan {plan_id} is {status}; cannot {action}", status = .status.as_str())]
    InvalidState {
        /// The plan.
        plan_id: String,
        /// Its status.
        status: PlanStatus,
        /// What was asked.
        action: &'static str,
    },
    /// No mission of that id (HTTP 404).
    #[error("unknown mission {0:?}")]
    UnknownMission(String),
    /// The action does not apply to the mission's current status (HTTP 409).
    #[error("mission {mission_id} is {status}; cannot {action}", status = .status.as_str())]
    MissionState {
        /// The mission.
        mission_id: String,
        /// Its status.
        status: MissionStatus,
        /// What was asked.
        action: &'static str,
    },
    /// The job queue is full (HTTP 429).
    #[error("the plan queue is full ({capacity} jobs waiting); retry later")]
    QueueFull {
        /// Configured capacity.
        capacity: usize,
    },
    /// The engine is shutting down and takes no new jobs (HTTP 503).
    #[error("shutting down")]
    ShuttingDown,
}

/// Result alias of this crate.
pub type Result<T, E = EngineError> = std::result::Result<T, E>;
