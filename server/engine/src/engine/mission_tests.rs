//! Missions in the engine: accepted, divided and planned by the real mission job, assigned, swept, done;
//! refused, cancelled, interrupted and restored.

use shift_proto::{MissionRequest, MissionRobot, MissionStatus, MissionView, PlanStatus};

use super::tests::{engine, site_event};
use super::*;
use crate::EngineError;
use crate::coverage::CoverageKey;
use crate::mission_job::{MissionJob, MissionOutcome, planned_outcome, run_mission_job};
use crate::robots::Pose2;

pub(super) fn mission_request() -> MissionRequest {
    MissionRequest {
        site: "s".into(),
        robots: vec![
            MissionRobot::new("r1", [0.5, 0.5], 0.1, 0.2),
            MissionRobot::new("r2", [2.5, 1.5], 0.1, 0.2),
        ],
        attribute: None,
        options: None,
        objective: None,
    }
}

pub(super) fn mission_job(cmds: &[Command]) -> Option<MissionJob> {
    cmds.iter().find_map(|c| match c {
        Command::StartMission(j) => Some((**j).clone()),
        _ => None,
    })
}

pub(super) fn view(cmds: &[Command]) -> Option<MissionView> {
    cmds.iter().rev().find_map(|c| match c {
        Command::MissionChanged(v) => Some(v.clone()),
        _ => None,
    })
}

/// Accepts the mission and runs its job for real: the engine with the mission planned, and the job.
pub(super) fn planned() -> (Engine, MissionJob) {
    let mut e = engine(1, 4);
    let c = e
        .handle(
            Event::MissionRequested {
                request: mission_request(),
            },
            10,
        )
        .expect("accepted");
    let v = view(&c).expect("view");
    assert_eq!(v.mission_id, "m-1");
    assert_eq!(v.status, MissionStatus::Planning, "a free worker starts it at once");
    assert_eq!(
        v.plans.iter().map(|p| p.plan_id.as_str()).collect::<Vec<_>>(),
        ["p-2", "p-3"]
    );
    let job = mission_job(&c).expect("started");
    assert_eq!(e.plan("p-2").map(|r| r.status), Some(PlanStatus::Planning));
    assert_eq!(e.plan("p-2").and_then(|r| r.mission.clone()), Some("m-1".into()));
    let fleet = run_mission_job(&job).expect("divides and plans");
    let outcome = planned_outcome(&job, &fleet, 5.0);
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome,
            },
            20,
        )
        .expect("finished");
    let v = view(&c).expect("view");
    assert_eq!(v.status, MissionStatus::Ready);
    assert!(v.coverage.planned_pct.is_some_and(|p| p >= 99.0), "{v:?}");
    assert_eq!(v.coverage.measured_pct, 0.0);
    for p in &v.plans {
        assert_eq!(p.status, PlanStatus::Ready);
        assert_eq!(p.version, 1);
        assert!(
            p.planned_duration_s.is_some_and(|d| d > 0.0) && p.area_m2.is_some_and(|a| a > 0.5),
            "{p:?}"
        );
    }
    assert!(v.eta_s.is_some_and(|t| t > 0.0));
    (e, job)
}

fn drive(e: &mut Engine, robot: &str, plan_id: &str, t0: u64) -> u64 {
    let doc = e
        .robots
        .get(robot)
        .and_then(|r| r.assignment.as_ref())
        .map(|a| a.doc.clone())
        .expect(plan_id);
    let mut t = t0;
    // Along the path every 0.1 m, as odometry at 10 Hz of a robot at 1 m/s.
    let mut poses = Vec::new();
    for pair in doc.waypoints.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let n = ((b.x - a.x).hypot(b.y - a.y) / 0.1).ceil().max(1.0) as usize;
        for k in 0..n {
            let f = k as f64 / n as f64;
            poses.push((
                a.x + (b.x - a.x) * f,
                a.y + (b.y - a.y) * f,
                (b.y - a.y).atan2(b.x - a.x),
            ));
        }
    }
    if let Some(w) = doc.waypoints.last() {
        poses.push((w.x, w.y, 0.0));
    }
    for (x, y, yaw) in poses {
        t += 100;
        let pose = Pose2 { x, y, yaw, stamp_ns: 0 };
        e.handle(
            Event::RobotPose {
                robot: robot.into(),
                pose,
            },
            t,
        )
        .expect("pose");
    }
    t
}

