//! Replans of a mission's remainder in the engine: a robot lost part-way (its token gone) hands what it had
//! left to the other, who gets a new version of its plan from where it stands; a restart with a mission under
//! way replans it; an explicit replan before the mission is planned is refused.

use shift_proto::{MissionStatus, PlanDocument, PlanStatus};

use super::mission_tests::{mission_job, planned, view};
use super::*;
use crate::EngineError;
use crate::coverage::CoverageKey;
use crate::mission_job::{MissionOutcome, planned_outcome, run_mission_job};
use crate::robots::Pose2;

/// Poses every 0.1 m along `doc` from `from` to `upto` of its length.
fn poses(doc: &PlanDocument, from: f64, upto: f64) -> Vec<Pose2> {
    let total: f64 = doc
        .waypoints
        .windows(2)
        .map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y))
        .sum();
    let (mut s, mut out) = (0.0, Vec::new());
    for pair in doc.waypoints.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let len = (b.x - a.x).hypot(b.y - a.y);
        let n = (len / 0.1).ceil().max(1.0) as usize;
        for k in 0..=n {
            let at = s + k as f64 / n as f64 * len;
            if at >= from * total && at <= upto * total {
                let f = k as f64 / n as f64;
                out.push(Pose2 {
                    x: a.x + (b.x - a.x) * f,
                    y: a.y + (b.y - a.y) * f,
                    yaw: (b.y - a.y).atan2(b.x - a.x),
                    stamp_ns: 0,
                });
            }
        }
        s += len;
    }
    out
}

/// Odometry of several robots at once, a pose of each every 100 ms (a robot whose poses ran out repeats its
/// last: it stands, but it is there); returns the time.
fn drive(e: &mut Engine, robots: &[(&str, Vec<Pose2>)], t0: u64) -> u64 {
    let n = robots.iter().map(|(_, p)| p.len()).max().unwrap_or(0);
    let mut t = t0;
    for k in 0..n {
        t += 100;
        for (robot, p) in robots {
            let Some(pose) = p.get(k).or(p.last()).copied() else {
                continue;
            };
            e.handle(
                Event::RobotPose {
                    robot: (*robot).into(),
                    pose,
                },
                t,
            )
            .expect("pose");
        }
    }
    t
}

fn alive(e: &mut Engine, robot: &str, alive: bool, t: u64) -> Vec<Command> {
    e.handle(
        Event::RobotLiveliness {
            robot: robot.into(),
            alive,
        },
        t,
    )
    .expect("liveliness")
}

fn delivered(cmds: &[Command]) -> Vec<(String, Arc<PlanDocument>)> {
    cmds.iter()
        .filter_map(|c| match c {
            Command::PublishPlan { robot, doc } => Some((robot.clone(), doc.clone())),
            _ => None,
        })
        .collect()
}

/// A planned mission, both robots alive (their tokens) and every plan assigned: the engine and the parts.
fn assigned() -> (Engine, Vec<crate::mission_job::PlannedPart>) {
    let (mut e, job) = planned();
    let fleet = run_mission_job(&job).expect("plans");
    let MissionOutcome::Planned { parts, .. } = planned_outcome(&job, &fleet, 5.0) else {
        unreachable!()
    };
    alive(&mut e, "r1", true, 25);
    alive(&mut e, "r2", true, 25);
    e.handle(
        Event::MissionAssignRequested {
            mission_id: "m-1".into(),
            docs: parts.iter().map(|p| p.doc.clone()).collect(),
        },
        30,
    )
    .expect("assigned");
    (e, parts)
}

