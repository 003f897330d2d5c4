//! Plan load on a 2-core machine (issue 22's bench): shiftd in-process with its default pool (one planning worker
//! per core) and queue, a 24 m × 12 m hall with shelves, and `N` (default 50) plan requests sent at once. A
//! reader meanwhile asks `GET /v1/plans/{id}` back to back while the cores plan; its latencies are what a fleet
//! backend polling status sees under full planning load. Prints one JSON line: requests accepted (202), refused
//! (429, and how many carried `Retry-After`), status reads and their p50/p99/max, how long the queue took.
//!
//! `cargo run --release -p shift-tests --example plan_load [-- N]`

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use serde_json::{Value, json};
use shift_tests::fleet::room_grid;
use shift_tests::{TestServer, test_config};

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[(((sorted.len() - 1) as f64 * q).round() as usize).min(sorted.len() - 1)]
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() -> Result<()> {
    let n: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(50);
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    let defaults = shiftd::Config::default();
    config.jobs.workers = defaults.jobs.workers;
    config.jobs.queue_capacity = defaults.jobs.queue_capacity;
    config.demo.enabled = false;
    let server = Arc::new(TestServer::start(config).await?);
    // Rows of shelves 1 m deep with 2 m aisles.
    let shelves: Vec<(f64, f64, f64, f64)> = (0..4)
        .map(|k| (3.0, 2.0 + 3.0 * f64::from(k), 21.0, 3.0 + 3.0 * f64::from(k)))
        .collect();
    let (code, body) = server
        .post("/v1/sites/hall/map", &room_grid(480, 240, 0.05, &shelves))
        .await?;
    if code != 201 {
        bail!("map upload: {code} {body}");
    }
    let request = json!({"site": "hall", "start": [1.0, 1.0], "robot": {"radius": 0.25, "tool_width": 0.5}});

    // One plan first, so the reader has an id to ask about while the burst plans.
    let (code, first) = server.post("/v1/plans", &request).await?;
    if code != 202 {
        bail!("first plan: {code} {first}");
    }
    let watched = first["plan_id"].as_str().context("plan id")?.to_owned();
    let stop = Arc::new(AtomicBool::new(false));
    let reader = tokio::spawn({
        let (server, stop, url) = (server.clone(), stop.clone(), format!("/v1/plans/{watched}"));
        async move {
            let mut ms = Vec::new();
            while !stop.load(Ordering::Relaxed) {
                let t = Instant::now();
                let (code, _) = server.get(&url).await?;
                ms.push(t.elapsed().as_secs_f64() * 1e3);
                if code != 200 {
                    bail!("status read: {code}");
                }
            }
            anyhow::Ok(ms)
        }
    });

    let started = Instant::now();
    let calls = (0..n).map(|_| {
        let (http, url, body) = (server.http.clone(), server.url("/v1/plans"), request.clone());
        async move {
            let r = http.post(url).json(&body).send().await?;
            let status = r.status().as_u16();
            let retry = r.headers().contains_key("retry-after");
            let body: Value = r.json().await?;
            anyhow::Ok((status, retry, body["plan_id"].as_str().map(str::to_owned)))
        }
    });
    let answers = futures_util::future::try_join_all(calls).await?;
    let burst_s = started.elapsed().as_secs_f64();
    let accepted: Vec<String> = answers
        .iter()
        .filter_map(|(s, _, id)| (*s == 202).then(|| id.clone()).flatten())
        .collect();
    let refused = answers.iter().filter(|(s, _, _)| *s == 429).count();
    let refused_with_retry = answers.iter().filter(|(s, r, _)| *s == 429 && *r).count();
    for id in accepted.iter().chain(std::iter::once(&watched)) {
        server
            .wait_plan(id, Duration::from_secs(1800), |s| s == "ready")
            .await?;
    }
    let drained_s = started.elapsed().as_secs_f64();
    stop.store(true, Ordering::Relaxed);
    let mut ms = reader.await??;
    ms.sort_by(f64::total_cmp);
    println!(
        "{}",
        json!({
            "requests": n,
            "accepted": accepted.len(),
            "refused_429": refused,
            "refused_with_retry_after": refused_with_retry,
            "other": n - accepted.len() - refused,
            "burst_s": (burst_s * 1e3).round() / 1e3,
            "queue_drained_s": (drained_s * 10.0).round() / 10.0,
            "workers": shiftd::Config::default().jobs.effective_workers(),
            "status_reads": ms.len(),
            "status_p50_ms": (percentile(&ms, 0.5) * 1e3).round() / 1e3,
            "status_p99_ms": (percentile(&ms, 0.99) * 1e3).round() / 1e3,
            "status_max_ms": (ms.last().copied().unwrap_or(f64::NAN) * 1e3).round() / 1e3,
        })
    );
    Ok(())
}
