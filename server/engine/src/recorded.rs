//! The engine's inputs and decisions as they are recorded (MCAP JSON channels) and replayed.
//!
//! Inputs are the [`Event`]s themselves (their serde form: maps travel as their [`crate::SiteRecord`], re-parsed
//! on replay with the same code the daemon uses; non-finite numbers as strings). [`Decision`] summarises a
//! [`Command`] to something comparable across runs (no store handles, no job payloads). A new `Command` variant
//! needs one arm here; the match is exhaustive on purpose, so the compiler points at it.
//!
//! Format versions ([`FORMAT`], in [`RecordedEngineConfig::format`]): 1 (before routing by assignment) lacks
//! the robots' feed site, sensor counts, plan status fields `corrections`, `watch`, `progress_jumps` and
//! `feed_site` decisions; [`Decision::as_format`] strips those from a replay's decisions so a format-1
//! recording is checked against what it could record.
//!
//! Replaying [`RecordedInput`]s in `seq` order through a fresh [`Engine`](crate::Engine) with the recorded
//! `now_ms` and [`EngineConfig`](crate::EngineConfig) gives the recorded [`RecordedDecisions`] again: the engine
//! is deterministic in its inputs.

use serde::{Deserialize, Serialize};
use shift_proto::{PlanEvent, PlanStatusResponse, RobotView, SiteSummary};

use crate::engine::{Command, Event};
use crate::error::Result;

/// The recording format this engine writes.
pub const FORMAT: u32 = 2;

/// One event the engine handled, with the time it was handled at.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RecordedInput {
    /// Identifies one daemon run (its start, milliseconds since the Unix epoch); `seq` restarts per run.
    pub run: u64,
    /// Handling order within the run, from 1.
    pub seq: u64,
    /// The `now_ms` passed to [`Engine::handle`](crate::Engine::handle), milliseconds since the Unix epoch.
    pub now_ms: u64,
    /// The event.
    pub event: Event,
}

/// What the engine decided for the input of the same `run` and `seq`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordedDecisions {
    /// Daemon run, as in [`RecordedInput::run`].
    pub run: u64,
    /// The input's `seq`.
    pub seq: u64,
    /// The input's `now_ms`.
    pub now_ms: u64,
    /// The commands, summarised, in order; a refused event gives one [`Decision::Refused`].
    pub decisions: Vec<Decision>,
}

/// The engine's sizes, recorded at the start of every file so a replay builds the same engine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordedEngineConfig {
    /// Daemon run.
    pub run: u64,
    /// [`EngineConfig::workers`](crate::EngineConfig::workers).
    pub workers: usize,
    /// [`EngineConfig::queue_capacity`](crate::EngineConfig::queue_capacity).
    pub queue_capacity: usize,
    /// [`EngineConfig::watch`](crate::EngineConfig::watch).
    #[serde(default)]
    pub watch: crate::watch::WatchParams,
    /// [`EngineConfig::default_site`](crate::EngineConfig::default_site).
    #[serde(default)]
    pub default_site: Option<String>,
    /// [`EngineConfig::blind_after_ms`](crate::EngineConfig::blind_after_ms) (absent: the default).
    #[serde(default)]
    pub blind_after_ms: Option<u64>,
    /// [`EngineConfig::retain_plans`](crate::EngineConfig::retain_plans) (absent: every plan kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retain_plans: Option<usize>,
    /// [`EngineConfig::coverage_commit_ms`](crate::EngineConfig::coverage_commit_ms) (absent: the default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage_commit_ms: Option<u64>,
    /// Recording format ([`FORMAT`]; absent in format 1).
    #[serde(default = "format_one")]
    pub format: u32,
}

fn format_one() -> u32 {
    1
}

