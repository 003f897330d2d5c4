//! Cloud ingest on loopback (DESIGN §7: ≥ 1 M points/s sustained, no drops at that rate).
//!
//! Starts shiftd in-process with a real loopback TCP Zenoh endpoint and a 100 m × 100 m site, then two robot
//! sessions publish CDR PointCloud2 (map frame, 30 k points each: rays from the robot onto the walls of a
//! building of 10 m rooms, 0.1–1.9 m high) while driving:
//!
//! 1. the rate phase: 10 Hz each for `--seconds` (default 20);
//! 2. the max-rate phase: as fast as each publisher can put (congestion control `Block`) for `--max-seconds`
//!    (default 10), to find the ceiling.
//!
//! Latency = the cloud's header stamp (the wall clock at publish) to the points being in the live map, from
//! the ingest thread's `shift_ingest_stamp_age_seconds` histogram (and `shift_ingest_latency_seconds`: arrival
//! at the daemon to in the map), read from /metrics before and after each phase; quantiles are interpolated
//! inside the histogram's buckets. Prints a table and one JSON line.
//!
//! `cargo run --release -p shift-tests --example ingest_bench -- [--seconds 20] [--max-seconds 10] [--points 30000]`

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Result, anyhow, bail};
use clap::Parser;
use serde_json::json;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_proto::ros::{Header, Time};
use shift_tests::bench::{Rng, Rooms, Scrape, quantile, restamp, wall_ns};
use shift_tests::fleet::{free_port, robot_session};
use shift_tests::{TestServer, test_config};
use zenoh::bytes::Encoding;
use zenoh::qos::CongestionControl;

/// Side of the bench site, metres.
const SITE_M: f64 = 100.0;
/// Room size of the walls' grid, metres.
const ROOM_M: f64 = 10.0;
/// The building the clouds see.
const ROOMS: Rooms = Rooms {
    site_m: SITE_M,
    room_m: ROOM_M,
};

/// Cloud ingest on loopback; see the module docs.
#[derive(Parser)]
struct Args {
    /// Seconds of the rate phase.
    #[arg(long, default_value_t = 20)]
    seconds: u64,
    /// Seconds of the max-rate phase.
    #[arg(long, default_value_t = 10)]
    max_seconds: u64,
    /// Points per cloud.
    #[arg(long, default_value_t = 30_000)]
    points: usize,
    /// Cloud rate per robot in the rate phase, Hz.
    #[arg(long, default_value_t = 10.0)]
    hz: f64,
}

/// The robot's position at `t` seconds: r1 along the rooms' middle row, r2 along the middle column, 1 m/s.
fn position(robot: usize, t: f64) -> (f64, f64) {
    let s = 5.0 + (t % 90.0);
    if robot == 0 { (s, 45.0 + 2.5) } else { (52.5, s) }
}

struct Phase {
    name: &'static str,
    seconds: f64,
    published_clouds: u64,
    ingested_clouds: f64,
    ingested_points: f64,
    dropped_queue: f64,
    dropped_other: f64,
    work_s: f64,
    lat: [Option<f64>; 2],
    arrive: [Option<f64>; 2],
}

impl Phase {
    fn points_per_s(&self) -> f64 {
        self.ingested_points / self.seconds
    }

    fn json(&self) -> serde_json::Value {
        let ms = |v: Option<f64>| v.map(|s| (s * 1e5).round() / 1e2);
        json!({
            "phase": self.name,
            "seconds": (self.seconds * 100.0).round() / 100.0,
            "published_clouds": self.published_clouds,
            "ingested_clouds": self.ingested_clouds,
            "points_per_s": self.points_per_s().round(),
            "dropped_queue_full": self.dropped_queue,
            "dropped_other": self.dropped_other,
            "transport_lost": self.published_clouds as f64 - self.ingested_clouds - self.dropped_queue - self.dropped_other,
            "ingest_busy_fraction": (self.work_s / self.seconds * 1000.0).round() / 1000.0,
            "points_per_busy_s": if self.work_s > 0.0 { (self.ingested_points / self.work_s).round() } else { 0.0 },
            "publish_to_map_ms": {"p50": ms(self.lat[0]), "p99": ms(self.lat[1])},
            "arrival_to_map_ms": {"p50": ms(self.arrive[0]), "p99": ms(self.arrive[1])},
        })
    }
}

