//! Fleet load on loopback (issue 22's figure): N robots (default 30) at 10 Hz odometry and 5 Hz clouds of 30 k
//! points, each driving its own assigned plan, with obstacles dropped ahead of them.
//!
//! Starts shiftd in-process with a real loopback TCP Zenoh endpoint and a 100 m × 100 m site of 10 m rooms
//! (the walls are in the static map, so the wall points robots see are known, not obstacles). Each robot is its
//! own Zenoh session with a liveliness token and a subscription to its corrections; it gets a plan over HTTP
//! (`POST /v1/plans` with a 5 m × 5 m `region` in its room, then `assign`) and drives it at 0.5 m/s:
//!
//! - odometry (CDR nav_msgs/Odometry, map frame, wall-clock stamps) at `--odom-hz`;
//! - clouds (CDR PointCloud2, map frame, `--points` rays onto the room's walls, 0.1–1.9 m high, stamped with
//!   the wall clock at publish) at `--cloud-hz`; a few are encoded once per robot and re-stamped;
//! - every `--obstacle-every` seconds (staggered across robots) a cloud of fresh wall points plus a small
//!   obstacle cluster (0.05–0.3 m across, 0.3 m high) 1.5–2.5 m ahead on its current path. The first correction
//!   that follows within 2 s (checked at the odometry ticks, so up to one odometry period more) is that
//!   obstacle's: publish → correction received (wall clock, one process). Every
//!   correction is applied to the robot's copy of its plan (re-fetched from the daemon's queryable on a version
//!   gap), and the robot drives on along the corrected path.
//!
//! Clouds and odometry are put with congestion control `Drop` (a robot's best-effort sensor streams;
//! `--block` puts clouds with `Block`). Daemon figures come from /metrics scraped before and after the run
//! (histogram quantiles interpolated inside buckets): clouds ingested and dropped by reason, points per second,
//! the ingest thread's busy fraction, publish → in the map. `compute_us` is the daemon's own check time carried
//! by each correction. RSS is `VmRSS` of this process: the daemon is in-process, so it includes the robots'
//! sessions and the bench's cloud buffers (printed too). Prints a table and one JSON line; it asserts nothing.
//!
//! `cargo run --release -p shift-tests --example fleet_load -- [--robots 30] [--seconds 30] [--points 30000]
//! [--odom-hz 10] [--cloud-hz 5] [--obstacle-every 3] [--block]`

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use clap::Parser;
use serde_json::{Value, json};
use shift_proto::ros::odometry::encode_odometry;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_proto::{CorrectionDoc, PlanDocument};
use shift_tests::bench::{Rng, Rooms, Scrape, percentile, quantile, restamp, wall_ns};
use shift_tests::fleet::{ScriptedRobot, free_port, header_ns, odom_at, wait_robot_alive};
use shift_tests::{TestServer, test_config};
use tokio::time::MissedTickBehavior;
use zenoh::bytes::Encoding;
use zenoh::pubsub::Publisher;
use zenoh::qos::CongestionControl;

/// Side of the bench site, metres.
const SITE_M: f64 = 100.0;
/// Room size of the walls' grid, metres.
const ROOM_M: f64 = 10.0;
/// The building.
const ROOMS: Rooms = Rooms {
    site_m: SITE_M,
    room_m: ROOM_M,
};
/// Map resolution, metres.
const RES_M: f64 = 0.1;
/// Driving speed, m/s.
const SPEED_M_S: f64 = 0.5;
/// Clouds encoded once per robot and re-stamped at every put.
const CLOUD_SET: usize = 3;
/// A correction this long after an obstacle cloud is no longer that obstacle's.
const CORRECTION_WAIT: Duration = Duration::from_secs(2);