impl RecordedEngineConfig {
    /// The configuration of the engine that made the recording.
    pub fn engine_config(&self) -> crate::EngineConfig {
        let defaults = crate::EngineConfig::default();
        crate::EngineConfig {
            workers: self.workers,
            queue_capacity: self.queue_capacity,
            watch: self.watch,
            default_site: self.default_site.clone(),
            blind_after_ms: self.blind_after_ms.unwrap_or(defaults.blind_after_ms),
            progress: defaults.progress,
            retain_plans: self.retain_plans.unwrap_or(defaults.retain_plans),
            coverage_commit_ms: self.coverage_commit_ms.unwrap_or(defaults.coverage_commit_ms),
        }
    }

    /// What a recording of `config` made by run `run` starts with.
    pub fn of(run: u64, config: &crate::EngineConfig) -> Self {
        Self {
            run,
            workers: config.workers,
            queue_capacity: config.queue_capacity,
            watch: config.watch,
            default_site: config.default_site.clone(),
            blind_after_ms: Some(config.blind_after_ms),
            retain_plans: (config.retain_plans != usize::MAX).then_some(config.retain_plans),
            coverage_commit_ms: Some(config.coverage_commit_ms),
            format: FORMAT,
        }
    }
}

/// One [`Command`], summarised: what an operator or a test compares between a run and its replay.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Decision {
    /// The event was refused; nothing changed.
    Refused {
        /// The engine's error message.
        error: String,
    },
    /// A client's request ([`Event::is_request`](crate::Event::is_request)) whose decisions the store could not
    /// commit: the engine was put back as it was before the request, and the request refused. A replay does
    /// the same (handles it on a snapshot and puts the snapshot back).
    Undone {
        /// Why the store refused.
        error: String,
    },
    /// [`Command::StoreSite`]: a site is persisted.
    StoreSite {
        /// Site name.
        site: String,
    },
    /// [`Command::SiteChanged`].
    SiteChanged {
        /// The new summary.
        summary: SiteSummary,
    },
    /// [`Command::StorePlan`]: a plan's status changed (persisted).
    PlanStatus {
        /// The plan's status.
        status: PlanStatusResponse,
    },
    /// [`Command::UpdatePlan`]: progress or driven fraction (read model only).
    PlanUpdate {
        /// The plan's status.
        status: PlanStatusResponse,
    },
    /// [`Command::StoreResult`]: a computed document is persisted.
    PlanResult {
        /// Plan id.
        plan_id: String,
        /// Document version.
        version: u64,
        /// Waypoints in it.
        waypoints: usize,
    },
    /// [`Command::StartJob`].
    StartJob {
        /// Plan id.
        plan_id: String,
    },
    /// [`Command::CancelJob`].
    CancelJob {
        /// Plan id.
        plan_id: String,
    },
    /// [`Command::Publish`]: an event to SSE subscribers.
    Publish {
        /// The event.
        event: PlanEvent,
    },
    /// [`Command::PublishPlan`]: a plan delivered to a robot.
    DeliverPlan {
        /// Robot id.
        robot: String,
        /// Plan id.
        plan_id: String,
        /// Document version.
        version: u64,
        /// Waypoints in it.
        waypoints: usize,
    },
    /// [`Command::RobotChanged`].
    Robot {
        /// The robot's view.
        view: RobotView,
    },
    /// [`Command::SiteStatic`]: the live map learns the site's static map.
    SiteStatic {
        /// Site name.
        site: String,
    },
    /// [`Command::StartCheck`]: a robot's path is checked.
    StartCheck {
        /// Robot.
        robot: String,
        /// Plan.
        plan_id: String,
        /// Version checked.
        version: u64,
        /// Why.
        trigger: crate::watch::Trigger,
    },
    /// [`Command::StoreCorrection`]: a correction is persisted.
    StoreCorrection {
        /// The correction.
        correction: shift_proto::CorrectionDoc,
    },
    /// [`Command::PublishCorrection`]: a correction is sent to its robot.
    DeliverCorrection {
        /// Robot.
        robot: String,
        /// Plan.
        plan_id: String,
        /// Version it produces.
        version: u64,
    },
    /// [`Command::ForgetPlan`]: a settled plan beyond `retain_plans` is forgotten.
    ForgetPlan {
        /// Plan.
        plan_id: String,
    },
    /// [`Command::ReplacePlanDoc`]: a replan's document replaces a plan's.
    ReplacePlan {
        /// The plan's status at the new version.
        status: PlanStatusResponse,
        /// Waypoints in the new document.
        waypoints: usize,
    },
    /// [`Command::StartMission`].
    StartMission {
        /// Mission id.
        mission_id: String,
    },
    /// [`Command::StoreMission`]: a mission's record is persisted.
    StoreMission {
        /// Mission id.
        mission_id: String,
        /// Its status.
        status: shift_proto::MissionStatus,
    },
    /// [`Command::MissionChanged`].
    Mission {
        /// The mission's view.
        view: shift_proto::MissionView,
    },
    /// [`Command::StoreCoverage`] (`stored`) and [`Command::CoverageChanged`]: a measured raster.
    Coverage {
        /// Whose.
        key: crate::coverage::CoverageKey,
        /// Run lengths of its swept cells.
        runs: usize,
        /// To the store (else to the read model).
        stored: bool,
    },
    /// [`Command::FeedSite`]: where a robot's sensor data goes.
    FeedSite {
        /// Robot.
        robot: String,
        /// Its plan's site (`None`: the default site).
        site: Option<String>,
    },
}

