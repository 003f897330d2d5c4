use std::sync::Arc;

use shift_proto::{PlanDocument, PlanMetricsDoc, PlanRequest, RegionReady, RobotSpec};

use super::*;
use crate::EngineError;
use crate::robots::Pose2;
use crate::site::{LoadedSite, MapSource, SiteRecord};

pub(super) fn site_event(name: &str) -> Event {
    let source = MapSource::Json {
        text: r#"{"resolution": 0.1, "origin": [0, 0], "width": 30, "height": 20, "cells": []}"#
            .replace("[]", &format!("[{}]", vec!["0"; 600].join(","))),
    };
    let site = LoadedSite::parse(SiteRecord {
        site: name.into(),
        source,
        updated_ms: 1,
    })
    .expect("valid map");
    Event::MapUploaded { site }
}

pub(super) fn request(site: &str) -> PlanRequest {
    PlanRequest {
        site: site.into(),
        start: [0.5, 0.5],
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
    }
}

pub(super) fn engine(workers: usize, queue_capacity: usize) -> Engine {
    let mut e = Engine::new(EngineConfig {
        workers,
        queue_capacity,
        ..EngineConfig::default()
    });
    e.handle(site_event("s"), 0).expect("site");
    e
}

fn started(cmds: &[Command]) -> Vec<String> {
    cmds.iter()
        .filter_map(|c| match c {
            Command::StartJob(j) => Some(j.plan_id.clone()),
            _ => None,
        })
        .collect()
}

fn stored(cmds: &[Command]) -> Vec<(String, PlanStatus)> {
    cmds.iter()
        .filter_map(|c| match c {
            Command::StorePlan(r) => Some((r.plan_id.clone(), r.status)),
            _ => None,
        })
        .collect()
}

fn planned() -> JobOutcome {
    JobOutcome::Planned {
        doc: Arc::new(PlanDocument {
            plan_id: "p-1".into(),
            version: 1,
            frame: "map".into(),
            waypoints: vec![],
            regions: vec![],
            metrics: PlanMetricsDoc::default(),
        }),
        warnings: vec![],
    }
}

#[test]
fn request_is_persisted_before_it_starts_and_queue_respects_workers() {
    let mut e = engine(1, 8);
    let c1 = e
        .handle(Event::PlanRequested { request: request("s") }, 10)
        .expect("accepted");
    // Persisted as queued first, then started.
    assert_eq!(
        stored(&c1),
        vec![("p-1".into(), PlanStatus::Queued), ("p-1".into(), PlanStatus::Planning)]
    );
    assert_eq!(started(&c1), vec!["p-1".to_string()]);
    let c2 = e
        .handle(Event::PlanRequested { request: request("s") }, 11)
        .expect("accepted");
    assert!(started(&c2).is_empty(), "one worker is busy");
    assert_eq!(e.queue_depth(), 1);
    // A region streams while the job runs: published at once, counted on the record.
    let region = RegionReady {
        region: 0,
        polygon: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
        path: vec![[0.5, 0.5], [0.6, 0.5]],
    };
    let cr = e
        .handle(
            Event::JobRegionReady {
                plan_id: "p-1".into(),
                region: region.clone(),
            },
            11,
        )
        .expect("region");
    assert!(cr.iter().any(
        |c| matches!(c, Command::Publish(PlanEvent::RegionReady { plan_id, region: r }) if plan_id == "p-1" && *r == region)
    ));
    assert_eq!(e.plan("p-1").expect("known").regions_ready, 1);
    // Not for a plan that is not planning.
    let late = e
        .handle(
            Event::JobRegionReady {
                plan_id: "p-2".into(),
                region,
            },
            11,
        )
        .expect("ignored");
    assert!(late.is_empty(), "{late:?}");
    let c3 = e
        .handle(
            Event::JobFinished {
                plan_id: "p-1".into(),
                outcome: planned(),
            },
            12,
        )
        .expect("finished");
    assert_eq!(started(&c3), vec!["p-2".to_string()]);
    let rec = e.plan("p-1").expect("known");
    assert_eq!(rec.status, PlanStatus::Ready);
    assert_eq!(rec.regions_ready, 1);
    assert_eq!(rec.version, 1);
    // The result is stored before the ready status is.
    let pos_result = c3.iter().position(|c| matches!(c, Command::StoreResult { .. }));
    let pos_ready = c3
        .iter()
        .position(|c| matches!(c, Command::StorePlan(r) if r.status == PlanStatus::Ready));
    assert!(pos_result < pos_ready);
}