/// Fleet load on loopback; see the module docs.
#[derive(Parser)]
struct Args {
    /// Robots, each its own Zenoh session.
    #[arg(long, default_value_t = 30, value_parser = at_least_one)]
    robots: usize,
    /// Seconds the fleet drives.
    #[arg(long, default_value_t = 30)]
    seconds: u64,
    /// Points per cloud.
    #[arg(long, default_value_t = 30_000)]
    points: usize,
    /// Odometry rate per robot, Hz.
    #[arg(long, default_value_t = 10.0, value_parser = positive)]
    odom_hz: f64,
    /// Cloud rate per robot, Hz.
    #[arg(long, default_value_t = 5.0, value_parser = positive)]
    cloud_hz: f64,
    /// Seconds between a robot's obstacle clouds.
    #[arg(long = "obstacle-every", default_value_t = 3.0, value_parser = positive)]
    obstacle_every_s: f64,
    /// Put clouds with congestion control `Block` instead of `Drop`.
    #[arg(long)]
    block: bool,
}

/// A count of one or more.
fn at_least_one(v: &str) -> Result<usize, String> {
    match v.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("{v:?} is not a count of one or more")),
    }
}

/// A finite number above zero.
fn positive(v: &str) -> Result<f64, String> {
    match v.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("{v:?} is not a positive number")),
    }
}

/// The static map: free rooms of ROOM_M with walls (the cells within one cell of every wall line, the site's
/// border included) occupied.
fn site_grid() -> Value {
    let n = (SITE_M / RES_M).round() as usize;
    let on_wall = |i: usize| {
        let p = (i as f64 + 0.5) * RES_M;
        let d = p - (p / ROOM_M).round() * ROOM_M;
        d.abs() < RES_M
    };
    let mut cells = vec![0u8; n * n];
    for r in 0..n {
        for c in 0..n {
            if on_wall(r) || on_wall(c) {
                cells[r * n + c] = 100;
            }
        }
    }
    json!({"resolution": RES_M, "origin": [0.0, 0.0], "width": n, "height": n, "cells": cells})
}

/// Lower-left corner of robot `i`'s room (row by row; rooms are reused beyond 100 robots).
fn room_of(i: usize) -> (f64, f64) {
    let per_row = (SITE_M / ROOM_M) as usize;
    let k = i % (per_row * per_row);
    ((k % per_row) as f64 * ROOM_M, (k / per_row) as f64 * ROOM_M)
}

/// Resident set size of this process, kB (`VmRSS` of /proc/self/status).
fn vm_rss_kb() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Where a robot is on its plan.
struct Drive {
    doc: PlanDocument,
    /// Waypoint it drives to.
    next: usize,
    x: f64,
    y: f64,
    yaw: f64,
    /// When its last obstacle cloud was published, until a correction follows or [`CORRECTION_WAIT`] passes.
    pending: Option<Instant>,
}

impl Drive {
    fn new(doc: PlanDocument) -> Self {
        let (x, y) = doc.waypoints.first().map_or((0.0, 0.0), |w| (w.x, w.y));
        Self {
            doc,
            next: 1,
            x,
            y,
            yaw: 0.0,
            pending: None,
        }
    }

    /// Moves `step` metres along the path.
    fn advance(&mut self, mut step: f64) {
        while step > 0.0 {
            let Some(w) = self.doc.waypoints.get(self.next) else {
                return; // the end of the plan: stand there
            };
            let (dx, dy) = (w.x - self.x, w.y - self.y);
            let l = dx.hypot(dy);
            if l > 1e-9 {
                self.yaw = dy.atan2(dx);
            }
            if l <= step {
                (self.x, self.y) = (w.x, w.y);
                self.next += 1;
                step -= l;
            } else {
                self.x += dx / l * step;
                self.y += dy / l * step;
                step = 0.0;
            }
        }
    }

    /// The point `dist` metres ahead along the path.
    fn ahead(&self, dist: f64) -> Option<(f64, f64)> {
        let (mut px, mut py, mut left) = (self.x, self.y, dist);
        for w in self.doc.waypoints.iter().skip(self.next) {
            let l = (w.x - px).hypot(w.y - py);
            if l >= left && l > 0.0 {
                let f = left / l;
                return Some((px + f * (w.x - px), py + f * (w.y - py)));
            }
            left -= l;
            (px, py) = (w.x, w.y);
        }
        None
    }

