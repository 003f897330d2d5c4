//! # shift-engine
//!
//! The fleet brain, sans-IO. It owns what the fleet decides: sites (their maps and live obstacle maps), plans
//! (status, progress, versions, results) and the plan job queue, robots (presence, the plan each drives, how far
//! along, which site its sensor data feeds), the sensor pipeline (frames, stamps, pose interpolation, scan →
//! points, waiting for a pose: [`sensors`]), path watching and corrections, and the planner → wire conversion
//! ([`plan_doc`]).
//!
//! [`Engine::handle`] takes an [`Event`] and the current time and returns the [`Command`]s the daemon must carry
//! out, in order (persist first, then start jobs, then publish). Plan computation is requested as
//! [`Command::StartJob`] and its result comes back as [`Event::JobFinished`], so a test or a recording can drive
//! the engine deterministically. [`sensors::SensorHub`] is driven by the daemon's ingest thread the same way
//! (messages and the time in, placed points and drops out). No tokio, no sockets, no clock: time is passed in.

pub(crate) mod bytes_as_hex;
pub mod cell_mask;
pub mod coverage;
mod engine;
pub mod error;
pub mod field;
pub mod job;
pub mod live_map;
pub mod live_maps;
pub(crate) mod lossless_f64;
pub mod mission;
pub mod mission_job;
pub mod plan;
pub mod plan_doc;
pub mod pose_history;
pub mod progress;
pub mod recorded;
pub mod request;
pub mod robots;
pub mod sensors;
pub mod site;
pub mod terrain_plan;
pub mod terrain_site;
pub mod watch;

pub use coverage::{CoverageKey, CoverageRecord};
pub use engine::{Command, Engine, EngineConfig, Event, JobOutcome};
pub use error::EngineError;
pub use job::{JobResult, PlanJob, attribute_map, run_job};
pub use live_map::{LiveMap, LiveMapParams, LiveMapStats};
pub use live_maps::{LiveMaps, SiteLive};
pub use mission::MissionRecord;
pub use mission_job::{MissionJob, MissionOutcome, planned_outcome, run_mission_job, run_mission_job_monitored};
pub use plan::PlanRecord;
pub use plan_doc::to_document;
pub use pose_history::{PoseHistory, PoseHistoryParams, PoseLookupError};
pub use progress::{Advance, Assignment, ProgressParams};
pub use robots::Pose2;
pub use site::{LoadedSite, MapSource, SiteMap, SiteRecord};
pub use watch::{CheckJob, CheckOutcome, ProposedCorrection, WatchParams, run_check};
