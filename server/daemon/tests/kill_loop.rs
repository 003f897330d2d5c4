//! kill -9 in a loop (issue 22): a real `shiftd` is killed 15 times at random moments (seeded) while a backend
//! submits plans over HTTP and a robot — its own Zenoh participant — drives an assigned plan, streaming odometry
//! and clouds that break its path, so corrections are produced and published. After every restart: `/readyz`
//! turns ready on the same data dir (the store opens), every plan that got a 202 exists and has not failed,
//! plan ids are never reused, the driven plan's committed version is at least every version the robot was
//! sent (a correction is committed before it is published), a version is never sent twice with different
//! contents, and the robot, applying corrections by version and fetching the path on a gap, holds exactly the
//! daemon's path. At the end every accepted plan is computed (those killed while queued or planning are
//! computed again).

mod common;

#[allow(dead_code)]
#[path = "../../../tests/src/path.rs"]
mod path;

use std::collections::{BTreeMap, HashSet};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail, ensure};
use serde_json::{Value, json};
use shift_proto::{CorrectionDoc, PlanDocument};

use common::{Daemon, Robot, free_port, stretch_after};

const KILLS: usize = 15;
const SEED: u64 = 0x5eed_0022;
const CONFIG: &str =
    "[zenoh]\nknown_tolerance_m = 0.0\n[jobs]\nworkers = 1\nqueue_capacity = 256\nshutdown_grace_s = 0\n";

/// splitmix64: the kill moments and the robot's positions, reproducible from [`SEED`].
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// What the robot holds of its plan, and every correction it was sent.
struct Follower {
    plan_id: String,
    doc: PlanDocument,
    sent: BTreeMap<u64, CorrectionDoc>,
    gaps: usize,
}

impl Follower {
    /// Takes a correction as a robot does: applied when it follows the version held, ignored when stale, and
    /// a fetch of the whole path on a gap.
    async fn take(&mut self, daemon: &Daemon, c: CorrectionDoc) -> Result<()> {
        ensure!(c.plan_id == self.plan_id, "a correction of another plan: {}", c.plan_id);
        ensure!(
            c.version == c.base_version + 1,
            "version {} on base {}",
            c.version,
            c.base_version
        );
        if let Some(before) = self.sent.get(&c.version) {
            ensure!(
                before == &c,
                "version {} was sent twice with different contents (published before it was committed?)",
                c.version
            );
        }
        self.sent.insert(c.version, c.clone());
        if c.base_version == self.doc.version {
            self.doc = c.apply(&self.doc).map_err(|e| anyhow!("{e}"))?;
        } else if c.version > self.doc.version {
            self.gaps += 1;
            self.fetch(daemon).await?;
            ensure!(
                self.doc.version >= c.version,
                "fetched {} after being sent {}",
                self.doc.version,
                c.version
            );
        }
        Ok(())
    }

    async fn fetch(&mut self, daemon: &Daemon) -> Result<()> {
        let (code, doc) = daemon.get(&format!("/v1/plans/{}/path", self.plan_id)).await?;
        ensure!(code == 200, "path: {code} {doc}");
        self.doc = serde_json::from_value(doc)?;
        Ok(())
    }
}

