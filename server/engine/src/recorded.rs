//! The engine's inputs and decisions as they are recorded (MCAP JSON channels) and replayed.
//!
//! [`RecordedEvent`] mirrors [`Event`] with serde: maps travel as their [`SiteRecord`] (re-parsed on replay,
//! with the same code the daemon uses), job results as the plan document. [`Decision`] summarises a
//! [`Command`] to something comparable across runs (no store handles, no job payloads). A new `Event` or
//! `Command` variant needs one arm here; the matches are exhaustive on purpose, so the compiler points at them.
//!
//! Replaying [`RecordedInput`]s in `seq` order through a fresh [`Engine`](crate::Engine) with the recorded
//! `now_ms` and [`EngineConfig`](crate::EngineConfig) gives the recorded [`RecordedDecisions`] again: the engine
//! is deterministic in its inputs.

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use shift_proto::{PlanDocument, PlanEvent, PlanRequest, PlanStatusResponse, RegionReady, RobotView, SiteSummary};

use crate::engine::{Command, Event, JobOutcome};
use crate::error::{EngineError, Result};
use crate::plan::PlanRecord;
use crate::robots::Pose2;
use crate::site::SiteRecord;

/// One event the engine handled, with the time it was handled at.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordedInput {
    /// Identifies one daemon run (its start, milliseconds since the Unix epoch); `seq` restarts per run.
    pub run: u64,
    /// Handling order within the run, from 1.
    pub seq: u64,
    /// The `now_ms` passed to [`Engine::handle`](crate::Engine::handle), milliseconds since the Unix epoch.
    pub now_ms: u64,
    /// The event.
    pub event: RecordedEvent,
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
}

/// A planar pose whose numbers survive JSON even when not finite (NaN and infinities as strings).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RecordedPose {
    /// x, metres, map frame.
    #[serde(with = "lossless_f64")]
    pub x: f64,
    /// y, metres, map frame.
    #[serde(with = "lossless_f64")]
    pub y: f64,
    /// Heading, radians.
    #[serde(with = "lossless_f64")]
    pub yaw: f64,
    /// Stamp, nanoseconds (robot clock).
    pub stamp_ns: i64,
}

/// [`JobOutcome`] with serde.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RecordedOutcome {
    /// Computed: the document, the planner's remarks and the per-region paths.
    Planned {
        /// The plan document (version 1).
        doc: Box<PlanDocument>,
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
    /// Stopped by shutdown.
    Interrupted,
}

/// [`Event`] with serde. See the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum RecordedEvent {
    /// [`Event::Restore`]: sites as stored (re-parsed on replay) and every plan record.
    Restore {
        /// Site records.
        sites: Vec<SiteRecord>,
        /// Plan records.
        plans: Vec<PlanRecord>,
    },
    /// [`Event::MapUploaded`].
    MapUploaded {
        /// The site record (its map source is re-parsed on replay).
        record: SiteRecord,
    },
    /// [`Event::PlanRequested`].
    PlanRequested {
        /// The request.
        request: PlanRequest,
    },
    /// [`Event::CancelRequested`].
    CancelRequested {
        /// Plan id.
        plan_id: String,
    },
    /// [`Event::JobProgress`].
    JobProgress {
        /// Plan id.
        plan_id: String,
        /// Fraction done.
        #[serde(with = "lossless_f64")]
        progress: f64,
    },
    /// [`Event::JobRegionReady`].
    JobRegionReady {
        /// Plan id.
        plan_id: String,
        /// The region and its cover path.
        region: RegionReady,
    },
    /// [`Event::JobFinished`].
    JobFinished {
        /// Plan id.
        plan_id: String,
        /// How.
        outcome: RecordedOutcome,
    },
    /// [`Event::RobotLiveliness`].
    RobotLiveliness {
        /// Robot id.
        robot: String,
        /// Token present.
        alive: bool,
    },
    /// [`Event::RobotPose`].
    RobotPose {
        /// Robot id.
        robot: String,
        /// Its pose, map frame.
        pose: RecordedPose,
    },
    /// [`Event::AssignPlan`].
    AssignPlan {
        /// Plan id.
        plan_id: String,
        /// Robot id.
        robot: String,
        /// The document assigned.
        doc: Box<PlanDocument>,
    },
    /// [`Event::MapChanged`].
    MapChanged {
        /// Site.
        site: String,
        /// Lower corner (x, y), metres.
        min: [f64; 2],
        /// Upper corner (x, y), metres.
        max: [f64; 2],
    },
    /// [`Event::CheckFinished`]: the check's result as computed live, so a replay needs no live map.
    CheckFinished {
        /// Robot checked.
        robot: String,
        /// Plan it drove.
        plan_id: String,
        /// Version checked.
        base_version: u64,
        /// What the check found.
        outcome: crate::watch::CheckOutcome,
        /// Check time, microseconds.
        compute_us: u64,
    },
    /// [`Event::Shutdown`].
    Shutdown,
}