fn docs(e: &Engine) -> Vec<Arc<shift_proto::PlanDocument>> {
    ["p-2", "p-3"]
        .iter()
        .map(|id| {
            let rec = e.plan(id).expect("plan");
            Arc::new(shift_proto::PlanDocument {
                plan_id: (*id).into(),
                version: rec.version,
                frame: "map".into(),
                waypoints: Vec::new(),
                regions: Vec::new(),
                metrics: rec.metrics.unwrap_or_default(),
            })
        })
        .collect()
}

#[test]
fn a_mission_is_divided_planned_assigned_swept_and_done() {
    let (mut e, job) = planned();
    // The daemon attaches the current documents; here the job's own.
    let fleet = run_mission_job(&job).expect("plans again, seeded");
    let MissionOutcome::Planned { parts, .. } = planned_outcome(&job, &fleet, 5.0) else {
        unreachable!()
    };
    let c = e
        .handle(
            Event::MissionAssignRequested {
                mission_id: "m-1".into(),
                docs: parts.iter().map(|p| p.doc.clone()).collect(),
            },
            30,
        )
        .expect("assigned");
    let delivered: Vec<(String, String)> = c
        .iter()
        .filter_map(|c| match c {
            Command::PublishPlan { robot, doc } => Some((robot.clone(), doc.plan_id.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(
        delivered,
        vec![("r1".into(), "p-2".into()), ("r2".into(), "p-3".into())]
    );
    assert_eq!(view(&c).map(|v| v.status), Some(MissionStatus::Active));
    let t = drive(&mut e, "r1", "p-2", 1_000);
    let half = e.mission("m-1").cloned().expect("mission");
    assert_eq!(half.status, MissionStatus::Active);
    let measured_half = e.coverage(&CoverageKey::Mission("m-1".into())).expect("raster");
    let t = drive(&mut e, "r2", "p-3", t + 2_000);
    // One more event past the view interval shows the final view.
    let c = e
        .handle(
            Event::RobotLiveliness {
                robot: "r1".into(),
                alive: true,
            },
            t + 5_000,
        )
        .expect("liveliness");
    assert_eq!(
        e.mission("m-1").map(|m| m.status),
        Some(MissionStatus::Done),
        "{:?}",
        [
            e.plan("p-2").map(|r| (r.status, r.driven_fraction)),
            e.plan("p-3").map(|r| (r.status, r.driven_fraction))
        ]
    );
    let v = view(&c).unwrap_or_else(|| e.mission("m-1").expect("m").to_view(&e.plans, 0.0));
    assert_eq!(v.status, MissionStatus::Done);
    assert!((v.progress - 1.0).abs() < 1e-9, "{}", v.progress);
    assert_eq!(v.eta_s, Some(0.0));
    let m = e.missions.get("m-1").and_then(|m| m.raster.clone()).expect("raster");
    assert!(m.pct() >= 97.0, "driving both plans sweeps the mission: {}", m.pct());
    let runs_half = measured_half.covered.runs.len();
    assert!(runs_half > 1, "half the mission was swept after r1");
    // The site's raster has what both swept; committed at the store interval.
    let site = e.coverage(&CoverageKey::Site("s".into())).expect("site raster");
    let swept = site.covered.decode(600).expect("cells").iter().filter(|&&c| c).count();
    assert!(swept >= 550, "{swept} of 600 cells");
}

#[test]
fn measured_coverage_is_committed_at_intervals_and_on_shutdown_and_restored() {
    let (mut e, job) = planned();
    let fleet = run_mission_job(&job).expect("plans");
    let MissionOutcome::Planned { parts, .. } = planned_outcome(&job, &fleet, 5.0) else {
        unreachable!()
    };
    e.handle(
        Event::MissionAssignRequested {
            mission_id: "m-1".into(),
            docs: parts.iter().map(|p| p.doc.clone()).collect(),
        },
        30,
    )
    .expect("assigned");
    let mut stores = Vec::new();
    let doc = parts[0].doc.clone();
    let mut t = 1_000;
    for w in doc.waypoints.iter().take(doc.waypoints.len() / 2) {
        t += 500;
        let c = e
            .handle(
                Event::RobotPose {
                    robot: "r1".into(),
                    pose: Pose2 {
                        x: w.x,
                        y: w.y,
                        yaw: 0.0,
                        stamp_ns: 0,
                    },
                },
                t,
            )
            .expect("pose");
        stores.extend(c.iter().filter_map(|c| match c {
            Command::StoreCoverage(r) => Some((t, r.key.clone())),
            _ => None,
        }));
    }
    assert!(!stores.is_empty(), "a drive of {} ms commits its sweep", t - 1_000);
    for w in stores.windows(2) {
        assert!(
            w[1].0 - w[0].0 >= e.config().coverage_commit_ms || w[1].0 == w[0].0,
            "{stores:?}"
        );
    }
    let c = e.handle(Event::Shutdown, t + 1).expect("shutdown");
    let saved: Vec<CoverageRecord> = c
        .iter()
        .filter_map(|c| match c {
            Command::StoreCoverage(r) => Some((**r).clone()),
            _ => None,
        })
        .collect();
    let before = e.coverage(&CoverageKey::Mission("m-1".into())).expect("raster");
    // Whatever was swept since the last commit is committed on shutdown.
    let last_mission = saved
        .iter()
        .find(|r| r.key == CoverageKey::Mission("m-1".into()))
        .cloned()
        .or_else(|| {
            stores.last().map(|_| before.clone()) // nothing new since: the last commit holds it
        })
        .expect("mission raster committed");
    assert_eq!(last_mission.covered, before.covered);
    // A restart reads the records back: the raster and the mission's measured figure are the same.
    let Event::MapUploaded { site } = site_event("s") else {
        unreachable!()
    };
    let mut e2 = Engine::new(e.config().clone());
    let plans: Vec<PlanRecord> = e.plans.values().cloned().collect();
    e2.handle(
        Event::Restore {
            sites: vec![site],
            plans,
            active: parts.iter().map(|p| p.doc.clone()).collect(),
            missions: vec![e.mission("m-1").cloned().expect("m")],
            coverage: vec![
                before.clone(),
                e.coverage(&CoverageKey::Site("s".into())).expect("site"),
            ],
        },
        t + 10,
    )
    .expect("restored");
    assert_eq!(e2.coverage(&CoverageKey::Mission("m-1".into())), Some(before));
    let pct = |e: &Engine| e.missions.get("m-1").and_then(|m| m.raster.as_ref()).map(|r| r.pct());
    assert_eq!(pct(&e2), pct(&e));
    assert!(pct(&e2).is_some_and(|p| p > 5.0));
}

#[test]
fn bad_missions_are_refused_and_nothing_is_kept() {
    let mut e = engine(1, 4);
    let mut req = mission_request();
    req.robots[1].id = "r1".into();
    let err = e
        .handle(Event::MissionRequested { request: req }, 1)
        .expect_err("duplicate");
    assert!(err.to_string().contains("robots[1].id \"r1\" is named twice"), "{err}");
    let mut req = mission_request();
    req.site = "nowhere".into();
    assert!(matches!(
        e.handle(Event::MissionRequested { request: req }, 1),
        Err(EngineError::UnknownSite(_))
    ));
    assert!(e.missions.is_empty() && e.plans.is_empty());
    assert!(matches!(
        e.handle(
            Event::MissionCancelRequested {
                mission_id: "m-9".into()
            },
            1
        ),
        Err(EngineError::UnknownMission(_))
    ));
}

#[test]
fn a_queued_mission_is_cancelled_with_its_plans_and_a_planning_one_ignores_its_late_job() {
    let mut e = engine(1, 4);
    e.handle(
        Event::PlanRequested {
            request: super::tests::request("s"),
        },
        1,
    )
    .expect("a plan takes the only worker");
    e.handle(
        Event::MissionRequested {
            request: mission_request(),
        },
        2,
    )
    .expect("queued");
    assert_eq!(e.mission("m-2").map(|m| m.status), Some(MissionStatus::Queued));
    let c = e
        .handle(
            Event::MissionCancelRequested {
                mission_id: "m-2".into(),
            },
            3,
        )
        .expect("cancelled");
    assert_eq!(view(&c).map(|v| v.status), Some(MissionStatus::Cancelled));
    assert_eq!(e.plan("p-3").map(|r| r.status), Some(PlanStatus::Cancelled));
    assert!(e.queue.is_empty(), "the mission left the queue");
    assert!(matches!(
        e.handle(
            Event::MissionCancelRequested {
                mission_id: "m-2".into()
            },
            4
        ),
        Err(EngineError::MissionState { .. })
    ));
    // A mission cancelled while planning: the job's end changes nothing.
    let (mut e, job) = {
        let mut e = engine(1, 4);
        let c = e
            .handle(
                Event::MissionRequested {
                    request: mission_request(),
                },
                1,
            )
            .expect("ok");
        (e, mission_job(&c).expect("started"))
    };
    let c = e
        .handle(
            Event::MissionCancelRequested {
                mission_id: "m-1".into(),
            },
            2,
        )
        .expect("cancelled");
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::CancelJob { plan_id } if plan_id == "m-1"))
    );
    let fleet = run_mission_job(&job).expect("plans");
    e.handle(
        Event::MissionFinished {
            mission_id: "m-1".into(),
            outcome: planned_outcome(&job, &fleet, 1.0),
        },
        3,
    )
    .expect("late end");
    assert_eq!(e.mission("m-1").map(|m| m.status), Some(MissionStatus::Cancelled));
    assert_eq!(e.plan("p-2").map(|r| r.status), Some(PlanStatus::Cancelled));
    assert_eq!(e.running(), 0);
}

#[test]
fn an_interrupted_or_restarted_mission_is_planned_again_not_its_plans_alone() {
    let mut e = engine(1, 4);
    e.handle(
        Event::MissionRequested {
            request: mission_request(),
        },
        1,
    )
    .expect("ok");
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome: MissionOutcome::Interrupted,
            },
            2,
        )
        .expect("interrupted");
    // Back in the queue, and with the worker free it starts again at once.
    assert!(mission_job(&c).is_some(), "re-started");
    assert_eq!(e.mission("m-1").map(|m| m.attempts), Some(2));
    // A restart while it plans: the mission is re-queued; its plans wait for it instead of planning alone.
    let Event::MapUploaded { site } = site_event("s") else {
        unreachable!()
    };
    let mut e2 = Engine::new(e.config().clone());
    let c = e2
        .handle(
            Event::Restore {
                sites: vec![site],
                plans: e.plans.values().cloned().collect(),
                active: Vec::new(),
                missions: vec![e.mission("m-1").cloned().expect("m")],
                coverage: Vec::new(),
            },
            3,
        )
        .expect("restored");
    assert!(
        !c.iter().any(|c| matches!(c, Command::StartJob(_))),
        "no part planned alone"
    );
    let job = mission_job(&c).expect("the mission is planned again");
    assert_eq!(job.plan_ids, vec!["p-2".to_string(), "p-3".to_string()]);
    assert!(
        e2.mission("m-1")
            .is_some_and(|m| m.warnings.iter().any(|w| w.contains("restart")))
    );
    // New ids continue after the mission's and its plans'.
    e2.handle(
        Event::PlanRequested {
            request: super::tests::request("s"),
        },
        4,
    )
    .expect("plan");
    assert!(e2.plan("p-4").is_some());
}