#[test]
fn full_queue_refuses_and_changes_nothing() {
    let mut e = engine(1, 1);
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("runs");
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("waits");
    let err = e
        .handle(Event::PlanRequested { request: request("s") }, 0)
        .expect_err("full");
    assert_eq!(err, EngineError::QueueFull { capacity: 1 });
    assert!(e.plan("p-3").is_none());
    // The next accepted plan still gets the next id.
    e.handle(
        Event::JobFinished {
            plan_id: "p-1".into(),
            outcome: JobOutcome::Failed { reason: "x".into() },
        },
        1,
    )
    .expect("finished");
    e.handle(Event::PlanRequested { request: request("s") }, 2)
        .expect("room again");
    assert!(e.plan("p-3").is_some());
}

#[test]
fn unknown_things_and_bad_requests_are_errors() {
    let mut e = engine(1, 4);
    assert_eq!(
        e.handle(
            Event::PlanRequested {
                request: request("nope")
            },
            0
        )
        .expect_err("no site"),
        EngineError::UnknownSite("nope".into())
    );
    let mut r = request("s");
    r.start = [100.0, 0.0];
    assert!(matches!(
        e.handle(Event::PlanRequested { request: r }, 0),
        Err(EngineError::InvalidRequest(_))
    ));
    assert!(matches!(
        e.handle(Event::CancelRequested { plan_id: "p-9".into() }, 0),
        Err(EngineError::UnknownPlan(_))
    ));
}

#[test]
fn cancel_queued_running_and_finished() {
    let mut e = engine(1, 4);
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("runs");
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("waits");
    // Queued: removed from the queue, no job command.
    let c = e
        .handle(Event::CancelRequested { plan_id: "p-2".into() }, 1)
        .expect("cancel queued");
    assert_eq!(stored(&c), vec![("p-2".into(), PlanStatus::Cancelled)]);
    assert_eq!(e.queue_depth(), 0);
    // Running: the flag is raised and the status changes at once.
    let c = e
        .handle(Event::CancelRequested { plan_id: "p-1".into() }, 2)
        .expect("cancel running");
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::CancelJob { plan_id } if plan_id == "p-1"))
    );
    assert_eq!(e.plan("p-1").map(|r| r.status), Some(PlanStatus::Cancelled));
    // The worker's late outcome does not resurrect it, but frees the slot.
    e.handle(
        Event::JobFinished {
            plan_id: "p-1".into(),
            outcome: planned(),
        },
        3,
    )
    .expect("late");
    assert_eq!(e.plan("p-1").map(|r| r.status), Some(PlanStatus::Cancelled));
    assert_eq!(e.running(), 0);
    // Cancelling again is an invalid state change.
    assert!(matches!(
        e.handle(Event::CancelRequested { plan_id: "p-1".into() }, 4),
        Err(EngineError::InvalidState { .. })
    ));
}

#[test]
fn progress_is_monotone_and_not_persisted() {
    let mut e = engine(1, 4);
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("runs");
    let c = e
        .handle(
            Event::JobProgress {
                plan_id: "p-1".into(),
                progress: 0.5,
            },
            1,
        )
        .expect("progress");
    assert!(stored(&c).is_empty());
    assert!(matches!(c.first(), Some(Command::UpdatePlan(_))));
    let c = e
        .handle(
            Event::JobProgress {
                plan_id: "p-1".into(),
                progress: 0.2,
            },
            2,
        )
        .expect("progress");
    assert!(c.is_empty(), "going backwards is not news");
    assert_eq!(e.plan("p-1").map(|r| r.progress), Some(0.5));
}