impl Decision {
    /// This decision as a recording of `format` holds it: `None` when that format had no such decision. See
    /// the module docs.
    pub fn as_format(&self, format: u32) -> Option<Self> {
        if format >= FORMAT {
            return Some(self.clone());
        }
        let status_v1 = |s: &PlanStatusResponse| PlanStatusResponse {
            corrections: 0,
            watch: None,
            progress_jumps: Vec::new(),
            mission: None,
            ..s.clone()
        };
        let view_v1 = |v: &RobotView| RobotView {
            site: None,
            sensors: None,
            ..v.clone()
        };
        Some(match self {
            Self::FeedSite { .. } => return None,
            Self::PlanStatus { status } => Self::PlanStatus {
                status: status_v1(status),
            },
            Self::PlanUpdate { status } => Self::PlanUpdate {
                status: status_v1(status),
            },
            Self::Robot { view } => Self::Robot { view: view_v1(view) },
            Self::Publish {
                event: PlanEvent::Status(status),
            } => Self::Publish {
                event: PlanEvent::Status(status_v1(status)),
            },
            other => other.clone(),
        })
    }
}

impl From<&Command> for Decision {
    fn from(c: &Command) -> Self {
        match c {
            Command::StoreSite(rec) => Self::StoreSite { site: rec.site.clone() },
            Command::SiteChanged(summary) => Self::SiteChanged {
                summary: summary.clone(),
            },
            Command::StorePlan(rec) => Self::PlanStatus {
                status: rec.to_response(),
            },
            Command::UpdatePlan(rec) => Self::PlanUpdate {
                status: rec.to_response(),
            },
            Command::StoreResult { plan_id, doc } => Self::PlanResult {
                plan_id: plan_id.clone(),
                version: doc.version,
                waypoints: doc.waypoints.len(),
            },
            Command::StartJob(job) => Self::StartJob {
                plan_id: job.plan_id.clone(),
            },
            Command::CancelJob { plan_id } => Self::CancelJob {
                plan_id: plan_id.clone(),
            },
            Command::Publish(event) => Self::Publish { event: event.clone() },
            Command::PublishPlan { robot, doc } => Self::DeliverPlan {
                robot: robot.clone(),
                plan_id: doc.plan_id.clone(),
                version: doc.version,
                waypoints: doc.waypoints.len(),
            },
            Command::RobotChanged(view) => Self::Robot { view: view.clone() },
            Command::SiteStatic { site, .. } => Self::SiteStatic { site: site.clone() },
            Command::StartCheck(job) => Self::StartCheck {
                robot: job.robot.clone(),
                plan_id: job.plan_id.clone(),
                version: job.doc.version,
                trigger: job.trigger,
            },
            Command::StoreCorrection { correction, .. } => Self::StoreCorrection {
                correction: (**correction).clone(),
            },
            Command::PublishCorrection(c) => Self::DeliverCorrection {
                robot: c.robot.clone(),
                plan_id: c.plan_id.clone(),
                version: c.version,
            },
            Command::FeedSite { robot, site } => Self::FeedSite {
                robot: robot.clone(),
                site: site.clone(),
            },
            Command::ForgetPlan { plan_id } => Self::ForgetPlan {
                plan_id: plan_id.clone(),
            },
            Command::ReplacePlanDoc { record, doc } => Self::ReplacePlan {
                status: record.to_response(),
                waypoints: doc.waypoints.len(),
            },
            Command::StartMission(job) => Self::StartMission {
                mission_id: job.mission_id.clone(),
            },
            Command::StoreMission(rec) => Self::StoreMission {
                mission_id: rec.mission_id.clone(),
                status: rec.status,
            },
            Command::MissionChanged(view) => Self::Mission { view: view.clone() },
            Command::StoreCoverage(rec) => Self::Coverage {
                key: rec.key.clone(),
                runs: rec.covered.runs.len(),
                stored: true,
            },
            Command::CoverageChanged(rec) => Self::Coverage {
                key: rec.key.clone(),
                runs: rec.covered.runs.len(),
                stored: false,
            },
        }
    }
}