#[test]
fn a_robot_lost_part_way_hands_its_rest_to_the_other_who_finishes_the_mission() {
    let (mut e, job) = planned();
    assert!(matches!(
        e.handle(
            Event::MissionReplanRequested {
                mission_id: "m-9".into()
            },
            21
        ),
        Err(EngineError::UnknownMission(_))
    ));
    let fleet = run_mission_job(&job).expect("plans");
    let MissionOutcome::Planned { parts, .. } = planned_outcome(&job, &fleet, 5.0) else {
        unreachable!()
    };
    alive(&mut e, "r1", true, 25);
    alive(&mut e, "r2", true, 25);
    let c = e
        .handle(
            Event::MissionAssignRequested {
                mission_id: "m-1".into(),
                docs: parts.iter().map(|p| p.doc.clone()).collect(),
            },
            30,
        )
        .expect("assigned");
    let docs = delivered(&c);
    // Both drive a third of their parts; then r2's token goes away.
    let t = drive(
        &mut e,
        &[("r1", poses(&docs[0].1, 0.0, 0.3)), ("r2", poses(&docs[1].1, 0.0, 0.3))],
        1_000,
    );
    let before = e
        .missions
        .get("m-1")
        .and_then(|m| m.raster.clone())
        .expect("raster")
        .pct();
    assert!((20.0..60.0).contains(&before), "{before}");
    let c = alive(&mut e, "r2", false, t + 10);
    let job = mission_job(&c).expect("the rest is replanned at once");
    assert_eq!(job.plan_ids, vec!["p-2".to_string()], "only r1 takes part");
    let r1_at = e.robots.get("r1").and_then(|r| r.pose).expect("pose");
    assert_eq!(
        job.request.robots[0].start,
        [r1_at.x, r1_at.y],
        "r1 starts where it stands"
    );
    let covered = job.covered.clone().expect("a replan");
    assert!(covered.iter().filter(|&&c| c).count() > 100);
    assert_eq!(
        e.mission("m-1").map(|m| m.dropped.clone()),
        Some(vec!["r2".to_string()])
    );
    // r1 drives on while it computes; the replan's end gives r1 version 2 from where it stands.
    let t = drive(&mut e, &[("r1", poses(&docs[0].1, 0.3, 0.35))], t + 20);
    assert_eq!(job.lost.len(), 1, "r2's plan goes with the job");
    assert_eq!(job.lost[0].doc.plan_id, "p-3");
    let fleet = run_mission_job(&job).expect("replans the remainder");
    // r1's plan resumed and r2's unfinished lanes handed to it: no new division.
    assert!(
        fleet.division.warnings.iter().any(|w| w.contains("handed over")),
        "{:?}",
        fleet.division.warnings
    );
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome: planned_outcome(&job, &fleet, 5.0),
            },
            t + 10,
        )
        .expect("replanned");
    let got = delivered(&c);
    assert_eq!(got.len(), 1, "{got:?}");
    let (robot, v2) = &got[0];
    assert_eq!((robot.as_str(), v2.plan_id.as_str(), v2.version), ("r1", "p-2", 2));
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::ReplacePlanDoc { record, .. } if record.version == 2))
    );
    let first = v2.waypoints.first().expect("waypoints");
    assert!((first.x - r1_at.x).hypot(first.y - r1_at.y) < 1.0, "v2 starts near r1");
    assert_eq!(
        e.plan("p-3").map(|r| r.status),
        Some(PlanStatus::Cancelled),
        "r2's part went to r1"
    );
    assert_eq!(e.robot("r2").and_then(|r| r.plan_id), None);
    let v = view(&c).expect("view");
    assert_eq!(v.status, MissionStatus::Active);
    assert!(
        v.warnings.iter().any(|w| w.contains("robot r2 lost")),
        "{:?}",
        v.warnings
    );
    // r1 drives version 2 to its end: the mission is done and the remainder was swept.
    let t = drive(&mut e, &[("r1", poses(v2, 0.0, 1.0))], t + 100);
    alive(&mut e, "r1", true, t + 2_000);
    assert_eq!(e.mission("m-1").map(|m| m.status), Some(MissionStatus::Done));
    let after = e.coverage(&CoverageKey::Mission("m-1".into())).expect("raster");
    let pct = e.missions.get("m-1").and_then(|m| m.raster.as_ref()).map(|r| r.pct());
    assert!(pct.is_some_and(|p| p >= 97.0), "{pct:?} {:?}", after.covered.runs.len());
}