    /// Applies a correction to the robot's copy; false on a version gap (the robot re-fetches its plan).
    fn correct(&mut self, c: &CorrectionDoc) -> bool {
        let Ok(doc) = c.apply(&self.doc) else {
            return false;
        };
        let (old_len, new_len) = (self.doc.waypoints.len(), doc.waypoints.len());
        if self.next > c.to || (self.next == c.to && c.from < c.to) {
            // Past the patch: the same waypoint, moved by the patch's length change.
            self.next = (self.next + new_len).saturating_sub(old_len);
        } else if self.next > c.from {
            // Heading into a replaced stretch: on to the patch's first waypoint.
            self.next = c.from;
        }
        self.doc = doc;
        self.next = self.next.min(self.doc.waypoints.len());
        true
    }

    /// A re-fetched plan: on to the waypoint after the nearest one.
    fn replace(&mut self, doc: PlanDocument) {
        let nearest = doc
            .waypoints
            .iter()
            .enumerate()
            .min_by(|a, b| {
                let da = (a.1.x - self.x).hypot(a.1.y - self.y);
                let db = (b.1.x - self.x).hypot(b.1.y - self.y);
                da.total_cmp(&db)
            })
            .map_or(0, |(i, _)| i);
        self.doc = doc;
        self.next = (nearest + 1).min(self.doc.waypoints.len());
    }
}

/// What one robot saw.
#[derive(Default)]
struct RobotStats {
    odom_sent: u64,
    clouds_published: u64,
    cloud_put_errors: u64,
    obstacles: u64,
    /// Obstacle clouds with no correction within [`CORRECTION_WAIT`].
    obstacles_uncorrected: u64,
    corrections: u64,
    /// Publish → correction received of the obstacles' first corrections, milliseconds.
    latency_ms: Vec<f64>,
    compute_us: Vec<f64>,
    by_reason: BTreeMap<String, u64>,
    refetched: u64,
}

/// One robot on the road.
struct Robot {
    name: String,
    scripted: ScriptedRobot,
    odom: Publisher<'static>,
    cloud: Publisher<'static>,
    drive: Mutex<Drive>,
    /// Wall clouds encoded once (stamp rewritten at each put).
    clouds: Vec<Vec<u8>>,
}

/// The robot's odometry at `odom_hz` along its plan, and its corrections, until `end` (and until a pending
/// obstacle's correction arrives or times out).
async fn drive(robot: Arc<Robot>, odom_hz: f64, end: Instant) -> Result<RobotStats> {
    let mut st = RobotStats::default();
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / odom_hz));
    tick.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let step = SPEED_M_S / odom_hz;
    loop {
        tokio::select! {
            _ = tick.tick() => {
                let now = Instant::now();
                let (x, y, yaw, waiting) = {
                    let mut d = robot.drive.lock().map_err(|_| anyhow!("drive lock"))?;
                    if d.pending.is_some_and(|t| now.duration_since(t) > CORRECTION_WAIT) {
                        d.pending = None;
                        st.obstacles_uncorrected += 1;
                    }
                    d.advance(step);
                    (d.x, d.y, d.yaw, d.pending.is_some())
                };
                if now >= end && !waiting {
                    break;
                }
                let msg = encode_odometry(&odom_at(x, y, yaw, header_ns("map", wall_ns())));
                robot.odom.put(msg).await.map_err(|e| anyhow!("odom put: {e}"))?;
                st.odom_sent += 1;
            }
            sample = robot.scripted.corrections.recv_async() => {
                let Ok(sample) = sample else { break };
                let received = Instant::now();
                let c: CorrectionDoc = serde_json::from_slice(&sample.payload().to_bytes())?;
                st.corrections += 1;
                st.compute_us.push(c.compute_us as f64);
                *st.by_reason.entry(c.reason.as_str().to_owned()).or_default() += 1;
                let applied = {
                    let mut d = robot.drive.lock().map_err(|_| anyhow!("drive lock"))?;
                    if let Some(t) = d.pending.take() {
                        st.latency_ms.push(received.duration_since(t).as_secs_f64() * 1e3);
                    }
                    d.correct(&c)
                };
                if !applied {
                    let doc = robot.scripted.query_plan(&robot.name, Duration::from_secs(5)).await?;
                    robot.drive.lock().map_err(|_| anyhow!("drive lock"))?.replace(doc);
                    st.refetched += 1;
                }
            }
        }
    }
    Ok(st)
}