async fn wait_status(daemon: &Daemon, id: &str, wanted: &[&str], within: Duration) -> Result<Value> {
    let end = Instant::now() + within;
    loop {
        let (code, st) = daemon.get(&format!("/v1/plans/{id}")).await?;
        ensure!(code == 200, "plan {id}: {code} {st}");
        if wanted.iter().any(|w| st["status"] == *w) {
            return Ok(st);
        }
        ensure!(st["status"] != "failed", "plan {id} failed: {st}");
        if Instant::now() > end {
            bail!("plan {id} not {wanted:?} after {within:?}: {st}");
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fifteen_kills_lose_no_accepted_plan_and_no_published_correction() -> Result<()> {
    let mut rng = Rng(SEED);
    let dir = tempfile::tempdir()?;
    let (port, zport) = (free_port()?, free_port()?);
    let endpoint = format!("tcp/127.0.0.1:{zport}");
    let mut daemon = Daemon::start(dir.path(), port, &endpoint, CONFIG).await?;
    let mut robot = Robot::join(&endpoint, "r1").await?;
    let request = json!({"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}});

    // The driven plan.
    let (code, acc) = daemon.post("/v1/plans", &request).await?;
    ensure!(code == 202, "{acc}");
    let driven = acc["plan_id"].as_str().context("plan id")?.to_owned();
    wait_status(&daemon, &driven, &["ready"], Duration::from_secs(60)).await?;
    let (code, st) = daemon
        .post(&format!("/v1/plans/{driven}/assign"), &json!({"robot": "r1"}))
        .await?;
    ensure!(code == 200, "{st}");
    let (code, doc) = daemon.get(&format!("/v1/plans/{driven}/path")).await?;
    ensure!(code == 200, "{doc}");
    let mut follower = Follower {
        plan_id: driven.clone(),
        doc: serde_json::from_value(doc)?,
        sent: BTreeMap::new(),
        gaps: 0,
    };
    let total = path::length(&follower.doc.waypoints);
    let mut accepted = vec![driven.clone()];
    let mut ids: HashSet<String> = accepted.iter().cloned().collect();
    let mut stamp = 10_000_000_000i64;
    let started = Instant::now();

    for kill in 0..KILLS {
        let window = Duration::from_millis(1500 + (rng.unit() * 4000.0) as u64);
        let until = Instant::now() + window;
        let mut step = 0usize;
        while Instant::now() < until {
            if step.is_multiple_of(4) {
                let (code, acc) = daemon.post("/v1/plans", &request).await?;
                ensure!(code == 202, "plan refused: {code} {acc}");
                let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
                ensure!(ids.insert(id.clone()), "plan id {id} given out twice");
                accepted.push(id);
            }
            // The robot somewhere along its plan, then something in its way 1.5 m ahead.
            let from = (0.1 + 0.8 * rng.unit()) * total;
            if let Some((x, y, h)) = stretch_after(&follower.doc.waypoints, from, 2.0) {
                for _ in 0..3 {
                    robot.odom(x, y, h, stamp).await?;
                    stamp += 50_000_000;
                }
                robot
                    .cloud(&path::post(x + 1.5 * h.cos(), y + 1.5 * h.sin()), stamp)
                    .await?;
            }
            tokio::time::sleep(Duration::from_millis(150)).await;
            for c in robot.drain_corrections()? {
                follower.take(&daemon, c).await?;
            }
            step += 1;
        }
        daemon.kill9()?;
        tokio::time::sleep(Duration::from_millis(100)).await;
        let in_flight = robot.drain_corrections()?;

        daemon = Daemon::start(dir.path(), port, &endpoint, CONFIG)
            .await
            .with_context(|| format!("restart after kill {}", kill + 1))?;
        robot.leave().await?;
        robot = Robot::join(&endpoint, "r1").await?;
        for c in in_flight {
            follower.take(&daemon, c).await?;
        }
        for id in &accepted {
            let (code, st) = daemon.get(&format!("/v1/plans/{id}")).await?;
            ensure!(
                code == 200,
                "after kill {}: accepted plan {id} is gone ({code} {st})",
                kill + 1
            );
            ensure!(
                st["status"] != "failed",
                "after kill {}: plan {id} failed: {st}",
                kill + 1
            );
        }
        let (_, st) = daemon.get(&format!("/v1/plans/{driven}")).await?;
        ensure!(st["status"] == "active", "after kill {}: {st}", kill + 1);
        let committed = st["version"].as_u64().context("version")?;
        let published = follower.sent.keys().next_back().copied().unwrap_or(1);
        ensure!(
            committed >= published,
            "after kill {}: committed version {committed} behind published {published}",
            kill + 1
        );
        if follower.doc.version != committed {
            follower.gaps += 1;
            follower.fetch(&daemon).await?;
        }
    }
    let killing = started.elapsed();

    for id in &accepted {
        let wanted: &[&str] = if *id == driven { &["active"] } else { &["ready"] };
        wait_status(&daemon, id, wanted, Duration::from_secs(180)).await?;
    }
    let (_, current) = daemon.get(&format!("/v1/plans/{driven}/path")).await?;
    let current: PlanDocument = serde_json::from_value(current)?;
    ensure!(
        follower.doc.version == current.version,
        "robot {} vs daemon {}",
        follower.doc.version,
        current.version
    );
    ensure!(
        follower.doc.waypoints == current.waypoints,
        "the robot's path is not the daemon's"
    );
    ensure!(
        !follower.sent.is_empty(),
        "no correction was ever published: the loop tested nothing of them"
    );
    eprintln!(
        "{KILLS} kills in {:.1} s (seed {SEED:#x}): {} plans accepted, all computed; driven plan at version {}, \
         {} corrections received, {} fetches on a gap",
        killing.as_secs_f64(),
        accepted.len(),
        current.version,
        follower.sent.len(),
        follower.gaps
    );
    robot.leave().await?;
    drop(daemon);
    Ok(())
}