#[test]
fn a_restart_with_a_mission_under_way_replans_it_and_a_mission_not_planned_cannot_be() {
    let (mut e, parts) = assigned();
    let t = drive(&mut e, &[("r1", poses(&parts[0].doc, 0.0, 0.5))], 1_000);
    e.handle(Event::Shutdown, t).expect("shutdown");
    let Event::MapUploaded { site } = super::tests::site_event("s") else {
        unreachable!()
    };
    let mut e2 = Engine::new(e.config().clone());
    let c = e2
        .handle(
            Event::Restore {
                sites: vec![site],
                plans: e.plans.values().cloned().collect(),
                active: parts.iter().map(|p| p.doc.clone()).collect(),
                missions: vec![e.mission("m-1").cloned().expect("m")],
                coverage: vec![e.coverage(&CoverageKey::Mission("m-1".into())).expect("raster")],
            },
            t + 100,
        )
        .expect("restored");
    let job = mission_job(&c).expect("replanned after the restart");
    assert_eq!(job.plan_ids.len(), 2);
    assert!(
        job.covered.as_ref().is_some_and(|c| c.iter().any(|&x| x)),
        "from what was swept"
    );
    // r1 starts where its plan says it is (no odometry since the restart), r2 at its dock.
    let on_plan = parts[0]
        .doc
        .waypoints
        .iter()
        .any(|w| [w.x, w.y] == job.request.robots[0].start);
    assert!(on_plan, "{:?}", job.request.robots[0].start);
    // A mission still queued cannot be replanned.
    let mut e3 = super::tests::engine(1, 4);
    e3.handle(
        Event::PlanRequested {
            request: super::tests::request("s"),
        },
        1,
    )
    .expect("busy");
    e3.handle(
        Event::MissionRequested {
            request: super::mission_tests::mission_request(),
        },
        2,
    )
    .expect("queued");
    assert!(matches!(
        e3.handle(
            Event::MissionReplanRequested {
                mission_id: "m-2".into()
            },
            3
        ),
        Err(EngineError::MissionState { .. })
    ));
}

#[test]
fn a_lost_robot_that_comes_back_takes_a_share_again() {
    let (mut e, parts) = assigned();
    let t = drive(
        &mut e,
        &[
            ("r1", poses(&parts[0].doc, 0.0, 0.2)),
            ("r2", poses(&parts[1].doc, 0.0, 0.2)),
        ],
        1_000,
    );
    let c = alive(&mut e, "r2", false, t + 10);
    let job = mission_job(&c).expect("replan without r2");
    let fleet = run_mission_job(&job).expect("replans");
    e.handle(
        Event::MissionFinished {
            mission_id: "m-1".into(),
            outcome: planned_outcome(&job, &fleet, 5.0),
        },
        t + 20,
    )
    .expect("replanned");
    assert_eq!(e.plan("p-3").map(|r| r.status), Some(PlanStatus::Cancelled));
    // r2 is back (its odometry, then its token): a replan for both, and r2 gets its plan's next version.
    e.handle(
        Event::RobotPose {
            robot: "r2".into(),
            pose: Pose2 {
                x: 2.5,
                y: 1.5,
                yaw: 0.0,
                stamp_ns: 0,
            },
        },
        t + 30,
    )
    .expect("pose");
    let c = alive(&mut e, "r2", true, t + 40);
    let job = mission_job(&c).expect("replan with r2 back");
    assert_eq!(job.plan_ids, vec!["p-2".to_string(), "p-3".to_string()]);
    assert_eq!(job.request.robots[1].start, [2.5, 1.5]);
    let fleet = run_mission_job(&job).expect("replans");
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome: planned_outcome(&job, &fleet, 5.0),
            },
            t + 50,
        )
        .expect("replanned");
    let got: Vec<(String, String, u64)> = delivered(&c)
        .into_iter()
        .map(|(r, d)| (r, d.plan_id.clone(), d.version))
        .collect();
    assert_eq!(
        got,
        vec![("r1".into(), "p-2".into(), 3), ("r2".into(), "p-3".into(), 2)]
    );
    assert_eq!(e.plan("p-3").map(|r| r.status), Some(PlanStatus::Active));
    assert_eq!(e.mission("m-1").map(|m| m.dropped.len()), Some(0));
}

