//! `shift-sim`: run a simulated fleet against a SHIFT daemon and write what happened.
//!
//! ```text
//! shift-sim --http http://127.0.0.1:PORT --zenoh tcp/127.0.0.1:ZPORT --site SITE --world world.json
//!           --robots N [--plan-per-robot] [--speedup K] [--mu M] [--seed S] [--timeout-s T]
//!           --report report.json [--trace DIR]
//! ```
//! Exit 0 when every robot finished its plan, 1 otherwise, 2 on bad input.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;
use shift_proto::keys::{KeySpace, Ros2Mapping};
use shift_sim::lidar::Lidar;
use shift_sim::sim::SimConfig;
use shift_sim::{RunOptions, SimError, run};

/// A simulated fleet for SHIFT: robots as Zenoh participants in a hidden world.
#[derive(Debug, Parser)]
#[command(name = "shift-sim", version)]
struct Args {
    /// The daemon's HTTP API.
    #[arg(long, env = "SHIFT_HTTP", default_value = "http://127.0.0.1:7878")]
    http: String,
    /// Bearer token for the API.
    #[arg(long, env = "SHIFT_TOKEN")]
    token: Option<String>,
    /// The daemon's Zenoh endpoint (each robot connects to it as a peer).
    #[arg(long, default_value = "tcp/127.0.0.1:7447")]
    zenoh: String,
    /// Key prefix of the fleet's keys.
    #[arg(long, default_value = "shift")]
    prefix: String,
    /// Fleet name.
    #[arg(long, default_value = "default")]
    fleet: String,
    /// Sensor key layout: `native`, `bridge_ros2dds[:NAMESPACE]` or `rmw_zenoh[:DOMAIN]`.
    #[arg(long, default_value = "native")]
    mapping: String,
    /// The site the robots drive on.
    #[arg(long)]
    site: String,
    /// The world file (JSON; its map path is relative to it).
    #[arg(long)]
    world: PathBuf,
    /// Number of robots (default: those the world file lists; more are spread over free cells).
    #[arg(long)]
    robots: Option<usize>,
    /// Ask the daemon for one plan per robot from its start pose and assign it.
    #[arg(long)]
    plan_per_robot: bool,
    /// Simulated seconds per real second (0: as fast as the machine goes).
    #[arg(long, default_value_t = 1.0)]
    speedup: f64,
    /// Dynamic-tracking threshold, metres (0: stop at every waypoint).
    #[arg(long, default_value_t = 0.2)]
    mu: f64,
    /// Seed for placing robots the world file does not list.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Give up after this many simulated seconds.
    #[arg(long, default_value_t = 3600.0)]
    timeout_s: f64,
    /// Odometry rate, Hz of simulated time.
    #[arg(long, default_value_t = 20.0)]
    odom_hz: f64,
    /// Scan rate, Hz of simulated time.
    #[arg(long, default_value_t = 10.0)]
    scan_hz: f64,
    /// Laser beams over a full turn.
    #[arg(long, default_value_t = 360)]
    beams: usize,
    /// Laser range, metres.
    #[arg(long, default_value_t = 10.0)]
    range_m: f64,
    /// Write the report here (JSON).
    #[arg(long)]
    report: PathBuf,
    /// Write each robot's ground truth to DIR/ROBOT.csv (t,x,y,yaw,v every 0.05 s of simulated time).
    #[arg(long)]
    trace: Option<PathBuf>,
}

fn mapping(text: &str) -> Result<Ros2Mapping, SimError> {
    let (kind, arg) = text.split_once(':').map_or((text, None), |(k, a)| (k, Some(a)));
    let m = match (kind, arg) {
        ("native", None) => Ros2Mapping::Native,
        ("bridge_ros2dds", ns) => Ros2Mapping::BridgeRos2dds {
            namespace: ns.map(str::to_owned),
        },
        ("rmw_zenoh", d) => Ros2Mapping::RmwZenoh {
            domain: d
                .map(str::parse)
                .transpose()
                .map_err(|_| shift_sim::error::bad("--mapping", format!("{text:?}: the domain is a number")))?
                .unwrap_or(0),
        },
        _ => {
            return Err(shift_sim::error::bad(
                "--mapping",
                format!("{text:?} is not native, bridge_ros2dds[:NS] or rmw_zenoh[:DOMAIN]"),
            ));
        }
    };
    m.validate()
        .map_err(|e| shift_sim::error::bad("--mapping", e.to_string()))?;
    Ok(m)
}

fn options(a: &Args) -> Result<RunOptions, SimError> {
    let positive = |field: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(shift_sim::error::bad(
                field,
                format!("must be a positive number, got {v}"),
            ))
        }
    };
    if !(a.mu.is_finite() && a.mu >= 0.0) {
        return Err(shift_sim::error::bad("--mu", format!("must be ≥ 0, got {}", a.mu)));
    }
    if !a.speedup.is_finite() || a.speedup < 0.0 {
        return Err(shift_sim::error::bad(
            "--speedup",
            format!("must be ≥ 0, got {}", a.speedup),
        ));
    }
    if a.beams == 0 {
        return Err(shift_sim::error::bad("--beams", "must be at least 1"));
    }
    Ok(RunOptions {
        http: a.http.clone(),
        token: a.token.clone(),
        zenoh: a.zenoh.clone(),
        keys: KeySpace::new(a.prefix.clone(), a.fleet.clone())
            .map_err(|e| shift_sim::error::bad("--prefix/--fleet", e.to_string()))?,
        mapping: mapping(&a.mapping)?,
        site: a.site.clone(),
        world: a.world.clone(),
        robots: a.robots,
        plan_per_robot: a.plan_per_robot,
        speedup: a.speedup,
        seed: a.seed,
        timeout_s: positive("--timeout-s", a.timeout_s)?,
        trace: a.trace.clone(),
        sim: SimConfig {
            dt: 0.05,
            odom_hz: positive("--odom-hz", a.odom_hz)?,
            scan_hz: positive("--scan-hz", a.scan_hz)?,
            lidar: Lidar {
                beams: a.beams,
                range_min: 0.05,
                range_max: positive("--range-m", a.range_m)?,
            },
            mu: a.mu,
        },
    })
}

#[tokio::main]
async fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info,zenoh=warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let args = Args::parse();
    let opts = match options(&args) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("shift-sim: {e}");
            return ExitCode::from(2);
        }
    };
    match run_and_write(&opts, &args.report).await {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("shift-sim: {e:#}");
            let bad = e
                .downcast_ref::<SimError>()
                .is_some_and(|s| matches!(s, SimError::BadInput { .. } | SimError::Map(_)));
            ExitCode::from(if bad { 2 } else { 1 })
        }
    }
}

async fn run_and_write(opts: &RunOptions, path: &std::path::Path) -> anyhow::Result<bool> {
    let report = run(opts).await?;
    let text = serde_json::to_string_pretty(&report)?;
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    for r in &report.robots {
        eprintln!(
            "{}: {} · {:.1} m in {:.1} s · covered {:.1} % · stops {} · skipped {} · collisions {} · corrections {} · version {:?}",
            r.id,
            if r.finished { "finished" } else { "NOT finished" },
            r.driven_m,
            r.time_s,
            r.covered_pct,
            r.stops,
            r.skipped_waypoints,
            r.collisions,
            r.corrections_applied,
            r.final_version
        );
    }
    eprintln!(
        "fleet: covered {:.1} % · {:.1} s · collisions {} · {:.1}× real time",
        report.fleet.covered_pct, report.fleet.time_s, report.fleet.collisions, report.fleet.speedup_achieved
    );
    Ok(report.all_finished())
}
