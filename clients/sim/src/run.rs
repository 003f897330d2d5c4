//! One simulation run against a daemon: load the world, join the fleet, optionally plan and assign, drive
//! paced by the clock, measure, report.

use std::path::PathBuf;
use std::time::Duration;

use shift_client::Client;
use shift_client::robot::Applied;
use shift_proto::WatchHealth;
use shift_proto::keys::{KeySpace, Ros2Mapping};
use tokio::sync::mpsc;

use crate::clock::SimClock;
use crate::error::SimError;
use crate::measure::measure;
use crate::net::RobotNet;
use crate::plans::plan_and_assign;
use crate::report::{Quantiles, Report, TraceWriter, Traffic};
use crate::robot::SimRobot;
use crate::sight::{SightClock, WatchWindow, news_on_path};
use crate::sim::{Outgoing, SimConfig, Simulation};
use crate::world::World;

/// Everything a run needs.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The daemon's HTTP base URL.
    pub http: String,
    /// Bearer token for the API, if it needs one.
    pub token: Option<String>,
    /// The daemon's Zenoh endpoint.
    pub zenoh: String,
    /// Key prefix and fleet.
    pub keys: KeySpace,
    /// How the robots name their sensor keys.
    pub mapping: Ros2Mapping,
    /// The site the robots drive on.
    pub site: String,
    /// The world file.
    pub world: PathBuf,
    /// How many robots (default: those of the world file).
    pub robots: Option<usize>,
    /// Ask the daemon for one plan per robot and assign it.
    pub plan_per_robot: bool,
    /// Simulated seconds per real second (≤ 0: as fast as possible).
    pub speedup: f64,
    /// Seed for placing extra robots.
    pub seed: u64,
    /// Give up after this many simulated seconds.
    pub timeout_s: f64,
    /// Per-robot ground-truth traces go here.
    pub trace: Option<PathBuf>,
    /// Steps, rates, laser, mu.
    pub sim: SimConfig,
}

/// How long planning may take per run.
const PLAN_TIMEOUT: Duration = Duration::from_secs(300);
/// How long a robot's sight of something new on its path waits for a correction, wall seconds.
const SIGHT_PATIENCE_S: f64 = 2.0;
/// Wall-clock seconds between progress lines.
const PROGRESS_EVERY_S: f64 = 10.0;