#[test]
fn a_robot_that_joins_a_mission_under_way_takes_a_share_of_what_is_left() {
    let (mut e, parts) = assigned();
    let t = drive(
        &mut e,
        &[
            ("r1", poses(&parts[0].doc, 0.0, 0.3)),
            ("r2", poses(&parts[1].doc, 0.0, 0.3)),
        ],
        1_000,
    );
    let joining = |id: &str, start: [f64; 2]| Event::MissionRobotJoined {
        mission_id: "m-1".into(),
        robot: shift_proto::MissionRobot::new(id, start, 0.1, 0.2),
    };
    // Refused, naming the field, nothing kept: a duplicate id, a dock off the map.
    let err = e.handle(joining("r1", [1.5, 1.0]), t).expect_err("duplicate");
    assert!(err.to_string().contains("robots[2].id \"r1\" is named twice"), "{err}");
    let err = e.handle(joining("r3", [9.0, 1.0]), t).expect_err("off the map");
    assert!(err.to_string().contains("robots[2] (r3)"), "{err}");
    assert_eq!(e.mission("m-1").map(|m| m.plan_ids.len()), Some(2));
    let c = e.handle(joining("r3", [1.5, 1.0]), t + 10).expect("joined");
    let job = mission_job(&c).expect("a replan with r3");
    assert_eq!(
        job.plan_ids,
        vec!["p-2".to_string(), "p-3".to_string(), "p-4".to_string()]
    );
    assert_eq!(job.request.robots[2].start, [1.5, 1.0]);
    let fleet = run_mission_job(&job).expect("replans");
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome: planned_outcome(&job, &fleet, 5.0),
            },
            t + 20,
        )
        .expect("replanned");
    let got: Vec<(String, String, u64)> = delivered(&c)
        .into_iter()
        .map(|(r, d)| (r, d.plan_id.clone(), d.version))
        .collect();
    assert_eq!(
        got,
        vec![
            ("r1".into(), "p-2".into(), 2),
            ("r2".into(), "p-3".into(), 2),
            ("r3".into(), "p-4".into(), 1)
        ]
    );
    let v = view(&c).expect("view");
    assert_eq!(v.plans.len(), 3);
    assert!(v.plans[2].area_m2.is_some_and(|a| a > 0.0), "{v:?}");
}

#[test]
fn a_mission_whose_robots_were_all_lost_is_picked_up_by_the_first_back() {
    let (mut e, parts) = assigned();
    let t = drive(
        &mut e,
        &[
            ("r1", poses(&parts[0].doc, 0.0, 0.3)),
            ("r2", poses(&parts[1].doc, 0.0, 0.3)),
        ],
        1_000,
    );
    // Both go, one after the other: the replan the first loss started ends after the second is gone, and the
    // one asked for then finds nobody to plan for.
    let c = alive(&mut e, "r1", false, t + 10);
    let first = mission_job(&c).expect("a replan for r2");
    alive(&mut e, "r2", false, t + 20);
    let fleet = run_mission_job(&first).expect("replans");
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome: planned_outcome(&first, &fleet, 5.0),
            },
            t + 30,
        )
        .expect("replanned");
    assert!(mission_job(&c).is_none(), "nobody left to plan for");
    assert_eq!(e.mission("m-1").map(|m| m.dropped.len()), Some(2));
    assert_eq!(e.mission("m-1").map(|m| m.status), Some(MissionStatus::Failed));
    // r1 comes back: the mission is replanned for it, and it is under way again.
    let c = alive(&mut e, "r1", true, t + 1_000);
    let job = mission_job(&c).expect("replanned for r1");
    assert_eq!(job.plan_ids, vec!["p-2".to_string()]);
    let fleet = run_mission_job(&job).expect("replans");
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome: planned_outcome(&job, &fleet, 5.0),
            },
            t + 1_100,
        )
        .expect("replanned");
    assert_eq!(delivered(&c).len(), 1);
    assert_eq!(e.mission("m-1").map(|m| m.status), Some(MissionStatus::Active));
}

