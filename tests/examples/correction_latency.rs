//! Correction latency on loopback (issue 7's bench): shiftd in-process with a real TCP Zenoh endpoint on
//! 127.0.0.1, one scripted robot driving its plan through an open 24 m × 12 m hall, and `TRIALS` obstacle
//! clusters of varying size (0.05–0.3 m across, 9–400 points) dropped on its path 1.5–2.5 m ahead. For each:
//! cloud published → correction received (wall clock, one process), and the daemon's own check time
//! (`compute_us`: judgment + IKD-SWOpt + verification + re-profiling). Prints one JSON line.
//!
//! Three scenarios, one line each: `default-site` (the hall is `[zenoh] site`, the robot drives from waypoint 0),
//! `own-site` (no default site: the robot's data reaches the hall only because its plan is there) and
//! `reacquired` (own site, and before every obstacle the robot jumps ahead along its plan, so its progress is
//! found again by the whole-plan search each time).
//!
//! `cargo run --release -p shift-tests --example correction_latency [-- TRIALS [SCENARIO]]`

use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use serde_json::json;
use shift_proto::{CorrectionReason, PlanDocument, WaypointDoc};
use shift_tests::fleet::{ScriptedRobot, free_port, room_grid};
use shift_tests::{TestServer, test_config};

/// A tiny seeded generator (xorshift64*), so every run places the same obstacles.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// The point `ahead_m` metres along the path from waypoint `i`, and the index of the segment it is on.
fn ahead(w: &[WaypointDoc], i: usize, ahead_m: f64) -> Option<(f64, f64, usize)> {
    let mut left = ahead_m;
    for k in i..w.len().saturating_sub(1) {
        let l = (w[k + 1].x - w[k].x).hypot(w[k + 1].y - w[k].y);
        if l >= left && l > 0.0 {
            let f = left / l;
            return Some((
                w[k].x + f * (w[k + 1].x - w[k].x),
                w[k].y + f * (w[k + 1].y - w[k].y),
                k,
            ));
        }
        left -= l;
    }
    None
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() -> Result<()> {
    let trials: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(200);
    let only = std::env::args().nth(2);
    for scenario in ["default-site", "own-site", "reacquired"] {
        if only.as_deref().is_none_or(|o| o == scenario) {
            run(scenario, trials).await?;
        }
    }
    Ok(())
}

/// Heading of the path at waypoint `i`, radians.
fn heading(w: &[WaypointDoc], i: usize) -> f64 {
    let j = (i + 1).min(w.len() - 1);
    let i = j.saturating_sub(1);
    (w[j].y - w[i].y).atan2(w[j].x - w[i].x)
}

async fn run(scenario: &str, trials: usize) -> Result<()> {
    let dir = tempfile::tempdir()?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = test_config(dir.path());
    config.zenoh.listen = vec![endpoint.clone()];
    config.zenoh.site = if scenario == "default-site" {
        "hall".into()
    } else {
        String::new()
    };
    let jump = scenario == "reacquired";
    // Old clusters leave the live map after a while, as they would when robots no longer see them.
    config.zenoh.horizon_s = 30;
    config.demo.enabled = false;
    let server = TestServer::start(config).await?;
    let (code, body) = server
        .post("/v1/sites/hall/map", &room_grid(480, 240, 0.05, &[]))
        .await?;
    if code != 201 {
        bail!("map upload: {code} {body}");
    }
    let robot = ScriptedRobot::join(&endpoint, "r1").await?;
    let req = json!({"site": "hall", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}});
    let (_, acc) = server.post("/v1/plans", &req).await?;
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    server
        .wait_plan(&id, Duration::from_secs(600), |s| s == "ready")
        .await?;
    server
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": "r1"}))
        .await?;
    let (_, served) = server.get(&format!("/v1/plans/{id}/path")).await?;
    let mut doc: PlanDocument = serde_json::from_value(served)?;

    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let (mut e2e_ms, mut compute_us) = (Vec::new(), Vec::new());
    let (mut at, mut missed, mut by_reason) = (0usize, 0usize, std::collections::BTreeMap::new());
    // A jump goes beyond the progress window (200 waypoints): the whole-plan search finds the robot.
    let stride = (doc.waypoints.len() / (trials + 1)).max(if jump { 250 } else { 8 });
    for _ in 0..trials {
        // Drive on along the current plan (progress follows the robot waypoint by waypoint).
        let target = (at + stride).min(doc.waypoints.len().saturating_sub(2));
        if !jump {
            for k in (at..=target).step_by(3) {
                let w = doc.waypoints[k];
                robot.odom("r1", w.x, w.y, heading(&doc.waypoints, k)).await?;
            }
        }
        at = target;
        let w = doc.waypoints[at];
        robot.odom("r1", w.x, w.y, heading(&doc.waypoints, at)).await?;
        tokio::time::sleep(Duration::from_millis(20)).await;
        let Some((ox, oy, _)) = ahead(&doc.waypoints, at, 1.5 + rng.unit()) else {
            break;
        };
        // A square cluster 0.05–0.3 m across, 3–20 points a side, 0.1–0.5 m high.
        let side = 0.05 + 0.25 * rng.unit();
        let n = 3 + (17.0 * rng.unit()) as usize;
        let mut pts = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n {
                let (u, v) = (i as f64 / (n - 1) as f64 - 0.5, j as f64 / (n - 1) as f64 - 0.5);
                pts.push([(ox + u * side) as f32, (oy + v * side) as f32, 0.3]);
            }
        }
        let sent = Instant::now();
        robot.cloud("r1", &pts).await?;
        match robot.next_correction(Duration::from_secs(2)).await {
            Ok(c) => {
                e2e_ms.push(sent.elapsed().as_secs_f64() * 1e3);
                compute_us.push(c.compute_us as f64);
                *by_reason.entry(c.reason.as_str()).or_insert(0usize) += 1;
                let len_before = doc.waypoints.len();
                doc = c.apply(&doc).context("the correction applies to the robot's copy")?;
                if at >= c.to {
                    at = at + doc.waypoints.len() - len_before;
                } else if at >= c.from {
                    at = c.from.saturating_sub(1);
                }
                if c.reason == CorrectionReason::Skipped && c.to >= len_before {
                    break; // the rest of the plan was dropped
                }
                // Let the re-check of the corrected window settle before the next obstacle.
                while let Ok(Ok(more)) = tokio::time::timeout(
                    Duration::from_millis(150),
                    robot.next_correction(Duration::from_secs(1)),
                )
                .await
                {
                    doc = more.apply(&doc).context("a follow-up correction applies")?;
                }
            }
            Err(_) => missed += 1,
        }
    }
    e2e_ms.sort_by(f64::total_cmp);
    compute_us.sort_by(f64::total_cmp);
    let reasons: serde_json::Map<String, serde_json::Value> =
        by_reason.iter().map(|(r, n)| ((*r).to_owned(), json!(n))).collect();
    println!(
        "{}",
        json!({
            "scenario": scenario,
            "trials": e2e_ms.len() + missed,
            "corrections": e2e_ms.len(),
            "no_correction_within_2s": missed,
            "by_reason": reasons,
            "cloud_to_correction_ms": {"p50": percentile(&e2e_ms, 0.5), "p99": percentile(&e2e_ms, 0.99),
                                        "max": e2e_ms.last().copied().unwrap_or(f64::NAN)},
            "check_compute_us": {"p50": percentile(&compute_us, 0.5), "p99": percentile(&compute_us, 0.99)},
            "final_version": doc.version,
        })
    );
    robot.session.close().await.map_err(|e| anyhow::anyhow!("{e}"))?;
    server.stop().await
}
