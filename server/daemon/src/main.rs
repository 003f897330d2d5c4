//! `shiftd`: the SHIFT daemon's command line.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};

/// jemalloc, not glibc's malloc: the daemon allocates tens of megabytes per plan job and frees them when it
/// ends; glibc keeps each new high-water mark in its arenas (RSS stepped up by 8-50 MB with bursts of jobs in
/// the soak), jemalloc hands freed pages back after its decay time (10 s by default).
#[global_allocator]
static ALLOCATOR: tikv_jemallocator::Jemalloc = tikv_jemallocator::Jemalloc;

use clap::{Parser, Subcommand};
use shift_engine::to_document;
use shift_planner::decompose::DecompositionMethod;
use shift_planner::footprint::Footprint;
use shift_planner::geom::Point2;
use shift_planner::order::OrderMethod;
use shift_planner::pattern::PatternMethod;
use shift_planner::pipeline::{NoMonitor, Objective, PlanParams, plan_footprinted, plan_shaped};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::{SpeedLimits, SpeedParams};
use shiftd::eval::{TABLE_HEADER, run_eval, table_line};
use shiftd::eval_fleet::{FLEET_TABLE_HEADER, fleet_table_line, run_fleet_eval};
use shiftd::render::render_png;
use shiftd::scene_io::{load_attribute, load_map, load_scene, scene_attribute_path};

#[derive(Parser)]
#[command(name = "shiftd", version, about = "SHIFT: coverage planning for robot fleets")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the service: HTTP API, plan jobs, durable store (embedded defaults: 127.0.0.1:7878, ./shift-data,
    /// a demo site).
    Serve(ServeArgs),
    /// Plan one coverage path and write the plan JSON (DESIGN §5.1).
    Plan(Box<PlanArgs>),
    /// Evaluate every decomposition × order and the baselines on a folder of scenes.
    Eval(EvalArgs),
    /// Replay an MCAP recording onto Zenoh with its original timing, or through the engine (--into-engine).
    Replay(shiftd::replay::ReplayArgs),
    /// The whole fleet loop in one command: the daemon with the demo site and three simulated robots
    /// (`shift-sim`), one of them meeting a box the daemon does not know; prints progress and the final report.
    Demo(DemoArgs),
}

#[derive(clap::Args)]
struct DemoArgs {
    /// HTTP address of the demo daemon (the API stays reachable while the robots drive).
    #[arg(long, default_value = "127.0.0.1:7878")]
    bind: std::net::SocketAddr,
    /// The shift-sim binary (default: beside this executable; `cargo build --release -p shift-sim`).
    #[arg(long)]
    sim: Option<PathBuf>,
    /// Simulated seconds per real second.
    #[arg(long, default_value_t = 5.0)]
    speedup: f64,
    /// Folder for the demo's store, world file and report (kept afterwards).
    #[arg(long, default_value = "./shift-demo")]
    dir: PathBuf,
}

#[derive(clap::Args)]
struct ServeArgs {
    /// Listen address (overrides [http] bind).
    #[arg(long)]
    bind: Option<std::net::SocketAddr>,
    /// Data folder for the store (overrides [store] data_dir).
    #[arg(long)]
    data_dir: Option<PathBuf>,
    /// TOML config file (see deploy/shiftd.toml); embedded defaults without it.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Zenoh endpoint to listen on (repeatable; replaces [zenoh] listen), e.g. tcp/127.0.0.1:7447.
    #[arg(long)]
    zenoh_listen: Vec<String>,
    /// Zenoh endpoint to connect to (repeatable; replaces [zenoh] connect), e.g. tcp/10.0.0.5:7447.
    #[arg(long)]
    zenoh_connect: Vec<String>,
    /// Record everything ingested and decided to MCAP files in this folder (overrides [record] dir).
    #[arg(long)]
    record: Option<PathBuf>,
}

