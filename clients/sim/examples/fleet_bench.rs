//! Simulated fleets against one daemon (issue 19's bench): N `shift-sim` robots (default 10, then 30) on the
//! shared `warehouse` map at `--speedup 5`, each its own Zenoh participant on loopback with odometry at 20 Hz and
//! 360-beam scans at 10 Hz of simulated time (100 Hz and 50 Hz real per robot at speedup 5), each given one
//! cell of a grid over the site as its region, with a 0.4 m box the daemon does not know in every cell and a
//! walker per five robots.
//!
//! The daemon is the release `shiftd` binary as a child process (so its CPU and RSS are its own, read from
//! `/proc` every second); the fleet runs in this process. Figures:
//! - rates held: messages the robots sent per robot and wall second, against the target, and the simulated
//!   seconds per wall second achieved (the simulator runs on the same two cores as the daemon);
//! - drops: the daemon's own counters (`shift_odom_dropped_total`, `shift_ingest_dropped_total` by reason,
//!   `shift_publish_dropped_total`), before and after;
//! - correction latency as the robots lived it: first scan showing something new across the robot's path in
//!   the daemon's watch window → the next correction applied (wall clock; [`shift_sim::sight`]);
//! - daemon CPU (percent of one core, median and max over the seconds no plan was being computed) and RSS
//!   (max), fleet coverage and collisions.
//!
//! It asserts nothing (the budgets — no dropped odometry, correction p99 < 50 ms at 30 robots — are printed
//! beside the figures).
//!
//! `cargo build --release -p shiftd && cargo run --release -p shift-sim --example fleet_bench -- [--robots 10
//! --robots 30] [--speedup 5] [--sim-s 120] [--seed 1] [--shiftd target/release/shiftd]`

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Parser;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};
use shift_client::Client;
use shift_planner::geom::Point2;
use shift_planner::map::OccupancyGrid;
use shift_proto::keys::{KeySpace, Ros2Mapping};
use shift_proto::mission::{MissionRequest, MissionRobot, MissionStatus};
use shift_sim::sim::SimConfig;
use shift_sim::world::World;
use shift_sim::{Report, RunOptions};
use shift_tests::bench::{Scrape, quantile};

/// Robot body and tool, metres; speed, m/s.
const RADIUS_M: f64 = 0.3;
const TOOL_M: f64 = 0.8;
const V_MAX: f64 = 1.0;
/// Side of the hidden boxes, metres.
const BOX_M: f64 = 0.4;

#[derive(Parser)]
struct Args {
    /// Fleet sizes to run, one run each.
    #[arg(long, default_values_t = [10, 30])]
    robots: Vec<usize>,
    /// Simulated seconds per wall second.
    #[arg(long, default_value_t = 5.0)]
    speedup: f64,
    /// Simulated seconds each run drives.
    #[arg(long, default_value_t = 120.0)]
    sim_s: f64,
    /// Seed of the robots' cells, boxes and walkers.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The shiftd binary (default: beside this example's folder, i.e. target/release/shiftd).
    #[arg(long)]
    shiftd: Option<PathBuf>,
    /// `[watch]` keys for the daemon, as TOML lines (e.g. `check_interval_ms = 50`), to compare settings on one
    /// build.
    #[arg(long)]
    watch: Vec<String>,
    /// Where the daemon's stderr (its log, filtered by `RUST_LOG` as this process's is) goes; discarded without.
    #[arg(long)]
    daemon_log: Option<PathBuf>,
    /// Writes each run's whole simulator report (per robot) to `PATH` with the fleet size appended
    /// (`PATH.30.json`).
    #[arg(long)]
    report: Option<PathBuf>,
    /// Divides the site among the robots with one mission (`POST /v1/missions`, then assign), as a fleet
    /// backend would, instead of giving each robot a grid cell as its region and planning it alone. The
    /// robots wait for the plans assigned to their ids; the simulated time includes the mission's planning.
    #[arg(long)]
    mission: bool,
}

fn warehouse() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenarios/warehouse")
}

fn free_port() -> Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// True when every cell within `r` of `p` is free.
fn clear(map: &OccupancyGrid, p: Point2, r: f64) -> bool {
    let g = map.geometry;
    let steps = (r / g.resolution).ceil() as i32;
    (-steps..=steps).all(|dy| {
        (-steps..=steps).all(|dx| {
            let q = Point2::new(p.x + f64::from(dx) * g.resolution, p.y + f64::from(dy) * g.resolution);
            (q - p).norm() > r || g.locate(q).is_some_and(|c| map.is_free(g.index(c)))
        })
    })
}