#[test]
fn a_mission_whose_division_fails_fails_its_plans() {
    let mut e = engine(1, 4);
    e.handle(
        Event::MissionRequested {
            request: mission_request(),
        },
        1,
    )
    .expect("ok");
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome: MissionOutcome::Failed {
                    reason: "robot 1 fits nowhere".into(),
                },
            },
            2,
        )
        .expect("failed");
    let v = view(&c).expect("view");
    assert_eq!(v.status, MissionStatus::Failed);
    assert_eq!(v.error.as_deref(), Some("robot 1 fits nowhere"));
    assert!(v.plans.iter().all(|p| p.status == PlanStatus::Failed));
    assert!(matches!(
        e.handle(
            Event::MissionAssignRequested {
                mission_id: "m-1".into(),
                docs: docs(&e)
            },
            3
        ),
        Err(EngineError::MissionState { .. })
    ));
}

#[test]
fn a_mission_robot_with_a_footprint_is_divided_and_planned_with_it() {
    let mut e = engine(1, 4);
    let mut req = mission_request();
    req.robots[0].radius = 0.0;
    req.robots[0].footprint = Some(vec![[0.12, 0.08], [-0.12, 0.08], [-0.12, -0.08], [0.12, -0.08]]);
    let c = e
        .handle(Event::MissionRequested { request: req.clone() }, 10)
        .expect("accepted");
    // The part's plan request carries the polygon: its watch and corrections check the robot by it.
    let rec = e.plan("p-2").expect("part plan");
    assert!(rec.request.robot.footprint.is_some());
    let job = mission_job(&c).expect("started");
    let fleet = run_mission_job(&job).expect("divides and plans");
    let (_, profile) = &fleet.plans[0];
    assert_eq!(
        profile.metrics.collisions, 0,
        "no footprint overlap: {:?}",
        profile.metrics
    );
    assert!(profile.metrics.coverage_pct > 50.0, "{:?}", profile.metrics);
    // A footprint that is not convex is refused naming the robot.
    let mut bad = req;
    bad.robots[0].footprint = Some(vec![[0.0, 0.0], [0.3, 0.0], [0.05, 0.05], [0.0, 0.3]]);
    let err = e
        .handle(Event::MissionRequested { request: bad }, 30)
        .expect_err("refused");
    assert!(
        err.to_string().contains("robots[0]") && err.to_string().contains("footprint"),
        "{err}"
    );
}
