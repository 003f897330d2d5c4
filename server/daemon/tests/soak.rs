//! Soak (issue 22): a real `shiftd` runs while a fleet works it — robots, each its own Zenoh participant,
//! drive their plans at 10 Hz odometry with clouds at 2 Hz in which obstacles appear ahead of them (so paths are
//! checked and corrected), a backend asks for a plan every few seconds and hands each new plan to an idle robot (or the next
//! in turn; its old plan settles). Every `SHIFT_SOAK_SAMPLE_S` the daemon's RSS, threads and open files, the
//! store's size, the plans it holds and the live map's points are sampled from outside (`/proc`, the API).
//!
//! After warm-up nothing may keep growing: RSS, threads, open files, the store file; the
//! live map stays within `max_points` and the settled plans held within `retain_plans`.
//!
//! Warm-up lasts the first third of the run, or until the fleet has cycled once (twice as many plans assigned as
//! robots) if that takes longer: the work in hand, hence RSS, grows until every robot is busy, which a slow
//! machine reaches late; the run is
//! extended so that two thirds of its length follow the warm-up.
//!
//! The default is the 3-minute version the test command runs. The 30-minute soak of the closing note is
//! `SHIFT_SOAK_S=1800 SHIFT_SOAK_SAMPLE_S=60 cargo test -p shiftd --test soak -- --nocapture`.

mod common;

#[allow(dead_code)]
#[path = "../../../tests/src/path.rs"]
mod path;

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail, ensure};
use serde_json::json;
use shift_proto::PlanDocument;

use common::{Daemon, Robot, free_port};

const RETAIN: usize = 12;
const MAX_POINTS: u64 = 30_000;

fn env_u64(key: &str, default: u64) -> u64 {
    std::env::var(key).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// One sample of the daemon from outside.
#[derive(Debug, Clone)]
struct Sample {
    at_s: f64,
    rss_kb: u64,
    threads: u64,
    fds: u64,
    store_bytes: u64,
    plans: u64,
    live_points: u64,
    corrections: u64,
    /// Plans held by status, e.g. `active 10, ready 12`.
    statuses: String,
    /// Settled plans held (done, failed, cancelled): what `retain_plans` bounds.
    settled: u64,
    /// Plans being driven.
    active: u64,
}

fn proc_status(pid: u32, field: &str) -> Result<u64> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/status"))?;
    let line = text
        .lines()
        .find(|l| l.starts_with(field))
        .with_context(|| format!("{field} in /proc/{pid}/status"))?;
    Ok(line.split_whitespace().nth(1).context("value")?.parse()?)
}

async fn sample(d: &Daemon, dir: &Path, started: Instant, corrections: u64) -> Result<Sample> {
    let pid = d.pid();
    let (_, plans) = d.get("/v1/plans?limit=500").await?;
    let (_, site) = d.get("/v1/sites/demo").await?;
    let mut by_status = std::collections::BTreeMap::<String, usize>::new();
    for p in plans["items"].as_array().into_iter().flatten() {
        *by_status
            .entry(p["status"].as_str().unwrap_or("?").to_owned())
            .or_default() += 1;
    }
    let statuses = by_status
        .iter()
        .map(|(k, n)| format!("{k} {n}"))
        .collect::<Vec<_>>()
        .join(", ");
    Ok(Sample {
        at_s: started.elapsed().as_secs_f64(),
        rss_kb: proc_status(pid, "VmRSS:")?,
        threads: proc_status(pid, "Threads:")?,
        fds: std::fs::read_dir(format!("/proc/{pid}/fd"))?.count() as u64,
        store_bytes: std::fs::metadata(dir.join("data").join("shift.redb"))?.len(),
        plans: plans["items"].as_array().map_or(0, Vec::len) as u64,
        live_points: site["points_in_tree"].as_u64().unwrap_or(0),
        corrections,
        statuses,
        settled: ["done", "failed", "cancelled"]
            .iter()
            .map(|k| by_status.get(*k).copied().unwrap_or(0) as u64)
            .sum(),
        active: by_status.get("active").copied().unwrap_or(0) as u64,
    })
}

/// A robot and the plan it drives.
struct Driver {
    robot: Robot,
    id: String,
    plan: Option<(String, PlanDocument, f64)>,
    along_m: f64,
}