#[derive(clap::Args)]
struct PlanArgs {
    /// Scene folder holding scene.json (DESIGN §5.2).
    #[arg(long, conflicts_with = "map")]
    scene: Option<PathBuf>,
    /// map_server YAML (with --start, --robot-radius, --tool-width).
    #[arg(long)]
    map: Option<PathBuf>,
    /// Start / dock position "X,Y" in metres, map frame.
    #[arg(long, value_parser = parse_xy, allow_hyphen_values = true)]
    start: Option<Point2>,
    /// Robot radius, metres.
    #[arg(long)]
    robot_radius: Option<f64>,
    /// A robot that is not a disc: its convex footprint in the robot frame (Nav2's convention: x forward,
    /// metres, origin where it turns), "X,Y;X,Y;…", e.g. "0.6,0.4;-0.6,0.4;-0.6,-0.4;0.6,-0.4". Instead of
    /// --robot-radius.
    #[arg(long, conflicts_with = "robot_radius", allow_hyphen_values = true)]
    footprint: Option<String>,
    /// Tool width, metres.
    #[arg(long)]
    tool_width: Option<f64>,
    /// Decomposition: auto (of bcd, walls and one undivided spiral, the plan that covers ≥ 99 % with the best --objective), bcd, walls, voronoi, grid, none.
    #[arg(long, default_value = "auto")]
    decomposition: DecompositionMethod,
    /// Visiting order solver: two-opt, rrt, anneal.
    #[arg(long, default_value = "rrt")]
    order: OrderMethod,
    /// In-region pattern: lanes, spiral.
    #[arg(long, default_value = "lanes")]
    pattern: PatternMethod,
    /// Seed for every random choice.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// What the plan minimises among those that cover ≥ 99 %: time (the driving time under the speed
    /// limits), length, overlap, turns.
    #[arg(long, default_value = "time")]
    objective: Objective,
    /// Move a start whose traversable piece is small into the largest piece when it is this close, metres.
    #[arg(long)]
    snap_start_m: Option<f64>,
    /// Attribute map (grey PGM/PNG of the map's size, or JSON blobs {"blobs": [{x, y, sigma, amplitude}]});
    /// default: the scene's attribute, else A = 1 everywhere.
    #[arg(long)]
    attribute: Option<PathBuf>,
    /// Slowest speed on the path, m/s.
    #[arg(long, default_value_t = 0.1)]
    v_min: f64,
    /// Fastest speed, m/s.
    #[arg(long, default_value_t = 1.0)]
    v_max: f64,
    /// Largest acceleration (tangential, and lateral in curves), m/s².
    #[arg(long, default_value_t = 0.5)]
    a_max: f64,
    /// Keep the planned corners sharp (no B-spline rounding).
    #[arg(long)]
    no_smooth: bool,
    /// Output file ("-" for stdout).
    #[arg(long, default_value = "-")]
    out: PathBuf,
    /// Also render the plan to this PNG.
    #[arg(long)]
    render: Option<PathBuf>,
    #[command(flatten)]
    terrain: shiftd::terrain_cli::TerrainArgs,
}

#[derive(clap::Args)]
struct EvalArgs {
    /// Folder of scene folders.
    #[arg(long)]
    scenes: PathBuf,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    json: bool,
    /// Write a PNG per plan into this folder.
    #[arg(long)]
    render: Option<PathBuf>,
    /// Divide each scene among this many robots from spread docks instead (comma-separated sizes, e.g.
    /// 2,3,4): one row per scene and size with the fleet's durations, coverage and seam overlap.
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(usize))]
    robots: Vec<usize>,
}

/// "X,Y;X,Y;…" → vertices, metres.
fn parse_polygon(s: &str) -> Result<Vec<[f64; 2]>> {
    s.split(';')
        .filter(|v| !v.trim().is_empty())
        .map(|v| {
            let p = parse_xy(v).map_err(anyhow::Error::msg)?;
            Ok([p.x, p.y])
        })
        .collect()
}

