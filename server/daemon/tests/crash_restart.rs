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