#[test]
fn shutdown_interrupts_back_to_queued_and_restore_requeues() {
    let mut e = engine(1, 4);
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("runs");
    e.handle(Event::Shutdown, 1).expect("drain");
    assert_eq!(
        e.handle(Event::PlanRequested { request: request("s") }, 1)
            .expect_err("draining"),
        EngineError::ShuttingDown
    );
    let c = e
        .handle(
            Event::JobFinished {
                plan_id: "p-1".into(),
                outcome: JobOutcome::Interrupted,
            },
            2,
        )
        .expect("interrupted");
    assert_eq!(stored(&c), vec![("p-1".into(), PlanStatus::Queued)]);
    assert!(started(&c).is_empty(), "no new jobs while draining");

    // A new engine restored from what was persisted: the queued plan and one left "planning" by a kill -9.
    let queued = e.plan("p-1").expect("known").clone();
    let mut killed = queued.clone();
    killed.plan_id = "p-7".into();
    killed.seq = 7;
    killed.status = PlanStatus::Planning;
    let mut orphan = queued.clone();
    orphan.plan_id = "p-8".into();
    orphan.seq = 8;
    orphan.request.site = "gone".into();
    let Event::MapUploaded { site } = site_event("s") else {
        unreachable!()
    };
    let mut e2 = Engine::new(EngineConfig {
        workers: 1,
        queue_capacity: 4,
        ..EngineConfig::default()
    });
    let c = e2
        .handle(
            Event::Restore {
                sites: vec![site],
                plans: vec![killed, orphan, queued],
                active: Vec::new(),
                missions: Vec::new(),
                coverage: Vec::new(),
            },
            10,
        )
        .expect("restore");
    assert_eq!(started(&c), vec!["p-1".to_string()]);
    assert_eq!(e2.plan("p-7").map(|r| r.status), Some(PlanStatus::Queued));
    let orphan = e2.plan("p-8").expect("known");
    assert_eq!(orphan.status, PlanStatus::Failed);
    assert!(orphan.error.as_deref().unwrap_or("").contains("no longer exists"));
    // New ids continue after the highest restored one.
    e2.handle(Event::PlanRequested { request: request("s") }, 11)
        .expect("accepted");
    assert!(e2.plan("p-9").is_some());
}

#[test]
fn same_events_give_same_commands() {
    let run = || {
        let mut e = engine(2, 4);
        let mut log = Vec::new();
        for t in 0..3 {
            let c = e
                .handle(Event::PlanRequested { request: request("s") }, t)
                .expect("accepted");
            log.push(format!("{:?}", stored(&c)));
        }
        log
    };
    assert_eq!(run(), run());
}

#[test]
fn bad_site_name_is_refused() {
    let mut e = engine(1, 1);
    let Event::MapUploaded { mut site } = site_event("x") else {
        unreachable!()
    };
    site.record.site = "../etc".into();
    assert!(matches!(
        e.handle(Event::MapUploaded { site }, 0),
        Err(EngineError::InvalidRequest(_))
    ));
    assert!(e.site("s").is_some());
}