/// Runs the simulation; the report says what happened (every robot finished or not).
pub async fn run(opts: &RunOptions) -> Result<Report, SimError> {
    let world = World::load(&opts.world)?;
    let n = opts.robots.unwrap_or(world.robots.len());
    if n == 0 {
        return Err(crate::error::bad(
            "--robots",
            "no robots: the world file lists none and --robots is 0",
        ));
    }
    let static_grid = world.static_grid();
    let specs = crate::spread::robots(&world.robots, n, &static_grid, opts.seed)?;
    let geometry = world.grid.geometry;
    let robots: Vec<SimRobot> = specs
        .into_iter()
        .map(|s| SimRobot::new(s, geometry, opts.sim.mu))
        .collect();
    let mut sim = Simulation::new(world, robots, opts.sim);

    let (inbox, mut messages) = mpsc::unbounded_channel();
    let mut nets = Vec::with_capacity(sim.robots.len());
    for (i, r) in sim.robots.iter().enumerate() {
        nets.push(RobotNet::connect(&opts.zenoh, &opts.keys, &opts.mapping, &r.spec.id, i, inbox.clone()).await?);
    }
    tracing::info!(robots = nets.len(), "robots joined the fleet");
    // One epoch for every stamp. The daemon sees the robots alive and at their starts before anything is
    // assigned.
    let clock = SimClock::start(opts.speedup);
    for (net, r) in nets.iter().zip(&sim.robots) {
        net.odometry(&r.body, clock.stamp_ns(0.0)).await?;
    }
    if opts.plan_per_robot {
        let mut client = Client::new(&opts.http).map_err(|e| SimError::Fleet(e.to_string()))?;
        if let Some(t) = &opts.token {
            client = client.with_token(t.clone());
        }
        plan_and_assign(&client, &opts.site, &sim.robots, PLAN_TIMEOUT).await?;
    }

    let ids: Vec<String> = sim.robots.iter().map(|r| r.spec.id.clone()).collect();
    let mut trace = opts
        .trace
        .as_deref()
        .map(|d| TraceWriter::create(d, &ids))
        .transpose()?;
    let clock = clock.pace_from_now();
    let mut next_progress = PROGRESS_EVERY_S;
    // Correction latency as the robots live it, with the daemon's default watch window.
    let window = WatchWindow::default();
    let mut sights = vec![SightClock::new(SIGHT_PATIENCE_S); sim.robots.len()];
    let mut traffic = Traffic::default();
    while sim.t < opts.timeout_s && !sim.all_finished() {
        while let Ok((i, message)) = messages.try_recv() {
            let applied = sim.robots[i].on_message(message);
            let id = &sim.robots[i].spec.id;
            match applied {
                Applied::Gap { .. } => {
                    tracing::debug!(robot = %id, t = sim.t, "version gap: fetching the plan");
                    nets[i].request_plan();
                }
                Applied::Watch {
                    health: WatchHealth::Blocked,
                } => sights[i].on_held(clock.wall_s()),
                Applied::Correction { version } => {
                    if let Some(ms) = sights[i].on_correction(clock.wall_s()) {
                        tracing::debug!(robot = %id, t = sim.t, version, latency_ms = ms, "sight answered");
                    }
                }
                _ => {}
            }
        }
        for out in sim.step() {
            match out {
                Outgoing::Odom { robot, body } => {
                    nets[robot].odometry(&body, clock.stamp_ns(sim.t)).await?;
                    traffic.odom_sent += 1;
                }
                Outgoing::Scan { robot, ranges } => {
                    nets[robot]
                        .scan(&sim.config.lidar, &ranges, clock.stamp_ns(sim.t))
                        .await?;
                    traffic.scans_sent += 1;
                    let r = &sim.robots[robot];
                    let ahead = r.path_ahead(window.window_radius_m);
                    // Known to the daemon already when it holds the plan's end at a blockage.
                    let news = (r.followed.watch() != Some(WatchHealth::Blocked))
                        .then(|| news_on_path(r.seen(), &ahead, r.position(), r.spec.radius, window, &static_grid))
                        .flatten();
                    if sights[robot].on_scan(clock.wall_s(), news.is_some())
                        && let Some(seen) = news
                    {
                        let p = r.position();
                        tracing::debug!(
                            robot = %r.spec.id,
                            t = sim.t,
                            x = p.x,
                            y = p.y,
                            seen_x = seen.x,
                            seen_y = seen.y,
                            target = r.target_index(),
                            "sight"
                        );
                    }
                }
            }
        }
        if let Some(w) = &mut trace {
            w.row(sim.t, &sim.robots)?;
        }
        if clock.wall_s() >= next_progress {
            next_progress += PROGRESS_EVERY_S;
            let done = sim.robots.iter().filter(|r| r.finished()).count();
            let driven: f64 = sim.robots.iter().map(|r| r.stats.driven_m).sum();
            tracing::info!(
                t = format!("{:.0}", sim.t),
                done,
                driven_m = format!("{driven:.0}"),
                "progress"
            );
        }
        if let Some(due) = clock.due(sim.t) {
            tokio::time::sleep_until(due.into()).await;
        } else if sim.t.rem_euclid(1.0) < sim.config.dt {
            // Unpaced: let the network tasks run now and then.
            tokio::task::yield_now().await;
        }
    }
    if let Some(w) = trace {
        w.finish()?;
    }
    let coverage = measure(&static_grid, &sim.robots);
    let mut report = Report::new(&sim.robots, &coverage, sim.t, clock.wall_s());
    let latencies: Vec<f64> = sights.iter().flat_map(|s| s.latencies_ms.iter().copied()).collect();
    traffic.wall_s = clock.wall_s();
    traffic.correction_latency_ms = Quantiles::of(&latencies);
    traffic.sights_unanswered = sights.iter().map(|s| s.unanswered).sum();
    let held: Vec<f64> = sights.iter().flat_map(|s| s.held_ms.iter().copied()).collect();
    traffic.held_latency_ms = Quantiles::of(&held);
    report.traffic = traffic;
    for net in nets {
        net.close().await;
    }
    Ok(report)
}