fn parse_xy(s: &str) -> Result<Point2, String> {
    let (x, y) = s.split_once(',').ok_or_else(|| format!("expected X,Y, got {s:?}"))?;
    let x: f64 = x.trim().parse().map_err(|e| format!("bad x in {s:?}: {e}"))?;
    let y: f64 = y.trim().parse().map_err(|e| format!("bad y in {s:?}: {e}"))?;
    Ok(Point2::new(x, y))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // The service logs its life at info; the one-shot commands only warnings. RUST_LOG overrides both.
    let default_filter = match cli.command {
        Command::Serve(_) | Command::Demo(_) => "info,tower_http=warn",
        _ => "warn",
    };
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default_filter)),
        )
        .with_writer(std::io::stderr)
        .init();
    let result = match cli.command {
        Command::Serve(args) => cmd_serve(args),
        Command::Plan(args) => cmd_plan(*args),
        Command::Eval(args) => cmd_eval(args),
        Command::Replay(args) => shiftd::replay::run_cli(args).map_err(anyhow::Error::from),
        Command::Demo(args) => cmd_demo(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line: what is wrong and where.
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn cmd_demo(args: DemoArgs) -> Result<()> {
    let sim = match args.sim.or_else(shiftd::demo::sim_beside_me) {
        Some(sim) => sim,
        None => anyhow::bail!(
            "no shift-sim beside shiftd: build both (`cargo build --release -p shiftd -p shift-sim`) or pass --sim PATH"
        ),
    };
    anyhow::ensure!(
        args.speedup.is_finite() && args.speedup > 0.0,
        "--speedup: {} is not a positive number",
        args.speedup
    );
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .thread_name("shiftd-io")
        .build()
        .context("starting the tokio runtime")?;
    let report = runtime.block_on(async move {
        survive_file_size_limit();
        shiftd::demo::run(shiftd::demo::DemoArgs {
            bind: args.bind,
            sim,
            speedup: args.speedup,
            dir: args.dir,
        })
        .await
    })?;
    println!("{}", shiftd::demo::table(&report));
    Ok(())
}

fn cmd_serve(args: ServeArgs) -> Result<()> {
    let mut config = match &args.config {
        Some(path) => shiftd::Config::load(path)?,
        None => shiftd::Config::default(),
    };
    if let Some(bind) = args.bind {
        config.http.bind = bind;
    }
    if let Some(dir) = args.data_dir {
        config.store.data_dir = dir;
    }
    if !args.zenoh_listen.is_empty() {
        config.zenoh.listen = args.zenoh_listen;
    }
    if !args.zenoh_connect.is_empty() {
        config.zenoh.connect = args.zenoh_connect;
    }
    if let Some(dir) = args.record {
        config.record.dir = dir;
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .thread_name("shiftd-io")
        .build()
        .context("starting the tokio runtime")?;
    shiftd::allocator::purge_idle_arenas();
    shiftd::allocator::spawn_allocator_stats();
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(config.http.bind)
            .await
            .with_context(|| format!("binding {}", config.http.bind))?;
        survive_file_size_limit();
        shiftd::run(config, listener, shutdown_signal()).await?;
        Ok(())
    })
}

/// A write past the process's file-size limit (`ulimit -f`, RLIMIT_FSIZE) raises SIGXFSZ, whose default is to
/// end the process. With a handler the write fails with EFBIG instead, which the store answers as a full disk
/// (507) while reads go on being served.
fn survive_file_size_limit() {
    #[cfg(unix)]
    match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::from_raw(libc::SIGXFSZ)) {
        Ok(mut s) => {
            tokio::spawn(async move {
                while s.recv().await.is_some() {
                    tracing::warn!("a write went past the file-size limit (SIGXFSZ): the store reports it as full");
                }
            });
        }
        Err(e) => tracing::warn!("SIGXFSZ cannot be caught, a file-size limit would end shiftd: {e}"),
    }
}

/// Resolves on SIGINT (Ctrl-C) or SIGTERM.
async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = term => {},
    }
    tracing::info!("shutdown requested");
}