#[test]
fn assign_tracks_progress_to_done_and_moves_between_robots() {
    use shift_proto::{WaypointDoc, WaypointKindDoc};
    let mut e = engine(1, 4);
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("runs");
    let pts = [(0.5, 0.5), (1.5, 0.5), (2.5, 0.5)];
    let doc = Arc::new(PlanDocument {
        plan_id: "p-1".into(),
        version: 1,
        frame: "map".into(),
        waypoints: pts
            .iter()
            .map(|&(x, y)| WaypointDoc {
                x,
                y,
                z: 0.0,
                v: 0.5,
                t: 0.0,
                kind: WaypointKindDoc::Cover,
                region: Some(0),
            })
            .collect(),
        regions: vec![],
        metrics: PlanMetricsDoc::default(),
    });
    // Not ready yet: 409.
    assert!(matches!(
        e.handle(
            Event::AssignPlan {
                plan_id: "p-1".into(),
                robot: "r1".into(),
                doc: doc.clone()
            },
            1
        ),
        Err(EngineError::InvalidState { .. })
    ));
    e.handle(
        Event::JobFinished {
            plan_id: "p-1".into(),
            outcome: JobOutcome::Planned {
                doc: doc.clone(),
                warnings: vec![],
            },
        },
        2,
    )
    .expect("ready");
    assert!(matches!(
        e.handle(
            Event::AssignPlan {
                plan_id: "p-1".into(),
                robot: "bad/name".into(),
                doc: doc.clone()
            },
            3
        ),
        Err(EngineError::InvalidRequest(_))
    ));
    let c = e
        .handle(
            Event::AssignPlan {
                plan_id: "p-1".into(),
                robot: "r1".into(),
                doc: doc.clone(),
            },
            3,
        )
        .expect("assigned");
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::PublishPlan { robot, .. } if robot == "r1"))
    );
    assert_eq!(stored(&c), vec![("p-1".into(), PlanStatus::Active)]);
    let pose = |x: f64| Pose2 {
        x,
        y: 0.5,
        yaw: 0.0,
        stamp_ns: 0,
    };
    e.handle(
        Event::RobotPose {
            robot: "r1".into(),
            pose: pose(1.45),
        },
        4,
    )
    .expect("pose");
    assert_eq!(e.plan("p-1").map(|r| r.driven_fraction), Some(0.5));
    assert_eq!(e.robot("r1").and_then(|r| r.driven_m), Some(1.0));
    let c = e
        .handle(
            Event::RobotPose {
                robot: "r1".into(),
                pose: pose(2.5),
            },
            5,
        )
        .expect("pose");
    assert_eq!(stored(&c), vec![("p-1".into(), PlanStatus::Done)]);
    // Liveliness: alive then lost.
    e.handle(
        Event::RobotLiveliness {
            robot: "r1".into(),
            alive: true,
        },
        6,
    )
    .expect("alive");
    assert_eq!(e.robot("r1").map(|r| r.alive), Some(true));
    e.handle(
        Event::RobotLiveliness {
            robot: "r1".into(),
            alive: false,
        },
        7,
    )
    .expect("lost");
    assert_eq!(e.robot("r1").map(|r| r.alive), Some(false));
}

#[test]
fn settled_plans_beyond_retain_plans_are_forgotten_oldest_first_in_flight_never() {
    let mut e = Engine::new(EngineConfig {
        workers: 1,
        retain_plans: 2,
        ..EngineConfig::default()
    });
    e.handle(site_event("s"), 0).expect("site");
    let forgotten = |cmds: &[Command]| -> Vec<String> {
        cmds.iter()
            .filter_map(|c| match c {
                Command::ForgetPlan { plan_id } => Some(plan_id.clone()),
                _ => None,
            })
            .collect()
    };
    // p-1 and p-2 computed (settled), p-3 and p-4 still queued or planning.
    for (i, id) in ["p-1", "p-2"].iter().enumerate() {
        e.handle(Event::PlanRequested { request: request("s") }, 10 + i as u64)
            .expect("accepted");
        let cmds = e
            .handle(
                Event::JobFinished {
                    plan_id: (*id).into(),
                    outcome: planned(),
                },
                20 + i as u64,
            )
            .expect("finished");
        assert!(forgotten(&cmds).is_empty());
    }
    let c3 = e
        .handle(Event::PlanRequested { request: request("s") }, 30)
        .expect("p-3");
    assert!(forgotten(&c3).is_empty(), "two settled plans are within the limit");
    e.handle(Event::CancelRequested { plan_id: "p-3".into() }, 31)
        .expect("cancel");
    // p-3 cancelled: three settled, one over: the oldest goes, the in-flight p-4 never.
    let c4 = e
        .handle(Event::PlanRequested { request: request("s") }, 40)
        .expect("p-4");
    assert_eq!(forgotten(&c4), vec!["p-1".to_string()]);
    assert!(e.plan("p-1").is_none() && e.plan("p-2").is_some() && e.plan("p-4").is_some());
    // A snapshot taken before a request is the engine as it was (what the daemon puts back on a store failure).
    let snapshot = e.clone();
    e.handle(Event::PlanRequested { request: request("s") }, 50)
        .expect("p-5");
    assert!(e.plan("p-5").is_some());
    e = snapshot;
    assert!(e.plan("p-5").is_none());
    let c = e
        .handle(Event::PlanRequested { request: request("s") }, 60)
        .expect("p-5 again");
    assert_eq!(
        stored(&c)[0].0,
        "p-5",
        "an undone request gives its id out again: nothing of it was stored"
    );
}