/// The robot a ready plan goes to: one without a plan, else one whose plan is over (done, or ended otherwise),
/// else the next in turn. A backend keeps its fleet busy, and a soak at steady work keeps the daemon's work in
/// hand, hence its RSS, comparable between warm-up and the end.
async fn idle_first(d: &Daemon, fleet: &[Driver], next_robot: &mut usize) -> Result<usize> {
    for (i, driver) in fleet.iter().enumerate() {
        let Some((plan_id, ..)) = &driver.plan else {
            return Ok(i);
        };
        // A finished plan past `retain_plans` is forgotten (404): over too.
        let (code, st) = d.get(&format!("/v1/plans/{plan_id}")).await?;
        ensure!(code == 200 || code == 404, "plan {plan_id}: {code} {st}");
        if st["status"].as_str() != Some("active") {
            return Ok(i);
        }
    }
    *next_robot += 1;
    Ok((*next_robot - 1) % fleet.len())
}

async fn fetch_path(d: &Daemon, plan_id: &str) -> Result<PlanDocument> {
    let (code, doc) = d.get(&format!("/v1/plans/{plan_id}/path")).await?;
    ensure!(code == 200, "path of {plan_id}: {code} {doc}");
    Ok(serde_json::from_value(doc)?)
}

/// The pose `s` metres along the path, with the heading of its segment.
fn pose_at(doc: &PlanDocument, s: f64) -> Option<(f64, f64, f64)> {
    let w = &doc.waypoints;
    let mut acc = 0.0;
    for p in w.windows(2) {
        let len = (p[1].x - p[0].x).hypot(p[1].y - p[0].y);
        if acc + len >= s && len > 1e-9 {
            let t = (s - acc) / len;
            let h = (p[1].y - p[0].y).atan2(p[1].x - p[0].x);
            return Some((p[0].x + t * (p[1].x - p[0].x), p[0].y + t * (p[1].y - p[0].y), h));
        }
        acc += len;
    }
    None
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_working_fleet_leaves_memory_threads_files_and_store_flat() -> Result<()> {
    let duration = Duration::from_secs(env_u64("SHIFT_SOAK_S", 180));
    let sample_every = Duration::from_secs(env_u64("SHIFT_SOAK_SAMPLE_S", 10));
    let robots = env_u64("SHIFT_SOAK_ROBOTS", 10) as usize;
    let plan_every = Duration::from_secs(env_u64("SHIFT_SOAK_PLAN_S", 5));
    let dir = tempfile::tempdir()?;
    let (port, zport) = (free_port()?, free_port()?);
    let endpoint = format!("tcp/127.0.0.1:{zport}");
    let config = format!(
        "[store]\nretain_plans = {RETAIN}\n[zenoh]\nknown_tolerance_m = 0.0\nmax_points = {MAX_POINTS}\n\
         horizon_s = 30\n[jobs]\nworkers = 1\nshutdown_grace_s = 0\n"
    );
    let d = Daemon::start(dir.path(), port, &endpoint, &config).await?;
    let request = json!({"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}});

    let mut fleet = Vec::new();
    for i in 0..robots {
        let id = format!("soak-{i}");
        fleet.push(Driver {
            robot: Robot::join(&endpoint, &id).await?,
            id,
            plan: None,
            along_m: 0.0,
        });
    }
    let mut pending: Vec<String> = Vec::new();
    let mut next_robot = 0usize;
    let mut unit = common::uniform(0x5eed_50a4);
    let started = Instant::now();
    let (mut next_plan, mut next_sample) = (started, started);
    let mut stamp = 10_000_000_000i64;
    let (mut tick, mut corrections, mut plans_made, mut assigned) = (0u64, 0u64, 0u64, 0u64);
    let mut samples: Vec<Sample> = Vec::new();
    let tick_len = Duration::from_millis(100);
    // When the fleet has cycled once (every robot on its second plan, in the mean): at full work from then on.
    let mut full_at: Option<Duration> = None;
    let warm_end = |full_at: Option<Duration>| full_at.map(|f| f.max(duration / 3));
    loop {
        let elapsed = started.elapsed();
        match warm_end(full_at) {
            Some(w) if elapsed >= w + duration * 2 / 3 => break,
            None => ensure!(
                elapsed < duration * 3,
                "the fleet never came to full work: {assigned} of {robots} robots got a plan in {elapsed:?}"
            ),
            _ => {}
        }
        let tick_start = Instant::now();
        if tick_start >= next_plan {
            next_plan += plan_every;
            let (code, acc) = d.post("/v1/plans", &request).await?;
            ensure!(code == 202, "plan refused: {code} {acc}");
            pending.push(acc["plan_id"].as_str().context("plan id")?.to_owned());
            plans_made += 1;
        }
        // Ready plans go to the next robot in turn; its previous plan settles.
        let mut still = Vec::new();
        for id in std::mem::take(&mut pending) {
            let (code, st) = d.get(&format!("/v1/plans/{id}")).await?;
            ensure!(code == 200, "plan {id}: {code} {st}");
            match st["status"].as_str() {
                Some("ready") => {
                    let pick = idle_first(&d, &fleet, &mut next_robot).await?;
                    let driver = &mut fleet[pick];
                    let (code, st) = d
                        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": driver.id}))
                        .await?;
                    ensure!(code == 200, "assign {id}: {code} {st}");
                    let doc = fetch_path(&d, &id).await?;
                    let total = path::length(&doc.waypoints);
                    driver.plan = Some((id, doc, total));
                    driver.along_m = 0.0;
                    assigned += 1;
                    if assigned == 2 * robots as u64 {
                        full_at = Some(started.elapsed());
                    }
                }
                Some("failed") => bail!("plan {id} failed: {st}"),
                _ => still.push(id),
            }
        }
        pending = still;
        // Odometry at 10 Hz (0.5 m/s along the plan), clouds at 2 Hz with an obstacle ahead now and then.
        for driver in &mut fleet {
            let Some((plan_id, doc, total)) = &driver.plan else {
                continue;
            };
            driver.along_m = (driver.along_m + 0.05) % total.max(1.0);
            let Some((x, y, h)) = pose_at(doc, driver.along_m) else {
                continue;
            };
            driver.robot.odom(x, y, h, stamp).await?;
            if tick.is_multiple_of(5) {
                let points = if unit() < 0.3 {
                    path::post(x + 1.5 * h.cos(), y + 1.5 * h.sin())
                } else {
                    Vec::new()
                };
                driver.robot.cloud(&points, stamp).await?;
            }
            let got = driver.robot.drain_corrections()?;
            if !got.is_empty() {
                corrections += got.len() as u64;
                let plan_id = plan_id.clone();
                let doc = fetch_path(&d, &plan_id).await?;
                let total = path::length(&doc.waypoints);
                driver.plan = Some((plan_id, doc, total));
            }
        }
        stamp += 100_000_000;
        tick += 1;
        if tick_start >= next_sample {
            next_sample += sample_every;
            let s = sample(&d, dir.path(), started, corrections).await?;
            eprintln!(
                "soak t={:>5.0}s rss={:>7} kB threads={:>3} fds={:>3} store={:>9} B plans={:>3} live_points={:>6} \
                 corrections={} ({})",
                s.at_s, s.rss_kb, s.threads, s.fds, s.store_bytes, s.plans, s.live_points, s.corrections, s.statuses
            );
            samples.push(s);
        }
        if let Some(rest) = tick_len.checked_sub(tick_start.elapsed()) {
            tokio::time::sleep(rest).await;
        }
    }
    samples.push(sample(&d, dir.path(), started, corrections).await?);
    eprintln!("soak: plans held at the end: {}", samples[samples.len() - 1].statuses);
    for driver in fleet {
        driver.robot.leave().await?;
    }

    let warm_s = warm_end(full_at).context("full work")?.as_secs_f64();
    let warm = samples
        .iter()
        .position(|s| s.at_s >= warm_s)
        .context("samples after warm-up")?;
    let (after, last) = (&samples[warm], &samples[samples.len() - 1]);
    let max_after = |f: fn(&Sample) -> u64| samples[warm..].iter().map(f).max().unwrap_or(0);
    // RSS follows the work in hand (jemalloc hands freed pages back within seconds) and the fleet's work comes in
    // waves (robots finish their plans and wait for the next), so one sample says little. Flat means: the median
    // RSS of the last third is not above the highest RSS of the warm-up by more than the bound. A leak raises
    // the median; a wave of work raises single samples.
    // The short run compares against the highest RSS before the last third (warm-up and middle third): its
    // fleet's work in hand still swings by half (4 to 10 plans driven at once; one CI-like run had 4-6 in
    // warm-up and 8-10 in the last third, +33 %, and the next run -41 %), and the middle third has seen such a
    // wave when the daemon is sound. A gross leak still outgrows it.
    let long = duration.as_secs() >= 1200;
    let tail_from = samples.len() - samples.len().div_ceil(3);
    let reference_end = if long { warm + 1 } else { tail_from.max(warm + 1) };
    let warm_peak = samples[..reference_end]
        .iter()
        .map(|s| s.rss_kb)
        .max()
        .unwrap_or(after.rss_kb);
    let mut tail: Vec<u64> = samples[tail_from..].iter().map(|s| s.rss_kb).collect();
    tail.sort_unstable();
    let tail_median = tail[tail.len() / 2];
    let growth = tail_median as f64 / warm_peak as f64;
    eprintln!(
        "soak: {:.0} s, {robots} robots, {plans_made} plans asked, {assigned} assigned, {corrections} corrections; \
         RSS {} kB at most before the last third (warm-up to {:.0} s) → median {} kB over the last third ({:+.1} %), {} kB at most \
         after warm-up, {} kB at the end; threads {} → {}; fds {} → {}; store {} → {} B",
        last.at_s,
        warm_peak,
        after.at_s,
        tail_median,
        (growth - 1.0) * 100.0,
        max_after(|s| s.rss_kb),
        last.rss_kb,
        after.threads,
        last.threads,
        after.fds,
        last.fds,
        after.store_bytes,
        last.store_bytes
    );
    ensure!(
        assigned >= robots as u64,
        "every robot drove a plan ({assigned} assigned)"
    );
    ensure!(
        corrections > 0,
        "obstacles appeared ahead but no correction came: the soak tested no watch"
    );
    ensure!(
        plans_made as usize > RETAIN,
        "too few plans to test retention ({plans_made})"
    );
    // Bounds by configuration.
    for s in &samples {
        ensure!(s.live_points <= MAX_POINTS, "live map over max_points: {s:?}");
        // Settled plans are what retention forgets; queued ones are the backend's asking outpacing the planner
        // (load, not a leak), ready ones were dropped by a robot given a newer plan (the backend's to cancel).
        // Retention runs when a plan is accepted, so between two acceptances every plan then driven may end:
        // up to one per robot over the bound until the next plan comes.
        ensure!(
            s.settled as usize <= RETAIN + robots,
            "settled plans held beyond retain_plans (+ one per robot since the last plan): {s:?}"
        );
        ensure!(s.active as usize <= robots, "more plans driven than robots: {s:?}");
    }
    // Flat after warm-up.
    // Issue 22's bar is 5 % over 30 minutes. Three minutes cannot tell a slow leak from a fleet whose work in
    // hand is still settling (corrections pile up on the plans being driven until they end), so the short run
    // the test command holds catches gross leaks only: 25 % of RSS, two doublings of the store. Keeping a
    // plan's document per correction (hundreds of corrections of ~100 kB) would fail both; the 30-minute run
    // holds the bar.
    let bound = if long { 1.05 } else { 1.25 };
    ensure!(
        growth <= bound,
        "RSS grew {:.1} % after warm-up (median of the last third against the peak before it; the warm-up's in the long run)",
        (growth - 1.0) * 100.0
    );
    ensure!(
        last.fds <= after.fds + 4,
        "open files grew after warm-up: {} → {}",
        after.fds,
        last.fds
    );
    ensure!(
        max_after(|s| s.threads)
            <= after
                .threads
                .max(samples[..warm].iter().map(|s| s.threads).max().unwrap_or(0))
                + 8,
        "threads grew after warm-up"
    );
    // redb's file grows in steps and shrinks when its tail frees (30 minutes: 6 → 25 → 9 → 17 MB; a 3-minute
    // run once doubled 25 → 50 MB just after warm-up): bounded means at most one doubling past the largest size
    // of the warm-up (two for the short run), with 1 MiB of slack. A leak keeps growing.
    let warm_store = samples[..=warm].iter().map(|s| s.store_bytes).max().unwrap_or(0);
    let growths = if long { 2 } else { 4 };
    ensure!(
        max_after(|s| s.store_bytes) <= growths * warm_store + 1_048_576,
        "store grew after warm-up: at most {warm_store} B in warm-up, {} B after",
        max_after(|s| s.store_bytes)
    );
    Ok(())
}