/// A seeded point of `[x0, x1] × [y0, y1]` with `r` of free space round it, nearest `near` when given.
fn pick(
    map: &OccupancyGrid,
    rng: &mut ChaCha8Rng,
    cell: [f64; 4],
    r: f64,
    near: Option<Point2>,
    avoid: Option<(Point2, f64)>,
) -> Option<Point2> {
    let [x0, y0, x1, y1] = cell;
    let mut candidates =
        (0..400).map(|_| Point2::new(rng.random_range(x0 + r..x1 - r), rng.random_range(y0 + r..y1 - r)));
    let ok = |p: &Point2| clear(map, *p, r) && avoid.is_none_or(|(a, d)| (*p - a).norm() >= d);
    match near {
        Some(c) => candidates
            .filter(ok)
            .min_by(|a, b| (*a - c).norm().total_cmp(&(*b - c).norm())),
        None => candidates.find(ok),
    }
}

/// The world file of `n` robots: one grid cell each (its region, unless `regions` is false), a hidden box in
/// each, a walker per five.
fn world(n: usize, seed: u64, map: &OccupancyGrid, regions: bool) -> Result<Value> {
    let g = map.geometry;
    let (w, h) = (g.width as f64 * g.resolution, g.height as f64 * g.resolution);
    let cols = ((n as f64 * w / h).sqrt().ceil() as usize).max(1);
    let rows = n.div_ceil(cols);
    let (cw, ch) = (w / cols as f64, h / rows as f64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut robots, mut obstacles, mut movers) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let (cx, cy) = ((i % cols) as f64, (i / cols) as f64);
        let cell = [
            g.origin.x + cx * cw,
            g.origin.y + cy * ch,
            g.origin.x + (cx + 1.0) * cw,
            g.origin.y + (cy + 1.0) * ch,
        ];
        let centre = Point2::new((cell[0] + cell[2]) / 2.0, (cell[1] + cell[3]) / 2.0);
        let start = pick(map, &mut rng, cell, RADIUS_M + 0.1, Some(centre), None)
            .with_context(|| format!("no free start in cell {cell:?}"))?;
        let half = BOX_M / 2.0;
        if let Some(b) = pick(map, &mut rng, cell, half + 0.1, None, Some((start, 1.5))) {
            obstacles.push(json!({"box": [b.x - half, b.y - half, b.x + half, b.y + half]}));
        }
        if i % 5 == 4
            && let (Some(a), Some(b)) = (
                pick(map, &mut rng, cell, 0.6, None, Some((start, 1.0))),
                pick(map, &mut rng, cell, 0.6, None, Some((start, 1.0))),
            )
        {
            movers.push(json!({"r": 0.2, "from": [a.x, a.y], "to": [b.x, b.y], "speed": 0.3}));
        }
        let mut robot = json!({
            "id": format!("r{i:02}"), "start": [start.x, start.y, 0.0], "radius": RADIUS_M, "tool_width": TOOL_M,
            "v_max": V_MAX,
        });
        if regions {
            robot["region"] = json!([
                [cell[0], cell[1]],
                [cell[2], cell[1]],
                [cell[2], cell[3]],
                [cell[0], cell[3]]
            ]);
        }
        robots.push(robot);
    }
    Ok(json!({"map": warehouse().join("map.yaml"), "obstacles": obstacles, "movers": movers, "robots": robots}))
}