fn cmd_plan(args: PlanArgs) -> Result<()> {
    let limits = SpeedLimits::new(args.v_min, args.v_max, args.a_max);
    limits.validate().context("speed limits (--v-min, --v-max, --a-max)")?;
    if args.terrain.terrain.is_some() {
        let common = shiftd::terrain_cli::TerrainCommon {
            tool_width_m: args.tool_width,
            robot_radius_m: args.robot_radius,
            start: args.start,
            limits,
            attribute: args.attribute.clone(),
            seed: args.seed,
            out: args.out.clone(),
            render: args.render.clone(),
        };
        return Ok(shiftd::terrain_cli::run(&args.terrain, &common)?);
    }
    let footprint = match &args.footprint {
        Some(text) => Some(Footprint::new(&parse_polygon(text).context("--footprint")?).context("--footprint")?),
        None => None,
    };
    // With a footprint the radius is set from it once the map's resolution is known.
    let radius = args.robot_radius.or(footprint.as_ref().map(|_| 0.0));
    let (grid, start, mut robot, mut warnings, scene_attribute) = if let Some(dir) = &args.scene {
        let s = load_scene(dir)?;
        let robot = RobotShape {
            radius_m: radius.unwrap_or(s.scene.robot_radius),
            tool_width_m: args.tool_width.unwrap_or(s.scene.tool_width),
        };
        let start = args.start.unwrap_or(Point2::new(s.scene.start[0], s.scene.start[1]));
        let attribute = scene_attribute_path(&s);
        (s.map.grid, start, robot, s.map.warnings, attribute)
    } else if let Some(map) = &args.map {
        let m = load_map(map)?;
        let start = args.start.context("--start X,Y is required with --map")?;
        let robot = RobotShape {
            radius_m: radius.context("--robot-radius or --footprint is required with --map")?,
            tool_width_m: args.tool_width.context("--tool-width is required with --map")?,
        };
        (m.grid, start, robot, m.warnings, None)
    } else {
        bail!("give --scene DIR, --map FILE.yaml or --terrain CLOUD");
    };
    let attribute = match args.attribute.as_ref().or(scene_attribute.as_ref()) {
        Some(path) => Some(load_attribute(path, grid.geometry)?),
        None => None,
    };
    if let Some(f) = &footprint {
        // Planned in the space of its inscribed planning radius; the band up to its circumscribed disc is decided
        // by heading (planner::pipeline::footprinted).
        robot.radius_m = f.planning_radius_m(grid.geometry.resolution);
    }
    let t = Instant::now();
    let space = CoverageSpace::with_start_snap(grid, robot, start, args.snap_start_m)?;
    let params = PlanParams {
        decomposition: args.decomposition,
        order: args.order,
        pattern: args.pattern,
        seed: args.seed,
        objective: args.objective,
        limits,
        ..PlanParams::default()
    };
    let mut speed = SpeedParams::new(limits, space.robot.tool_width_m);
    if args.no_smooth {
        speed.smooth = None;
    }
    let (out, profile) = match &footprint {
        Some(f) => plan_footprinted(&space, f, &params, attribute.as_ref(), &speed, &mut NoMonitor)?,
        None => plan_shaped(&space, &params, attribute.as_ref(), &speed, &mut NoMonitor)?,
    };
    let ms = t.elapsed().as_secs_f64() * 1e3;
    warnings.extend(out.warnings.iter().cloned());
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let doc = to_document("p-cli", (&space, &out), &profile, attribute.is_some(), ms);
    let text = serde_json::to_string_pretty(&doc)?;
    if args.out.as_os_str() == "-" {
        println!("{text}");
    } else {
        std::fs::write(&args.out, text).with_context(|| format!("writing {}", args.out.display()))?;
    }
    if let Some(png) = &args.render {
        render_png(&space, &out, Some((&profile, &limits)), png, 1200)?;
    }
    let m = profile.metrics;
    eprintln!(
        "coverage {:.2} %  overlap {:.2} %  length {:.1} m  turns {}  collisions {}  regions {}  compute {:.0} ms  ({} + {})",
        m.coverage_pct,
        m.overlap_pct,
        m.length_m,
        m.turns,
        m.collisions,
        out.regions.len(),
        ms,
        out.decomposition.name(),
        out.pattern.name()
    );
    let d = profile.dwell;
    eprintln!(
        "speed: duration {:.0} s  {}  corners rounded {} sharp {}{}",
        d.duration_s,
        if attribute.is_some() {
            format!(
                "dwell_cv {:.3} (constant speed {:.3})",
                d.dwell_cv, d.dwell_cv_const_speed
            )
        } else {
            "no attribute: fastest profile, no dwell figures".to_owned()
        },
        profile.rounded_corners,
        profile.sharp_corners,
        if profile.smoothing_reverted {
            " (smoothing reverted)"
        } else {
            ""
        }
    );
    let st = out.stats;
    eprintln!(
        "length by purpose: pattern {:.1} m, passes {:.1} m, visits {}, steps {:.1} m, transit {:.1} m",
        st.pattern_m, st.passes_m, st.visits, st.steps_m, st.transit_m
    );
    Ok(())
}

/// Prints one evaluation row: a JSON line, or `line(row)` under the table's header.
fn print_row<R: serde::Serialize>(json: bool, row: &R, line: impl Fn(&R) -> String) {
    if json {
        match serde_json::to_string(row) {
            Ok(s) => println!("{s}"),
            Err(e) => eprintln!("error: {e}"),
        }
    } else {
        println!("{}", line(row));
    }
}

fn cmd_eval(args: EvalArgs) -> Result<()> {
    if !args.robots.is_empty() {
        if let Some(bad) = args.robots.iter().find(|&&n| n == 0) {
            anyhow::bail!("--robots: every fleet size must be at least 1, got {bad}");
        }
        if !args.json {
            println!("{FLEET_TABLE_HEADER}");
        }
        run_fleet_eval(&args.scenes, &args.robots, args.render.as_deref(), |row| {
            print_row(args.json, row, fleet_table_line)
        })?;
        return Ok(());
    }
    if !args.json {
        println!("{TABLE_HEADER}");
    }
    run_eval(&args.scenes, args.render.as_deref(), |row| {
        print_row(args.json, row, table_line)
    })?;
    Ok(())
}