/// A replan asked for with every robot still driving resumes their plans: each gets a version 2 that starts
/// where it stands, continues its own path (no longer than 1.2 × what it had left) and sweeps the regions of
/// version 1, and the rest is still swept to the end.
#[test]
fn a_replan_with_every_robot_driving_resumes_their_plans() {
    let (mut e, parts) = assigned();
    let t = drive(
        &mut e,
        &[
            ("r1", poses(&parts[0].doc, 0.0, 0.5)),
            ("r2", poses(&parts[1].doc, 0.0, 0.5)),
        ],
        1_000,
    );
    let c = e
        .handle(
            Event::MissionReplanRequested {
                mission_id: "m-1".into(),
            },
            t + 10,
        )
        .expect("asked");
    let job = mission_job(&c).expect("a replan job");
    assert!(
        job.previous.iter().all(Option::is_some),
        "both robots drive a plan of the mission"
    );
    let fleet = run_mission_job(&job).expect("replans");
    let outcome = planned_outcome(&job, &fleet, 5.0);
    let MissionOutcome::Planned { parts: v2_parts, .. } = &outcome else {
        unreachable!()
    };
    let length = |w: &[shift_proto::WaypointDoc]| -> f64 {
        w.windows(2).map(|p| (p[1].x - p[0].x).hypot(p[1].y - p[0].y)).sum()
    };
    for (k, (v1, v2)) in parts.iter().zip(v2_parts).enumerate() {
        assert!(
            v2.warnings.iter().any(|w| w.starts_with("resumed")),
            "robot {k}: {:?} {:?} covered {}",
            v2.warnings,
            fleet.division.warnings,
            job.covered.as_ref().map_or(0, |c| c.iter().filter(|&&x| x).count())
        );
        let at = job.request.robots[k].start;
        let first = &v2.doc.waypoints[0];
        assert!(
            (first.x - at[0]).hypot(first.y - at[1]) < 0.5,
            "robot {k} starts where it stands"
        );
        let rest = length(&v1.doc.waypoints) / 2.0;
        let l2 = length(&v2.doc.waypoints);
        assert!(l2 <= 1.2 * rest, "robot {k}: {l2:.1} m against {rest:.1} m left");
        assert_eq!(v2.doc.regions, v1.doc.regions);
    }
    let c = e
        .handle(
            Event::MissionFinished {
                mission_id: "m-1".into(),
                outcome,
            },
            t + 20,
        )
        .expect("replanned");
    let got = delivered(&c);
    assert_eq!(got.len(), 2);
    let t = drive(
        &mut e,
        &[("r1", poses(&got[0].1, 0.0, 1.0)), ("r2", poses(&got[1].1, 0.0, 1.0))],
        t + 100,
    );
    alive(&mut e, "r1", true, t + 2_000);
    let pct = e.missions.get("m-1").and_then(|m| m.raster.as_ref()).map(|r| r.pct());
    assert!(pct.is_some_and(|p| p >= 97.0), "{pct:?}");
    assert_eq!(e.mission("m-1").map(|m| m.status), Some(MissionStatus::Done));
}