/// One mission over the site for the world's robots (each from its start, with its body and tool), planned and
/// assigned; errors when the mission fails or takes longer than [`MISSION_TIMEOUT`].
async fn divide(client: &Client, world: &Value) -> Result<()> {
    let robots = world["robots"]
        .as_array()
        .context("the world's robots")?
        .iter()
        .map(|r| {
            let id = r["id"].as_str().context("a robot's id")?;
            let start = [r["start"][0].as_f64(), r["start"][1].as_f64()];
            let [Some(x), Some(y)] = start else {
                bail!("robot {id}: its start");
            };
            let mut robot = MissionRobot::new(id, [x, y], RADIUS_M, TOOL_M);
            robot.v_max = V_MAX;
            Ok(robot)
        })
        .collect::<Result<Vec<_>>>()?;
    let accepted = client
        .create_mission(&MissionRequest {
            site: "wh".into(),
            robots,
            attribute: None,
            options: None,
            objective: None,
        })
        .await?;
    let id = accepted.mission_id;
    let deadline = Instant::now() + MISSION_TIMEOUT;
    loop {
        let view = client.mission(&id).await?;
        match view.status {
            MissionStatus::Ready => break,
            MissionStatus::Queued | MissionStatus::Planning if Instant::now() < deadline => {
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
            other => bail!("mission {id} is {other:?}: {:?} {:?}", view.error, view.warnings),
        }
    }
    client.assign_mission(&id).await?;
    Ok(())
}

/// How long a mission may take to plan.
const MISSION_TIMEOUT: Duration = Duration::from_secs(300);

/// The daemon as a child process on loopback.
struct Daemon {
    child: Child,
    base: String,
    endpoint: String,
}

impl Daemon {
    async fn start(bin: &Path, dir: &Path, watch: &[String], log: Option<&Path>) -> Result<Self> {
        let (port, zport) = (free_port()?, free_port()?);
        let endpoint = format!("tcp/127.0.0.1:{zport}");
        let config = dir.join("shiftd.toml");
        let watch: String = watch.iter().map(|l| format!("{l}\n")).collect();
        std::fs::write(
            &config,
            format!("[zenoh]\nsite = \"\"\n[demo]\nenabled = false\n[watch]\n{watch}"),
        )?;
        let child = Command::new(bin)
            .args([
                "serve",
                "--bind",
                &format!("127.0.0.1:{port}"),
                "--zenoh-listen",
                &endpoint,
            ])
            .arg("--data-dir")
            .arg(dir.join("data"))
            .arg("--config")
            .arg(&config)
            .stdout(Stdio::null())
            .stderr(match log {
                Some(path) => {
                    Stdio::from(std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?)
                }
                None => Stdio::null(),
            })
            .spawn()
            .with_context(|| format!("starting {} (cargo build --release -p shiftd)", bin.display()))?;
        let d = Self {
            child,
            base: format!("http://127.0.0.1:{port}"),
            endpoint,
        };
        let http = reqwest::Client::new();
        for _ in 0..400 {
            if http
                .get(format!("{}/readyz", d.base))
                .send()
                .await
                .is_ok_and(|r| r.status().is_success())
            {
                return Ok(d);
            }
            tokio::time::sleep(Duration::from_millis(25)).await;
        }
        bail!("shiftd did not become ready")
    }

    fn pid(&self) -> u32 {
        self.child.id()
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// One second's reading of the daemon from outside.
#[derive(Debug, Clone, Copy)]
struct Reading {
    cpu_pct: f64,
    rss_mb: f64,
    planning: bool,
}

fn cpu_ticks(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name (which may hold spaces): state is field 3, utime 14, stime 15.
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = rest.split_whitespace().collect();
    Some(f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?)
}

fn rss_mb(pid: u32) -> Option<f64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let kb: f64 = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()?;
    Some(kb / 1024.0)
}

/// Reads the daemon every second until `stop`.
async fn watch(pid: u32, base: String, readings: Arc<Mutex<Vec<Reading>>>, stop: Arc<tokio::sync::Notify>) {
    // Linux reports CPU time in clock ticks of 1/100 s on every mainstream configuration.
    const TICKS_PER_S: f64 = 100.0;
    let http = reqwest::Client::new();
    let mut last = (Instant::now(), cpu_ticks(pid).unwrap_or(0));
    loop {
        tokio::select! {
            () = stop.notified() => return,
            () = tokio::time::sleep(Duration::from_secs(1)) => {}
        }
        let (now, ticks) = (Instant::now(), cpu_ticks(pid).unwrap_or(last.1));
        let cpu_pct = (ticks - last.1) as f64 / TICKS_PER_S / (now - last.0).as_secs_f64() * 100.0;
        last = (now, ticks);
        let planning = match Scrape::fetch(&http, &base).await {
            Ok(s) => s.get("shift_plan_jobs_running") > 0.0 || s.get("shift_plan_queue_depth") > 0.0,
            Err(_) => true,
        };
        if let Ok(mut r) = readings.lock() {
            r.push(Reading {
                cpu_pct,
                rss_mb: rss_mb(pid).unwrap_or(f64::NAN),
                planning,
            });
        }
    }
}

/// Sum of a counter over all its label sets (`name` and `name{...}`).
fn counter(s: &Scrape, name: &str) -> f64 {
    s.values
        .iter()
        .filter(|(k, _)| *k == name || k.starts_with(&format!("{name}{{")))
        .map(|(_, v)| v)
        .sum()
}

/// The label sets of counter `name` that rose between two scrapes, with how much (`{labels}: n`, joined).
/// Robots that wait unassigned on a daemon without a default site have their scans dropped as `unrouted`,
/// which is the design, not load; the breakdown tells such drops from a full queue.
fn rises(before: &Scrape, after: &Scrape, name: &str) -> String {
    let mut rose: Vec<String> = after
        .values
        .iter()
        .filter_map(|(k, v)| {
            let labels = k.strip_prefix(name)?.strip_prefix('{')?.strip_suffix('}')?;
            let d = v - before.get(k);
            (d > 0.0).then(|| format!("{labels}: {d:.0}"))
        })
        .collect();
    rose.sort();
    rose.join("; ")
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

struct RunFigures {
    n: usize,
    report: Report,
    /// Each drop counter's increase, with the label sets that rose (`reason="unrouted",stream="scan": 120`).
    drops: Vec<(&'static str, f64, String)>,
    /// Daemon-side p50 / p99 in ms: a scan's arrival → in the live map, and one path check's compute time.
    ingest_ms: (Option<f64>, Option<f64>),
    check_ms: (Option<f64>, Option<f64>),
    engine_wait_ms: (Option<f64>, Option<f64>),
    cpu_median: f64,
    cpu_max: f64,
    rss_max: f64,
    seconds_read: usize,
}

async fn run_fleet(args: &Args, bin: &Path, n: usize) -> Result<RunFigures> {
    let dir = tempfile::tempdir()?;
    let daemon = Daemon::start(bin, dir.path(), &args.watch, args.daemon_log.as_deref()).await?;
    let client = Client::new(&daemon.base)?;
    let scene = warehouse();
    let yaml = std::fs::read_to_string(scene.join("map.yaml"))?;
    let image = std::fs::read(scene.join("map.pgm"))?;
    client.upload_map("wh", yaml, image, "map.pgm").await?;

    // The static map, from a world of one robot at the scene's start.
    let probe = json!({"map": scene.join("map.yaml"), "robots": [{"id": "p", "start": [1.0, 1.0, 0.0], "radius": RADIUS_M, "tool_width": TOOL_M}]});
    let probe_path = dir.path().join("probe.json");
    std::fs::write(&probe_path, serde_json::to_vec(&probe)?)?;
    let map = World::load(&probe_path)?.static_grid();
    let world_path = dir.path().join("world.json");
    let world_doc = world(n, args.seed, &map, !args.mission)?;
    std::fs::write(&world_path, serde_json::to_vec_pretty(&world_doc)?)?;

    let http = reqwest::Client::new();
    let before = Scrape::fetch(&http, &daemon.base).await?;
    let readings = Arc::new(Mutex::new(Vec::new()));
    let stop = Arc::new(tokio::sync::Notify::new());
    let watcher = tokio::spawn(watch(daemon.pid(), daemon.base.clone(), readings.clone(), stop.clone()));
    let opts = RunOptions {
        http: daemon.base.clone(),
        token: None,
        zenoh: daemon.endpoint.clone(),
        keys: KeySpace::new("shift".to_owned(), "default".to_owned())?,
        mapping: Ros2Mapping::Native,
        site: "wh".into(),
        world: world_path,
        robots: Some(n),
        plan_per_robot: !args.mission,
        speedup: args.speedup,
        seed: args.seed,
        timeout_s: args.sim_s,
        trace: None,
        sim: SimConfig::default(),
    };
    let report = if args.mission {
        let sim = tokio::spawn(async move { shift_sim::run(&opts).await });
        let planned = Instant::now();
        divide(&client, &world_doc).await?;
        eprintln!(
            "mission of {n} robots planned and assigned in {:.1} s",
            planned.elapsed().as_secs_f64()
        );
        sim.await??
    } else {
        shift_sim::run(&opts).await?
    };
    stop.notify_one();
    let _ = watcher.await;
    let after = Scrape::fetch(&http, &daemon.base).await?;
    let drops = [
        "shift_odom_dropped_total",
        "shift_ingest_dropped_total",
        "shift_publish_dropped_total",
    ]
    .map(|k| (k, counter(&after, k) - counter(&before, k), rises(&before, &after, k)))
    .to_vec();
    let ms = |name: &str| {
        let q = |p: f64| quantile(&before, &after, name, p).map(|s| s * 1e3);
        (q(0.5), q(0.99))
    };
    let (ingest_ms, check_ms) = (ms("shift_ingest_latency_seconds"), ms("shift_check_seconds"));
    let engine_wait_ms = ms("shift_engine_wait_seconds");
    let readings = readings.lock().map(|r| r.clone()).unwrap_or_default();
    let driving: Vec<Reading> = readings.iter().copied().filter(|r| !r.planning).collect();
    Ok(RunFigures {
        n,
        report,
        drops,
        ingest_ms,
        check_ms,
        engine_wait_ms,
        cpu_median: median(driving.iter().map(|r| r.cpu_pct).collect()),
        cpu_max: driving.iter().map(|r| r.cpu_pct).fold(f64::NAN, f64::max),
        rss_max: readings.iter().map(|r| r.rss_mb).fold(f64::NAN, f64::max),
        seconds_read: driving.len(),
    })
}

fn print(f: &RunFigures, args: &Args) {
    let sim = SimConfig::default();
    let t = &f.report.traffic;
    let per_robot_s = f.n as f64 * t.wall_s.max(1e-9);
    let lat = t.correction_latency_ms.as_ref();
    let fmt = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.0}"));
    let fmt1 = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.1}"));
    println!(
        "\n## {} robots, speedup {} ({:.0} simulated s, {:.1} wall s)",
        f.n, args.speedup, args.sim_s, t.wall_s
    );
    println!("| figure | value | target |");
    println!("|---|---|---|");
    println!(
        "| odometry sent per robot | {:.1} Hz | {:.0} Hz |",
        t.odom_sent as f64 / per_robot_s,
        sim.odom_hz * args.speedup
    );
    println!(
        "| scans sent per robot | {:.1} Hz | {:.0} Hz |",
        t.scans_sent as f64 / per_robot_s,
        sim.scan_hz * args.speedup
    );
    println!(
        "| speedup achieved | {:.2} | {} |",
        f.report.fleet.speedup_achieved, args.speedup
    );
    for (k, v, by) in &f.drops {
        let by = if by.is_empty() {
            String::new()
        } else {
            format!(" ({by})")
        };
        println!("| {k} | {v:.0}{by} | 0 |");
    }
    println!(
        "| correction latency p50 / p99 / max (n) | {} / {} / {} ms ({}) | p99 < 50 ms |",
        fmt(lat.map(|q| q.p50)),
        fmt(lat.map(|q| q.p99)),
        fmt(lat.map(|q| q.max)),
        lat.map_or(0, |q| q.n)
    );
    let held = t.held_latency_ms.as_ref();
    println!(
        "| sights answered by holding the plan's end (status blocked) p50 / max (n) | {} / {} ms ({}) | |",
        fmt(held.map(|q| q.p50)),
        fmt(held.map(|q| q.max)),
        held.map_or(0, |q| q.n)
    );
    println!("| sights without a correction in 2 s | {} | |", t.sights_unanswered);
    println!(
        "| daemon: scan arrival → live map p50 / p99 | {} / {} ms | |",
        fmt1(f.ingest_ms.0),
        fmt1(f.ingest_ms.1)
    );
    println!(
        "| daemon: one path check p50 / p99 | {} / {} ms | |",
        fmt1(f.check_ms.0),
        fmt1(f.check_ms.1)
    );
    println!(
        "| daemon: an event's wait in the engine's inbox p50 / p99 | {} / {} ms | |",
        fmt1(f.engine_wait_ms.0),
        fmt1(f.engine_wait_ms.1)
    );
    println!(
        "| daemon CPU, % of one core, median / max ({} s read) | {:.0} / {:.0} | |",
        f.seconds_read, f.cpu_median, f.cpu_max
    );
    println!("| daemon RSS max | {:.1} MB | |", f.rss_max);
    let corrections: u64 = f.report.robots.iter().map(|r| r.corrections_applied).sum();
    let stops: u64 = f.report.robots.iter().map(|r| r.stops).sum();
    println!(
        "| fleet covered / collisions / corrections applied / safety stops | {:.1} % / {} / {corrections} / {stops} | |",
        f.report.fleet.covered_pct, f.report.fleet.collisions
    );
    println!(
        "| coverable from each robot's start without leaving its region (the most its plans can sweep) | {:.1} % | |",
        f.report.fleet.within_regions_pct
    );
    let line = json!({
        "robots": f.n, "speedup": args.speedup, "traffic": t, "drops": f.drops.iter().map(|(k, v, by)| json!({k.to_string(): v, "by": by})).collect::<Vec<_>>(),
        "cpu_pct_median": f.cpu_median, "cpu_pct_max": f.cpu_max, "rss_mb_max": f.rss_max, "fleet": f.report.fleet,
    });
    println!("{line}");
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()))
        .with_writer(std::io::stderr)
        .init();
    let args = Args::parse();
    let bin = match &args.shiftd {
        Some(p) => p.clone(),
        None => std::env::current_exe()?
            .parent()
            .and_then(Path::parent)
            .context("the example's folder")?
            .join("shiftd"),
    };
    for &n in &args.robots {
        let figures = run_fleet(&args, &bin, n).await?;
        print(&figures, &args);
        if let Some(path) = &args.report {
            let path = path.with_extension(format!("{n}.json"));
            std::fs::write(&path, serde_json::to_vec_pretty(&figures.report)?)
                .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    Ok(())
}
