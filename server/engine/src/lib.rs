//! # shift-engine
//!
//! The fleet brain, sans-IO: sites (their maps), plans (status, progress, versions, results) and the plan job
//! queue. [`Engine::handle`] takes an [`Event`] and the current time and returns the [`Command`]s the daemon
//! must carry out, in order (persist first, then start jobs, then publish). Plan computation is requested as
//! [`Command::StartJob`] and its result comes back as [`Event::JobFinished`], so a test or a recording can drive
//! the engine deterministically. No tokio, no sockets, no clock.

mod engine;
pub mod error;
pub mod job;
pub mod live_map;
pub mod plan;
pub mod pose_history;
pub mod recorded;
pub mod request;
pub mod robots;
pub mod site;
pub mod watch;

pub use engine::{Command, Engine, EngineConfig, Event, JobOutcome};
pub use error::EngineError;
pub use job::{JobResult, PlanJob, attribute_map, run_job};
pub use live_map::{LiveMap, LiveMapParams, LiveMapStats};
pub use plan::PlanRecord;
pub use pose_history::{PoseHistory, PoseHistoryParams, PoseLookupError};
pub use robots::Pose2;
pub use site::{MapSource, SiteMap, SiteRecord};
pub use watch::{CheckJob, CheckOutcome, ProposedCorrection, WatchParams, run_check};
