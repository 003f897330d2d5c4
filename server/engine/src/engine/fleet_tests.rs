//! Robots in the engine: where their sensor data goes, blind plans, presence, plans restored to the robots that
//! drove them.

use shift_proto::{PlanStatus, WatchHealth};

use super::tests::{engine, site_event};
use super::watch_tests::{assigned_with, lane_doc};
use super::*;
use crate::robots::Pose2;

fn feeds(cmds: &[Command]) -> Vec<(String, Option<String>)> {
    cmds.iter()
        .filter_map(|c| match c {
            Command::FeedSite { robot, site } => Some((robot.clone(), site.clone())),
            _ => None,
        })
        .collect()
}

fn pose_at(x: f64) -> Event {
    Event::RobotPose {
        robot: "r1".into(),
        pose: Pose2 {
            x,
            y: 0.5,
            yaw: 0.0,
            stamp_ns: 0,
        },
    }
}

fn with_default(site: Option<&str>) -> Engine {
    let mut e = Engine::new(EngineConfig {
        workers: 1,
        queue_capacity: 4,
        default_site: site.map(str::to_owned),
        blind_after_ms: 1_000,
        ..EngineConfig::default()
    });
    e.handle(site_event("s"), 0).expect("site");
    e
}

#[test]
fn assignment_routes_the_robots_data_to_the_plans_site_and_reassignment_moves_it() {
    let (mut e, doc) = assigned_with(with_default(Some("demo")));
    assert_eq!(e.robot("r1").and_then(|r| r.site), Some("s".into()));
    // The plan moves to r2: r1 falls back to the default site, r2 feeds the plan's.
    let c = e
        .handle(
            Event::AssignPlan {
                plan_id: "p-1".into(),
                robot: "r2".into(),
                doc,
            },
            10,
        )
        .expect("reassigned");
    assert_eq!(feeds(&c), vec![("r1".into(), None), ("r2".into(), Some("s".into()))]);
    assert_eq!(e.robot("r1").and_then(|r| r.site), Some("demo".into()));
    assert_eq!(e.robot("r2").and_then(|r| r.site), Some("s".into()));
    // Without a default site an unassigned robot feeds nothing.
    let mut e = with_default(None);
    e.handle(pose_at(0.5), 0).expect("pose");
    assert_eq!(e.robot("r1").and_then(|r| r.site), None);
}

#[test]
fn a_watched_plan_whose_site_gets_no_points_is_blind_until_points_come() {
    let (mut e, _) = assigned_with(with_default(None));
    e.handle(
        Event::RobotLiveliness {
            robot: "r1".into(),
            alive: true,
        },
        3,
    )
    .expect("alive");
    assert_eq!(e.plan("p-1").and_then(|p| p.watch), Some(WatchHealth::Watching));
    e.handle(pose_at(0.5), 500).expect("pose");
    assert_eq!(
        e.plan("p-1").and_then(|p| p.watch),
        Some(WatchHealth::Watching),
        "not yet"
    );
    let c = e.handle(pose_at(0.5), 1_500).expect("pose");
    assert_eq!(e.plan("p-1").and_then(|p| p.watch), Some(WatchHealth::Blind));
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::Publish(PlanEvent::Status(s)) if s.watch == Some(WatchHealth::Blind))),
        "the status change is published"
    );
    e.handle(Event::SiteFed { site: "s".into() }, 1_600).expect("fed");
    assert_eq!(e.plan("p-1").and_then(|p| p.watch), Some(WatchHealth::Watching));
    // A lost robot's plan is not blind (nothing could feed it).
    e.handle(
        Event::RobotLiveliness {
            robot: "r1".into(),
            alive: false,
        },
        5_000,
    )
    .expect("lost");
    e.handle(pose_at(0.5), 9_000).expect("pose");
    assert_eq!(e.plan("p-1").and_then(|p| p.watch), Some(WatchHealth::Watching));
}

#[test]
fn a_lost_robot_keeps_the_time_of_its_last_message() {
    let mut e = engine(1, 4);
    e.handle(pose_at(0.5), 100).expect("pose");
    e.handle(
        Event::RobotLiveliness {
            robot: "r1".into(),
            alive: false,
        },
        9_000,
    )
    .expect("lost");
    let r = e.robot("r1").expect("known");
    assert!(!r.alive);
    assert_eq!(r.last_seen_ms, 100);
}

#[test]
fn a_restart_gives_robots_back_their_plans_at_the_committed_version_and_finds_them_along_it() {
    let (mut e, _) = assigned_with(engine(1, 4));
    e.handle(pose_at(0.9), 3).expect("pose");
    let rec = e.plan("p-1").cloned().expect("plan");
    assert_eq!(rec.status, PlanStatus::Active);
    let Event::MapUploaded { site } = site_event("s") else {
        unreachable!()
    };
    let mut restarted = engine(1, 4);
    let c = restarted
        .handle(
            Event::Restore {
                sites: vec![site],
                plans: vec![rec],
                active: vec![lane_doc()],
                missions: Vec::new(),
                coverage: Vec::new(),
            },
            100,
        )
        .expect("restore");
    assert_eq!(feeds(&c), vec![("r1".into(), Some("s".into()))]);
    assert_eq!(restarted.robot("r1").and_then(|r| r.plan_id), Some("p-1".into()));
    // The robot's first odometry after the restart, at the fourth of six waypoints (x = 1.7), far from the
    // first: progress is found there, and the jump is in the plan's status.
    let mut cfg = restarted.config().clone();
    cfg.progress.window = 1;
    let mut narrow = Engine::new(cfg);
    let Event::MapUploaded { site } = site_event("s") else {
        unreachable!()
    };
    narrow
        .handle(
            Event::Restore {
                sites: vec![site],
                plans: vec![restarted.plan("p-1").cloned().expect("plan")],
                active: vec![lane_doc()],
                missions: Vec::new(),
                coverage: Vec::new(),
            },
            100,
        )
        .expect("restore");
    let c = narrow.handle(pose_at(1.7), 200).expect("pose");
    let rec = narrow.plan("p-1").expect("plan");
    assert!((rec.driven_fraction - 0.6).abs() < 1e-9, "{}", rec.driven_fraction);
    assert_eq!(rec.progress_jumps.len(), 1);
    assert!(!rec.progress_jumps[0].backwards);
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::StartCheck(j) if j.ahead_from == 3)),
        "the window follows the robot at once"
    );
}