/// The robot's clouds at `cloud_hz` until `end`, an obstacle every `obstacle_every_s` from `first_obstacle`.
async fn clouds(
    robot: Arc<Robot>,
    seed: u64,
    points: usize,
    cloud_hz: f64,
    obstacle_every_s: f64,
    first_obstacle: Instant,
    end: Instant,
) -> Result<RobotStats> {
    let mut st = RobotStats::default();
    let mut rng = Rng(seed);
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / cloud_hz));
    tick.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let mut next_obstacle = first_obstacle;
    let mut set = robot.clouds.clone();
    let mut i = 0usize;
    loop {
        tick.tick().await;
        let now = Instant::now();
        if now >= end {
            break;
        }
        // Where the next obstacle goes, when one is due and the last one is settled.
        let obstacle = if now >= next_obstacle {
            let d = robot.drive.lock().map_err(|_| anyhow!("drive lock"))?;
            if d.pending.is_none() {
                d.ahead(1.5 + rng.next_f64()).map(|at| (at, (d.x, d.y)))
            } else {
                None
            }
        } else {
            None
        };
        let payload = match obstacle {
            Some(((ox, oy), (x, y))) => {
                // A square cluster 0.05–0.3 m across, 3–20 points a side, 0.3 m high, among fresh wall points.
                let side = 0.05 + 0.25 * rng.next_f64();
                let n = 3 + (17.0 * rng.next_f64()) as usize;
                let mut pts = ROOMS.cloud(&mut rng, x, y, points.saturating_sub(n * n));
                for a in 0..n {
                    for b in 0..n {
                        let (u, v) = (a as f64 / (n - 1) as f64 - 0.5, b as f64 / (n - 1) as f64 - 0.5);
                        pts.push([(ox + u * side) as f32, (oy + v * side) as f32, 0.3]);
                    }
                }
                next_obstacle += Duration::from_secs_f64(obstacle_every_s);
                st.obstacles += 1;
                robot.drive.lock().map_err(|_| anyhow!("drive lock"))?.pending = Some(Instant::now());
                encode_point_cloud2_xyz(&header_ns("map", wall_ns()), &pts)
            }
            None => {
                let k = i % set.len();
                i += 1;
                restamp(&mut set[k], wall_ns());
                set[k].clone()
            }
        };
        match robot.cloud.put(payload).await {
            Ok(()) => st.clouds_published += 1,
            Err(_) => st.cloud_put_errors += 1,
        }
    }
    Ok(st)
}