/// The decisions of one `handle` call: its commands summarised, or one [`Decision::Refused`].
pub fn decisions_of(result: &Result<Vec<Command>>) -> Vec<Decision> {
    match result {
        Ok(cmds) => cmds.iter().map(Decision::from).collect(),
        Err(e) => vec![Decision::Refused { error: e.to_string() }],
    }
}

#[cfg(test)]
mod tests {
    use shift_proto::{PlanMetricsDoc, RobotSpec, WaypointDoc, WaypointKindDoc};

    use std::sync::Arc;

    use shift_proto::{PlanDocument, PlanRequest, RegionReady};

    use super::*;
    use crate::robots::Pose2;
    use crate::site::{LoadedSite, MapSource, SiteRecord};
    use crate::{Engine, EngineConfig, JobOutcome};

    fn doc(plan_id: &str) -> PlanDocument {
        PlanDocument {
            plan_id: plan_id.into(),
            version: 1,
            frame: "map".into(),
            waypoints: (0..5)
                .map(|i| WaypointDoc {
                    x: 0.25 + f64::from(i) * 0.1,
                    y: 0.25,
                    z: 0.0,
                    v: 0.3,
                    t: f64::from(i) / 3.0,
                    kind: WaypointKindDoc::Cover,
                    region: Some(0),
                })
                .collect(),
            regions: vec![],
            metrics: PlanMetricsDoc::default(),
        }
    }

    fn site() -> SiteRecord {
        SiteRecord {
            site: "s".into(),
            source: MapSource::Json {
                text: format!(
                    r#"{{"resolution": 0.1, "origin": [0, 0], "width": 10, "height": 10, "cells": [{}]}}"#,
                    vec!["0"; 100].join(",")
                ),
            },
            updated_ms: 5,
        }
    }