impl From<&Event> for RecordedEvent {
    fn from(e: &Event) -> Self {
        match e {
            Event::Restore { sites, plans } => Self::Restore {
                sites: sites.iter().map(|(r, _)| r.clone()).collect(),
                plans: plans.clone(),
            },
            Event::MapUploaded { record, .. } => Self::MapUploaded { record: record.clone() },
            Event::PlanRequested(request) => Self::PlanRequested {
                request: request.clone(),
            },
            Event::CancelRequested { plan_id } => Self::CancelRequested {
                plan_id: plan_id.clone(),
            },
            Event::JobProgress { plan_id, progress } => Self::JobProgress {
                plan_id: plan_id.clone(),
                progress: *progress,
            },
            Event::JobRegionReady { plan_id, region } => Self::JobRegionReady {
                plan_id: plan_id.clone(),
                region: region.clone(),
            },
            Event::JobFinished { plan_id, outcome } => Self::JobFinished {
                plan_id: plan_id.clone(),
                outcome: match outcome {
                    JobOutcome::Planned { doc, warnings } => RecordedOutcome::Planned {
                        doc: Box::new((**doc).clone()),
                        warnings: warnings.clone(),
                    },
                    JobOutcome::Failed(reason) => RecordedOutcome::Failed { reason: reason.clone() },
                    JobOutcome::Cancelled => RecordedOutcome::Cancelled,
                    JobOutcome::Interrupted => RecordedOutcome::Interrupted,
                },
            },
            Event::RobotLiveliness { robot, alive } => Self::RobotLiveliness {
                robot: robot.clone(),
                alive: *alive,
            },
            Event::RobotPose { robot, pose } => Self::RobotPose {
                robot: robot.clone(),
                pose: RecordedPose {
                    x: pose.x,
                    y: pose.y,
                    yaw: pose.yaw,
                    stamp_ns: pose.stamp_ns,
                },
            },
            Event::AssignPlan { plan_id, robot, doc } => Self::AssignPlan {
                plan_id: plan_id.clone(),
                robot: robot.clone(),
                doc: Box::new((**doc).clone()),
            },
            Event::MapChanged { site, min, max } => Self::MapChanged {
                site: site.clone(),
                min: *min,
                max: *max,
            },
            Event::CheckFinished {
                robot,
                plan_id,
                base_version,
                outcome,
                compute_us,
            } => Self::CheckFinished {
                robot: robot.clone(),
                plan_id: plan_id.clone(),
                base_version: *base_version,
                outcome: outcome.clone(),
                compute_us: *compute_us,
            },
            Event::Shutdown => Self::Shutdown,
        }
    }
}