/// Runs the publishers for `seconds`: at `hz` each, or (None) as fast as they can, and measures the phase.
async fn phase(
    name: &'static str,
    server: &TestServer,
    publishers: &[Arc<zenoh::pubsub::Publisher<'static>>],
    clouds: &[Vec<Vec<u8>>],
    seconds: u64,
    hz: Option<f64>,
) -> Result<Phase> {
    let before = Scrape::take(server).await?;
    let published = Arc::new(AtomicU64::new(0));
    let start = Instant::now();
    let end = start + Duration::from_secs(seconds);
    let mut tasks = Vec::new();
    for (r, publisher) in publishers.iter().enumerate() {
        let (publisher, mut set, published) = (publisher.clone(), clouds[r].clone(), published.clone());
        tasks.push(tokio::spawn(async move {
            let mut tick = hz.map(|hz| tokio::time::interval(Duration::from_secs_f64(1.0 / hz)));
            let mut i = 0usize;
            while Instant::now() < end {
                if let Some(t) = tick.as_mut() {
                    t.tick().await;
                }
                let k = i % set.len();
                restamp(&mut set[k], wall_ns());
                if publisher.put(set[k].clone()).await.is_err() {
                    break;
                }
                published.fetch_add(1, Ordering::Relaxed);
                i += 1;
                if hz.is_none() {
                    tokio::task::yield_now().await;
                }
            }
        }));
    }
    for t in tasks {
        t.await?;
    }
    let sent = published.load(Ordering::Relaxed);
    // Let the queues drain (each holds at most a few clouds).
    let drain_until = Instant::now() + Duration::from_secs(10);
    let mut last = -1.0;
    loop {
        tokio::time::sleep(Duration::from_millis(200)).await;
        let s = Scrape::take(server).await?;
        let n = s.get("shift_ingest_clouds_total{stream=\"cloud\"}");
        if n == last || Instant::now() > drain_until {
            break;
        }
        last = n;
    }
    let seconds = start.elapsed().as_secs_f64().min(seconds as f64 + 0.5).max(1e-3);
    let after = Scrape::take(server).await?;
    let d = |k: &str| after.get(k) - before.get(k);
    let dropped_all: f64 = after
        .values
        .iter()
        .filter(|(k, _)| k.starts_with("shift_ingest_dropped_total{") && k.contains("stream=\"cloud\""))
        .map(|(k, v)| v - before.get(k))
        .sum();
    let dropped_queue = d("shift_ingest_dropped_total{reason=\"queue_full\",stream=\"cloud\"}");
    let q = |name: &str, p: f64| quantile(&before, &after, name, p);
    Ok(Phase {
        name,
        seconds,
        published_clouds: sent,
        ingested_clouds: d("shift_ingest_clouds_total{stream=\"cloud\"}"),
        ingested_points: d("shift_ingest_points_total{stream=\"cloud\"}"),
        dropped_queue,
        dropped_other: dropped_all - dropped_queue,
        work_s: d("shift_ingest_work_seconds_sum"),
        lat: [
            q("shift_ingest_stamp_age_seconds", 0.5),
            q("shift_ingest_stamp_age_seconds", 0.99),
        ],
        arrive: [
            q("shift_ingest_latency_seconds", 0.5),
            q("shift_ingest_latency_seconds", 0.99),
        ],
    })
}

#[tokio::main(flavor = "multi_thread")]
async fn main() -> Result<()> {
    let args = Args::parse();
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::new("warn"))
        .try_init();
    let dir = tempfile::tempdir()?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = test_config(dir.path());
    config.zenoh.listen = vec![endpoint.clone()];
    config.zenoh.site = "bench".into();
    config.demo.enabled = false;
    let server = TestServer::start(config).await?;

    // A 100 m × 100 m free site at 0.1 m.
    let n = (SITE_M / 0.1) as usize;
    let grid = json!({"resolution": 0.1, "origin": [0.0, 0.0], "width": n, "height": n, "cells": vec![0; n * n]});
    let (code, body) = server.post("/v1/sites/bench/map", &grid).await?;
    if code != 201 {
        bail!("site upload: {code} {body}");
    }

    // Two robots; 50 clouds each along their drive (5 s of driving at 10 Hz), stamped again at every put.
    let mut publishers = Vec::new();
    let mut clouds = Vec::new();
    let mut sessions = Vec::new();
    let mut rng = Rng(0x5eed_1234_abcd_ef01);
    for r in 0..2 {
        let session = robot_session(&endpoint).await?;
        let key = format!("shift/default/robots/r{}/cloud", r + 1);
        let publisher = session
            .declare_publisher(key)
            .encoding(Encoding::APPLICATION_CDR)
            .congestion_control(CongestionControl::Block)
            .await
            .map_err(|e| anyhow!("publisher: {e}"))?;
        publishers.push(Arc::new(publisher));
        let set: Vec<Vec<u8>> = (0..50)
            .map(|i| {
                let (x, y) = position(r, i as f64 * 0.1);
                let header = Header {
                    stamp: Time::default(),
                    frame_id: "map".into(),
                };
                encode_point_cloud2_xyz(&header, &ROOMS.cloud(&mut rng, x, y, args.points))
            })
            .collect();
        clouds.push(set);
        sessions.push(session);
    }
    // Subscriptions take a moment to reach the robots' sessions.
    tokio::time::sleep(Duration::from_secs(2)).await;

    let rate = phase("rate", &server, &publishers, &clouds, args.seconds, Some(args.hz)).await?;
    let max = phase("max", &server, &publishers, &clouds, args.max_seconds, None).await?;
    let (_, site) = server.get("/v1/sites/bench").await?;

    println!(
        "{:<6} {:>7} {:>9} {:>9} {:>12} {:>8} {:>8} {:>6} {:>13} {:>10} {:>10} {:>10} {:>10}",
        "phase",
        "secs",
        "published",
        "ingested",
        "points/s",
        "q_drops",
        "lost",
        "busy",
        "points/busy-s",
        "pub→map50",
        "pub→map99",
        "arr→map50",
        "arr→map99"
    );
    let ms = |v: Option<f64>| v.map_or("-".to_owned(), |s| format!("{:.2} ms", s * 1e3));
    for p in [&rate, &max] {
        let j = p.json();
        println!(
            "{:<6} {:>7.1} {:>9} {:>9} {:>12.0} {:>8} {:>8} {:>6.2} {:>13.0} {:>10} {:>10} {:>10} {:>10}",
            p.name,
            p.seconds,
            p.published_clouds,
            p.ingested_clouds,
            p.points_per_s(),
            p.dropped_queue,
            j["transport_lost"],
            p.work_s / p.seconds,
            j["points_per_busy_s"].as_f64().unwrap_or(0.0),
            ms(p.lat[0]),
            ms(p.lat[1]),
            ms(p.arrive[0]),
            ms(p.arrive[1]),
        );
    }
    let summary = json!({
        "points_per_cloud": args.points,
        "robots": 2,
        "hz": args.hz,
        "live_map_points": site["points_in_tree"],
        "phases": [rate.json(), max.json()],
        "budget_points_per_s": 1_000_000,
    });
    println!("{summary}");
    for s in sessions {
        s.close().await.map_err(|e| anyhow!("{e}"))?;
    }
    server.stop().await
}
