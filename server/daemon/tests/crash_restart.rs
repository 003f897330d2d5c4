//! kill -9 of a real `shiftd` process while a robot drives its plan: after the restart the robot (a separate
//! Zenoh participant) keeps publishing, its progress is recovered from its first odometry message, and a new
//! obstacle still gets a correction based on the last committed version.
//!
//! This test lives in the daemon's package because it needs the `shiftd` binary (`CARGO_BIN_EXE_shiftd`) to kill;
//! its HTTP helper is deliberately tiny, the plan geometry is the end-to-end tests' own (`tests/src/path.rs`).

mod common;

/// The end-to-end tests' plan geometry (`tests/src/path.rs`), shared by path: this package cannot depend on
/// `shift-tests`, which depends on it.
#[allow(dead_code)]
#[path = "../../../tests/src/path.rs"]
mod path;

use std::time::Duration;

use anyhow::{Context, Result, anyhow};
use serde_json::{Value, json};
use shift_proto::PlanDocument;

use common::{Daemon, Robot, free_port, stretch_after};

const LONG: Duration = Duration::from_secs(120);
const CONFIG: &str = "[zenoh]\nknown_tolerance_m = 0.0\n[jobs]\nworkers = 1\nshutdown_grace_s = 0\n";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_kill_9_progress_is_recovered_and_corrections_continue_from_the_committed_version() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (port, zport) = (free_port()?, free_port()?);
    let endpoint = format!("tcp/127.0.0.1:{zport}");
    let daemon = Daemon::start(dir.path(), port, &endpoint, CONFIG).await?;
    let robot = Robot::join(&endpoint, "r1").await?;
    let req = json!({"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}});
    let (code, acc) = daemon.post("/v1/plans", &req).await?;
    assert_eq!(code, 202, "{acc}");
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    for _ in 0..2400 {
        let (_, st) = daemon.get(&format!("/v1/plans/{id}")).await?;
        if st["status"] == "ready" {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let (code, st) = daemon
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": "r1"}))
        .await?;
    assert_eq!(code, 200, "{st}");
    let (_, doc) = daemon.get(&format!("/v1/plans/{id}/path")).await?;
    let doc: PlanDocument = serde_json::from_value(doc)?;
    let total: f64 = doc
        .waypoints
        .windows(2)
        .map(|p| (p[1].x - p[0].x).hypot(p[1].y - p[0].y))
        .sum();

    // Mid-plan: the robot at 30 % of its plan, an obstacle 1.5 m ahead, a correction.
    let (x, y, h) = stretch_after(&doc.waypoints, 0.3 * total, 2.5).context("a stretch after 30 %")?;
    let mut t = 10_000_000_000i64;
    for _ in 0..3 {
        robot.odom(x, y, h, t).await?;
        t += 50_000_000;
        tokio::time::sleep(Duration::from_millis(30)).await;
    }
    robot
        .cloud(&path::post(x + 1.5 * h.cos(), y + 1.5 * h.sin()), t)
        .await?;
    let first = robot.next_correction(LONG).await?;
    assert_eq!(first.base_version, 1);
    // Let the daemon settle, then read what it committed.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let (_, before) = daemon.get(&format!("/v1/plans/{id}")).await?;
    let committed = before["version"].as_u64().context("version")?;
    assert!(committed >= 2, "{before}");
    daemon.kill9()?;

    // Restart on the same data dir; the robot (re)joins and keeps publishing, further along.
    let daemon = Daemon::start(dir.path(), port, &endpoint, CONFIG).await?;
    robot.leave().await?;
    let robot = Robot::join(&endpoint, "r1").await?;
    let (_, after) = daemon.get(&format!("/v1/plans/{id}")).await?;
    assert_eq!(after["status"], "active", "{after}");
    assert_eq!(after["version"].as_u64(), Some(committed), "{after}");
    let (_, current) = daemon.get(&format!("/v1/plans/{id}/path")).await?;
    let current: PlanDocument = serde_json::from_value(current)?;
    assert_eq!(current.version, committed);
    let (x, y, h) = stretch_after(&current.waypoints, 0.6 * total, 2.5).context("a stretch after 60 %")?;
    for _ in 0..3 {
        robot.odom(x, y, h, t).await?;
        t += 50_000_000;
        tokio::time::sleep(Duration::from_millis(30)).await;
    }
    let mut recovered = Value::Null;
    for _ in 0..400 {
        let (_, st) = daemon.get(&format!("/v1/plans/{id}")).await?;
        if st["driven_fraction"].as_f64().unwrap_or(0.0) >= 0.55 {
            recovered = st;
            break;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    assert!(
        !recovered.is_null(),
        "progress recovered from the first odometry after the restart"
    );
    let (_, r) = daemon.get("/v1/robots/r1").await?;
    assert_eq!(r["plan_id"].as_str(), Some(id.as_str()), "{r}");
    assert_eq!(r["site"], "demo", "{r}");
    robot
        .cloud(&path::post(x + 1.5 * h.cos(), y + 1.5 * h.sin()), t)
        .await?;
    let c = robot.next_correction(LONG).await?;
    assert_eq!(c.plan_id, id);
    assert_eq!(c.base_version, committed, "based on the last committed version");
    assert_eq!(c.version, committed + 1);
    c.apply(&current).map_err(|e| anyhow!("{e}"))?;
    robot.leave().await?;
    drop(daemon);
    Ok(())
}

/// Odometry along `doc` every 0.3 m from 0 to `upto` of its length (stamps from `t`, 20 ms apart), then 1.5 s
/// standing there, still publishing (robots do; the daemon commits what was swept on its own cadence).
async fn drive_part(robot: &Robot, doc: &PlanDocument, upto: f64, t: &mut i64) -> Result<()> {
    let w = &doc.waypoints;
    let total: f64 = w.windows(2).map(|p| (p[1].x - p[0].x).hypot(p[1].y - p[0].y)).sum();
    let (mut s, mut last, mut sent) = (0.0, (w[0].x, w[0].y, 0.0), 0usize);
    'path: for p in w.windows(2) {
        let (a, b) = (p[0], p[1]);
        let len = (b.x - a.x).hypot(b.y - a.y);
        let n = (len / 0.3).ceil().max(1.0) as usize;
        for k in 0..n {
            let f = k as f64 / n as f64;
            if s + f * len > upto * total {
                break 'path;
            }
            last = (
                a.x + (b.x - a.x) * f,
                a.y + (b.y - a.y) * f,
                (b.y - a.y).atan2(b.x - a.x),
            );
            robot.odom(last.0, last.1, last.2, *t).await?;
            *t += 20_000_000;
            sent += 1;
            if sent.is_multiple_of(16) {
                tokio::time::sleep(Duration::from_millis(4)).await;
            }
        }
        s += len;
    }
    for _ in 0..15 {
        robot.odom(last.0, last.1, last.2, *t).await?;
        *t += 100_000_000;
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_kill_9_a_mission_and_what_was_swept_are_restored_and_only_the_rest_is_replanned() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (port, zport) = (free_port()?, free_port()?);
    let endpoint = format!("tcp/127.0.0.1:{zport}");
    let config = format!("{CONFIG}[store]\ncoverage_commit_s = 1\n");
    let daemon = Daemon::start(dir.path(), port, &endpoint, &config).await?;
    let robot = |id: &str, start: [f64; 2]| json!({"id": id, "start": start, "radius": 0.15, "tool_width": 0.3});
    let req = json!({"site": "demo", "robots": [robot("k1", [0.5, 0.5]), robot("k2", [7.5, 7.5])]});
    let (code, acc) = daemon.post("/v1/missions", &req).await?;
    assert_eq!(code, 202, "{acc}");
    let id = acc["mission_id"].as_str().context("mission id")?.to_owned();
    let path = format!("/v1/missions/{id}");
    let mut ready = Value::Null;
    for _ in 0..2400 {
        let (_, m) = daemon.get(&path).await?;
        if m["status"] == "ready" {
            ready = m;
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert_eq!(ready["status"], "ready", "{ready}");
    let robots = [Robot::join(&endpoint, "k1").await?, Robot::join(&endpoint, "k2").await?];
    tokio::time::sleep(Duration::from_millis(300)).await;
    let (code, active) = daemon.post(&format!("{path}/assign"), &json!({})).await?;
    assert_eq!(code, 200, "{active}");
    // Both robots drive half of their parts.
    let mut t = 10_000_000_000i64;
    let mut areas = Vec::new();
    for (r, p) in robots.iter().zip(ready["plans"].as_array().context("plans")?) {
        let pid = p["plan_id"].as_str().context("plan id")?;
        let (_, doc) = daemon.get(&format!("/v1/plans/{pid}/path")).await?;
        let doc: PlanDocument = serde_json::from_value(doc)?;
        areas.push(doc.metrics.coverable_area_m2.context("area")?);
        drive_part(r, &doc, 0.5, &mut t).await?;
    }
    let (_, before) = daemon.get(&path).await?;
    let swept = before["coverage"]["measured_pct"].as_f64().context("measured")?;
    assert!((25.0..75.0).contains(&swept), "half of each part swept: {before}");
    daemon.kill9()?;

    // Restarted: the mission and its raster are back (at most the last second of sweep lost), and the rest is
    // replanned at once, for both robots.
    let daemon = Daemon::start(dir.path(), port, &endpoint, &config).await?;
    let mut after = Value::Null;
    for _ in 0..2400 {
        let (_, m) = daemon.get(&path).await?;
        if m["plans"]
            .as_array()
            .is_some_and(|p| p.iter().all(|p| p["version"].as_u64() >= Some(2)))
        {
            after = m;
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert!(!after.is_null(), "the mission was replanned after the restart");
    let restored = after["coverage"]["measured_pct"].as_f64().context("measured")?;
    assert!(
        restored >= swept - 1.0 && restored <= swept + 1e-9,
        "{restored} % restored of {swept} %"
    );
    assert!(
        after["warnings"].to_string().contains("the daemon restarted"),
        "{after}"
    );
    // Both robots are still there with their plans half driven: their own plans are resumed, not the site
    // divided again.
    assert!(
        after["warnings"].to_string().contains("resumed each robot's plan"),
        "{after}"
    );
    for (p, area) in after["plans"].as_array().context("plans")?.iter().zip(&areas) {
        let pid = p["plan_id"].as_str().context("plan id")?;
        let (_, doc) = daemon.get(&format!("/v1/plans/{pid}/path")).await?;
        let doc: PlanDocument = serde_json::from_value(doc)?;
        let rest = doc.metrics.coverable_area_m2.context("area")?;
        assert!(
            rest < 0.8 * area,
            "{pid}: the replan covers {rest} m² of a {area} m² part"
        );
        assert!(doc.metrics.coverage_pct >= 99.0, "{:?}", doc.metrics);
    }
    for r in robots {
        r.leave().await?;
    }
    drop(daemon);
    Ok(())
}