impl RecordedEvent {
    /// The event again; maps are re-parsed from their sources (an error if one no longer parses).
    pub fn into_event(self) -> Result<Event> {
        Ok(match self {
            Self::Restore { sites, plans } => Event::Restore {
                sites: sites
                    .into_iter()
                    .map(|r| {
                        let map = r.source.parse()?;
                        Ok::<_, EngineError>((r, map))
                    })
                    .collect::<Result<_>>()?,
                plans,
            },
            Self::MapUploaded { record } => {
                let map = record.source.parse()?;
                Event::MapUploaded { record, map }
            }
            Self::PlanRequested { request } => Event::PlanRequested(request),
            Self::CancelRequested { plan_id } => Event::CancelRequested { plan_id },
            Self::JobProgress { plan_id, progress } => Event::JobProgress { plan_id, progress },
            Self::JobRegionReady { plan_id, region } => Event::JobRegionReady { plan_id, region },
            Self::JobFinished { plan_id, outcome } => Event::JobFinished {
                plan_id,
                outcome: match outcome {
                    RecordedOutcome::Planned { doc, warnings } => JobOutcome::Planned {
                        doc: Arc::from(doc),
                        warnings,
                    },
                    RecordedOutcome::Failed { reason } => JobOutcome::Failed(reason),
                    RecordedOutcome::Cancelled => JobOutcome::Cancelled,
                    RecordedOutcome::Interrupted => JobOutcome::Interrupted,
                },
            },
            Self::RobotLiveliness { robot, alive } => Event::RobotLiveliness { robot, alive },
            Self::RobotPose { robot, pose } => Event::RobotPose {
                robot,
                pose: Pose2 {
                    x: pose.x,
                    y: pose.y,
                    yaw: pose.yaw,
                    stamp_ns: pose.stamp_ns,
                },
            },
            Self::AssignPlan { plan_id, robot, doc } => Event::AssignPlan {
                plan_id,
                robot,
                doc: Arc::from(doc),
            },
            Self::MapChanged { site, min, max } => Event::MapChanged { site, min, max },
            Self::CheckFinished {
                robot,
                plan_id,
                base_version,
                outcome,
                compute_us,
            } => Event::CheckFinished {
                robot,
                plan_id,
                base_version,
                outcome,
                compute_us,
            },
            Self::Shutdown => Event::Shutdown,
        })
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

/// `f64` as a JSON number when finite, else as `"NaN"`, `"inf"` or `"-inf"` (plain serde_json writes `null`,
/// which does not read back).
mod lossless_f64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else if v.is_nan() {
            s.serialize_str("NaN")
        } else if *v > 0.0 {
            s.serialize_str("inf")
        } else {
            s.serialize_str("-inf")
        }
    }

    #[derive(Deserialize)]
    #[serde(untagged)]
    enum NumOrText {
        Num(f64),
        Text(String),
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        match NumOrText::deserialize(d)? {
            NumOrText::Num(v) => Ok(v),
            NumOrText::Text(t) => match t.as_str() {
                "NaN" => Ok(f64::NAN),
                "inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                other => Err(serde::de::Error::custom(format!("not a number: {other:?}"))),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use shift_proto::{PlanMetricsDoc, RobotSpec, WaypointDoc, WaypointKindDoc};

    use super::*;
    use crate::site::MapSource;
    use crate::{Engine, EngineConfig};

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
        let record = site();
        let map = record.source.parse().expect("map parses");
        let request = PlanRequest {
            site: "s".into(),
            start: [0.25, 0.25],
            robot: RobotSpec {
                radius: 0.1,
                tool_width: 0.2,
                v_min: 0.1,
                v_max: 1.0,
                a_max: 0.5,
            },
            attribute: None,
            region: None,
            options: None,
        };
        vec![
            Event::MapUploaded { record, map },
            Event::RobotLiveliness {
                robot: "r1".into(),
                alive: true,
            },
            Event::PlanRequested(request.clone()),
            Event::PlanRequested(PlanRequest {
                site: "nowhere".into(),
                ..request
            }),
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
                event: RecordedEvent::from(&e),
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
                input.event.into_event().expect("event rebuilds")
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
        let pose = RecordedPose {
            x: f64::NAN,
            y: f64::NEG_INFINITY,
            yaw: f64::INFINITY,
            stamp_ns: -1,
        };
        let text = serde_json::to_string(&pose).expect("json");
        assert_eq!(text, r#"{"x":"NaN","y":"-inf","yaw":"inf","stamp_ns":-1}"#);
        let back: RecordedPose = serde_json::from_str(&text).expect("reads back");
        assert!(back.x.is_nan() && back.y == f64::NEG_INFINITY && back.yaw == f64::INFINITY);
        assert!(serde_json::from_str::<RecordedPose>(r#"{"x":"one","y":0,"yaw":0,"stamp_ns":0}"#).is_err());
    }
}