#[tokio::main(flavor = "multi_thread")]
async fn main() -> Result<()> {
    let args = Args::parse();
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::new("error"))
        .try_init();
    let dir = tempfile::tempdir()?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = test_config(dir.path());
    config.zenoh.listen = vec![endpoint.clone()];
    config.zenoh.site = "bench".into();
    config.demo.enabled = false;
    let defaults = shiftd::Config::default();
    config.jobs.workers = defaults.jobs.workers;
    config.jobs.queue_capacity = defaults.jobs.queue_capacity.max(args.robots);
    let server = TestServer::start(config).await?;

    let setup = Instant::now();
    let (code, body) = server.post("/v1/sites/bench/map", &site_grid()).await?;
    if code != 201 {
        bail!("site upload: {code} {body}");
    }
    let rss_idle_kb = vm_rss_kb();

    // The robots join, then each gets a plan of a 5 m × 5 m square in its room.
    let mut scripted = Vec::new();
    for r in 0..args.robots {
        let name = format!("r{:02}", r + 1);
        scripted.push((name.clone(), ScriptedRobot::join(&endpoint, &name).await?));
    }
    for (name, _) in &scripted {
        wait_robot_alive(&server, name).await?;
    }
    let mut plan_ids = Vec::new();
    for r in 0..args.robots {
        let (x0, y0) = room_of(r);
        let region = [
            [x0 + 2.0, y0 + 2.0],
            [x0 + 7.0, y0 + 2.0],
            [x0 + 7.0, y0 + 7.0],
            [x0 + 2.0, y0 + 7.0],
        ];
        let req = json!({"site": "bench", "start": [x0 + 2.5, y0 + 2.5], "region": region,
                         "robot": {"radius": 0.15, "tool_width": 0.3}});
        let id = loop {
            let (code, acc) = server.post("/v1/plans", &req).await?;
            match code {
                202 => break acc["plan_id"].as_str().context("plan id")?.to_owned(),
                429 => tokio::time::sleep(Duration::from_millis(500)).await,
                _ => bail!("plan request: {code} {acc}"),
            }
        };
        plan_ids.push(id);
    }
    let mut robots = Vec::new();
    let mut rng = Rng(0x5eed_f1ee_7000_0001);
    for ((name, s), id) in scripted.into_iter().zip(&plan_ids) {
        let status = server
            .wait_plan(id, Duration::from_secs(600), |s| s != "queued" && s != "planning")
            .await?;
        if status["status"] != "ready" {
            bail!("plan {id} of {name}: {status}");
        }
        let (code, body) = server
            .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": name}))
            .await?;
        if code != 200 {
            bail!("assign {id} to {name}: {code} {body}");
        }
        let (_, served) = server.get(&format!("/v1/plans/{id}/path")).await?;
        let doc: PlanDocument = serde_json::from_value(served)?;
        let congestion = if args.block {
            CongestionControl::Block
        } else {
            CongestionControl::Drop
        };
        let odom = s
            .session
            .declare_publisher(format!("shift/default/robots/{name}/odom"))
            .encoding(Encoding::APPLICATION_CDR)
            .congestion_control(CongestionControl::Drop)
            .await
            .map_err(|e| anyhow!("odom publisher: {e}"))?;
        let cloud = s
            .session
            .declare_publisher(format!("shift/default/robots/{name}/cloud"))
            .encoding(Encoding::APPLICATION_CDR)
            .congestion_control(congestion)
            .await
            .map_err(|e| anyhow!("cloud publisher: {e}"))?;
        // Wall clouds seen from points spread over the plan's start.
        let w = &doc.waypoints;
        let clouds = (0..CLOUD_SET)
            .map(|k| {
                let p = w.get(k * w.len() / (4 * CLOUD_SET)).context("empty plan")?;
                Ok(encode_point_cloud2_xyz(
                    &header_ns("map", 0),
                    &ROOMS.cloud(&mut rng, p.x, p.y, args.points),
                ))
            })
            .collect::<Result<Vec<_>>>()?;
        robots.push(Arc::new(Robot {
            name,
            scripted: s,
            odom,
            cloud,
            drive: Mutex::new(Drive::new(doc)),
            clouds,
        }));
    }
    let waypoints: Vec<usize> = robots
        .iter()
        .filter_map(|r| r.drive.lock().ok().map(|d| d.doc.waypoints.len()))
        .collect();
    let buffers_mb = robots
        .iter()
        .map(|r| r.clouds.iter().map(Vec::len).sum::<usize>())
        .sum::<usize>() as f64
        / 1e6;
    let setup_s = setup.elapsed().as_secs_f64();
    let rss_setup_kb = vm_rss_kb();
    // Publisher declarations take a moment to reach the daemon's session.
    tokio::time::sleep(Duration::from_secs(2)).await;

    // The run.
    let before = Scrape::take(&server).await?;
    let start = Instant::now();
    let end = start + Duration::from_secs(args.seconds);
    let mut tasks = Vec::new();
    for (r, robot) in robots.iter().enumerate() {
        // Staggered: the robots' obstacles spread over each period.
        let first = start + Duration::from_secs_f64(args.obstacle_every_s * (1.0 + r as f64 / args.robots as f64));
        tasks.push(tokio::spawn(drive(robot.clone(), args.odom_hz, end)));
        tasks.push(tokio::spawn(clouds(
            robot.clone(),
            0x5eed_0000_0000_0001 ^ ((r as u64 + 1) << 20),
            args.points,
            args.cloud_hz,
            args.obstacle_every_s,
            first,
            end,
        )));
    }
    let mut st = RobotStats::default();
    for t in tasks {
        let s = t.await??;
        st.odom_sent += s.odom_sent;
        st.clouds_published += s.clouds_published;
        st.cloud_put_errors += s.cloud_put_errors;
        st.obstacles += s.obstacles;
        st.obstacles_uncorrected += s.obstacles_uncorrected;
        st.corrections += s.corrections;
        st.latency_ms.extend(s.latency_ms);
        st.compute_us.extend(s.compute_us);
        st.refetched += s.refetched;
        for (k, v) in s.by_reason {
            *st.by_reason.entry(k).or_default() += v;
        }
    }
    let run_s = start.elapsed().as_secs_f64().min(args.seconds as f64 + 0.5);
    // Let the ingest queues drain (each holds a few clouds).
    let drain_until = Instant::now() + Duration::from_secs(10);
    let mut last = -1.0;
    loop {
        tokio::time::sleep(Duration::from_millis(200)).await;
        let n = Scrape::take(&server)
            .await?
            .get("shift_ingest_clouds_total{stream=\"cloud\"}");
        if n == last || Instant::now() > drain_until {
            break;
        }
        last = n;
    }
    let after = Scrape::take(&server).await?;
    let rss_end_kb = vm_rss_kb();
    let (_, site) = server.get("/v1/sites/bench").await?;

    let d = |k: &str| after.get(k) - before.get(k);
    let delta_of = |prefix: &str, filter: &dyn Fn(&str) -> bool| -> BTreeMap<String, f64> {
        after
            .values
            .iter()
            .filter(|(k, _)| k.starts_with(prefix) && filter(k.as_str()))
            .map(|(k, v)| (k.clone(), v - before.get(k)))
            .filter(|(_, v)| *v > 0.0)
            .collect()
    };
    let label = |k: &str, name: &str| -> String {
        let pat = format!("{name}=\"");
        k.split_once(&pat)
            .and_then(|(_, rest)| rest.split_once('"'))
            .map_or_else(|| k.to_owned(), |(v, _)| v.to_owned())
    };
    let dropped: BTreeMap<String, f64> = delta_of("shift_ingest_dropped_total{", &|k| k.contains("stream=\"cloud\""))
        .into_iter()
        .map(|(k, v)| (label(&k, "reason"), v))
        .collect();
    let odom_dropped: BTreeMap<String, f64> = delta_of("shift_odom_dropped_total{", &|_| true)
        .into_iter()
        .map(|(k, v)| (label(&k, "reason"), v))
        .collect();
    let dropped_all: f64 = dropped.values().sum();
    let ingested = d("shift_ingest_clouds_total{stream=\"cloud\"}");
    let points = d("shift_ingest_points_total{stream=\"cloud\"}");
    let work_s = d("shift_ingest_work_seconds_sum");
    let lost = st.clouds_published as f64 - ingested - dropped_all;
    let q = |name: &str, p: f64| quantile(&before, &after, name, p).map(|s| (s * 1e5).round() / 1e2);
    st.latency_ms.sort_by(f64::total_cmp);
    st.compute_us.sort_by(f64::total_cmp);
    let r2 = |v: f64| {
        if v.is_finite() {
            json!((v * 100.0).round() / 100.0)
        } else {
            Value::Null
        }
    };
    let lat = |p: f64| r2(percentile(&st.latency_ms, p));
    let cus = |p: f64| r2(percentile(&st.compute_us, p));
    let mb = |kb: Option<u64>| kb.map(|k| (k as f64 / 1024.0 * 10.0).round() / 10.0);
    let min_wp = waypoints.iter().min().copied().unwrap_or(0);
    let max_wp = waypoints.iter().max().copied().unwrap_or(0);

    let summary = json!({
        "robots": args.robots,
        "seconds": (run_s * 100.0).round() / 100.0,
        "points_per_cloud": args.points,
        "odom_hz": args.odom_hz,
        "cloud_hz": args.cloud_hz,
        "cloud_congestion": if args.block { "block" } else { "drop" },
        "setup_s": (setup_s * 10.0).round() / 10.0,
        "plan_waypoints": {"min": min_wp, "max": max_wp},
        "odom_sent": st.odom_sent,
        "odom_dropped": odom_dropped,
        "clouds": {
            "scheduled": (args.robots as f64 * args.seconds as f64 * args.cloud_hz).round(),
            "published": st.clouds_published,
            "put_errors": st.cloud_put_errors,
            "ingested": ingested,
            "dropped": dropped,
            "lost_in_transport": lost,
        },
        "ingested_points_per_s": (points / run_s).round(),
        "ingest_busy_fraction": (work_s / run_s * 1000.0).round() / 1000.0,
        "publish_to_map_ms": {"p50": q("shift_ingest_stamp_age_seconds", 0.5), "p99": q("shift_ingest_stamp_age_seconds", 0.99)},
        "arrival_to_map_ms": {"p50": q("shift_ingest_latency_seconds", 0.5), "p99": q("shift_ingest_latency_seconds", 0.99)},
        "checks": d("shift_check_seconds_count"),
        "obstacles": st.obstacles,
        "obstacles_uncorrected_2s": st.obstacles_uncorrected,
        "corrections": st.corrections,
        "corrections_by_reason": st.by_reason,
        "plans_refetched": st.refetched,
        "correction_latency_ms": {"n": st.latency_ms.len(), "p50": lat(0.5), "p99": lat(0.99), "max": lat(1.0)},
        "compute_us": {"p50": cus(0.5), "p99": cus(0.99)},
        "live_map_points": site["points_in_tree"],
        "rss_mb_in_process": {"after_site_upload": mb(rss_idle_kb), "after_setup": mb(rss_setup_kb), "end": mb(rss_end_kb)},
        "bench_cloud_buffers_mb": (buffers_mb * 10.0).round() / 10.0,
    });

    let rows: Vec<(&str, String)> = vec![
        ("robots", args.robots.to_string()),
        ("seconds", format!("{run_s:.1}")),
        ("setup (site, plans, assign)", format!("{setup_s:.1} s")),
        ("plan waypoints", format!("{min_wp}–{max_wp}")),
        ("odometry sent", st.odom_sent.to_string()),
        ("odometry dropped (daemon)", format!("{odom_dropped:?}")),
        ("clouds scheduled", summary["clouds"]["scheduled"].to_string()),
        ("clouds published", st.clouds_published.to_string()),
        ("clouds ingested", ingested.to_string()),
        ("clouds dropped (daemon)", format!("{dropped:?}")),
        ("clouds lost in transport", lost.to_string()),
        ("ingested points/s", format!("{:.0}", points / run_s)),
        ("ingest busy", format!("{:.2}", work_s / run_s)),
        (
            "publish→map p50 / p99",
            format!(
                "{} / {} ms",
                summary["publish_to_map_ms"]["p50"], summary["publish_to_map_ms"]["p99"]
            ),
        ),
        (
            "arrival→map p50 / p99",
            format!(
                "{} / {} ms",
                summary["arrival_to_map_ms"]["p50"], summary["arrival_to_map_ms"]["p99"]
            ),
        ),
        ("checks run", summary["checks"].to_string()),
        ("obstacles dropped ahead", st.obstacles.to_string()),
        ("  no correction within 2 s", st.obstacles_uncorrected.to_string()),
        ("corrections received", format!("{} {:?}", st.corrections, st.by_reason)),
        (
            "correction latency p50 / p99 / max",
            format!(
                "{} / {} / {} ms (n = {})",
                lat(0.5),
                lat(0.99),
                lat(1.0),
                st.latency_ms.len()
            ),
        ),
        ("compute_us p50 / p99", format!("{} / {} µs", cus(0.5), cus(0.99))),
        ("live map points", site["points_in_tree"].to_string()),
        (
            "RSS (in-process: daemon + robots + bench)",
            format!(
                "{} MB after site upload, {} MB after setup, {} MB at end (bench cloud buffers {buffers_mb:.1} MB)",
                summary["rss_mb_in_process"]["after_site_upload"],
                summary["rss_mb_in_process"]["after_setup"],
                summary["rss_mb_in_process"]["end"]
            ),
        ),
    ];
    for (k, v) in &rows {
        println!("{k:<42} {v}");
    }
    println!("{summary}");

    for r in robots {
        r.scripted.session.close().await.map_err(|e| anyhow!("{e}"))?;
    }
    server.stop().await
}