    fn inputs() -> Vec<Event> {
        let site = LoadedSite::parse(site()).expect("map parses");
        let request = PlanRequest {
            site: "s".into(),
            start: [0.25, 0.25],
            robot: RobotSpec {
                radius: 0.1,
                footprint: None,
                tool_width: 0.2,
                v_min: 0.1,
                v_max: 1.0,
                a_max: 0.5,
            },
            attribute: None,
            region: None,
            options: None,
            objective: None,
            snap_start_m: None,
        };
        vec![
            Event::MapUploaded { site },
            Event::RobotLiveliness {
                robot: "r1".into(),
                alive: true,
            },
            Event::PlanRequested {
                request: request.clone(),
            },
            Event::PlanRequested {
                request: PlanRequest {
                    site: "nowhere".into(),
                    ..request
                },
            },
            Event::JobProgress {
                plan_id: "p-1".into(),
                progress: 0.1 + 0.2,
            },
            Event::JobRegionReady {
                plan_id: "p-1".into(),
                region: RegionReady {
                    region: 3,
                    polygon: vec![[0.0, 0.0], [1.0, 0.0], [0.5, 0.1 + 0.2]],
                    path: vec![[0.25, 0.5]],
                },
            },
            Event::JobFinished {
                plan_id: "p-1".into(),
                outcome: JobOutcome::Planned {
                    doc: Arc::new(doc("p-1")),
                    warnings: vec!["w".into()],
                },
            },
            Event::AssignPlan {
                plan_id: "p-1".into(),
                robot: "r1".into(),
                doc: Arc::new(doc("p-1")),
            },
            Event::RobotPose {
                robot: "r1".into(),
                pose: Pose2 {
                    x: 0.35,
                    y: 0.25 + 1e-9,
                    yaw: 0.1,
                    stamp_ns: 7,
                },
            },
            Event::RobotPose {
                robot: "r1".into(),
                pose: Pose2 {
                    x: f64::NAN,
                    y: f64::INFINITY,
                    yaw: 0.0,
                    stamp_ns: 8,
                },
            },
            Event::RobotLiveliness {
                robot: "r1".into(),
                alive: false,
            },
            Event::Shutdown,
        ]
    }

    /// Runs events through an engine; returns the recorded inputs (as JSON text) and the decisions (as JSON).
    fn run(events: Vec<Event>) -> (Vec<String>, Vec<serde_json::Value>) {
        let mut engine = Engine::new(EngineConfig::default());
        let (mut recorded, mut decided) = (Vec::new(), Vec::new());
        for (i, e) in events.into_iter().enumerate() {
            let seq = i as u64 + 1;
            let now_ms = 1_000 + seq * 17;
            let input = RecordedInput {
                run: 1,
                seq,
                now_ms,
                event: e.clone(),
            };
            recorded.push(serde_json::to_string(&input).expect("input serialises"));
            let result = engine.handle(e, now_ms);
            let d = RecordedDecisions {
                run: 1,
                seq,
                now_ms,
                decisions: decisions_of(&result),
            };
            decided.push(serde_json::to_value(&d).expect("decisions serialise"));
        }
        (recorded, decided)
    }

    #[test]
    fn replaying_recorded_inputs_gives_the_same_decisions() {
        let (recorded, decided) = run(inputs());
        let replayed: Vec<Event> = recorded
            .iter()
            .map(|t| {
                let input: RecordedInput = serde_json::from_str(t).expect("input reads back");
                input.event
            })
            .collect();
        let (again, decided_again) = run(replayed);
        assert_eq!(again, recorded, "inputs re-record identically");
        assert_eq!(decided_again, decided);
        // The run contains what a replay is for.
        let text = serde_json::to_string(&decided).expect("json");
        for needle in [
            r#""type":"refused""#,
            r#""status":"active""#,
            r#""type":"deliver_plan""#,
            r#""alive":false"#,
        ] {
            assert!(text.contains(needle), "{needle} missing from {text}");
        }
    }

    #[test]
    fn non_finite_numbers_survive_json() {
        let pose = Pose2 {
            x: f64::NAN,
            y: f64::NEG_INFINITY,
            yaw: f64::INFINITY,
            stamp_ns: -1,
        };
        let text = serde_json::to_string(&pose).expect("json");
        assert_eq!(text, r#"{"x":"NaN","y":"-inf","yaw":"inf","stamp_ns":-1}"#);
        let back: Pose2 = serde_json::from_str(&text).expect("reads back");
        assert!(back.x.is_nan() && back.y == f64::NEG_INFINITY && back.yaw == f64::INFINITY);
        assert!(serde_json::from_str::<Pose2>(r#"{"x":"one","y":0,"yaw":0,"stamp_ns":0}"#).is_err());
    }
}
