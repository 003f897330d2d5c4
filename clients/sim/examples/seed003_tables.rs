//! Seed 003's Tables 1 and 2 (coverage ratio and time consumption of random walk, "S" shape, spiral and the
//! proposed scheme, for two coverage widths w and the dynamic-tracking thresholds mu) reproduced with SHIFT's
//! own code, fully in-process: no daemon, no network.
//!
//! ```text
//! cargo run --release -p shift-sim --example seed003_tables
//! cargo run --release -p shift-sim --example seed003_tables -- --scene four-rooms --seed 7
//! cargo run --release -p shift-sim --example seed003_tables -- --scene four-rooms --w 3 --mu 0.2
//! RUST_LOG=shift_sim=info cargo run --release -p shift-sim --example seed003_tables  # the robot's give-ups
//! ```
//!
//! The whole default run (2 scenes × 2 widths × 3 thresholds × 4 methods, 48 simulated runs) takes about two
//! minutes of one core in release.
//!
//! What it does, per scene (default: `four-rooms` and `four-rooms-obstacles`, the analogues of the paper's
//! Scenario 1 and 2, from `../shared/scenarios` of the workspace):
//!
//! - Plans with `shift-planner` as `shiftd eval` does: "ours" is the default plan (`auto` decomposition, default
//!   order, targeted passes) and the "S" shape and spiral are the planner's baselines (one pattern over the whole
//!   map, no decomposition, no targeted passes). Each plan is speed-profiled (default limits: v_max 1 m/s,
//!   a_max 0.5 m/s²) and turned into the plan document a robot receives ([`shift_engine::to_document`]).
//! - Drives each plan document with the simulator's sans-IO core: one [`SimRobot`] in a [`Simulation`] of the
//!   scene's map, the plan handed to it as the fleet would ([`SimRobot::on_message`]), stepped unpaced with the
//!   default steps (0.05 s, laser at 10 Hz, its safety stop and detours on). The follower is seed 003's Alg. 2:
//!   once within `mu` of its target the robot takes the next one; `mu = 0` is stop-and-go, braking to a stop on
//!   every target and turning on the spot. The targets are the paper's: its robot goes from grid cell to grid
//!   cell, a robot diameter apart, so the document's waypoints (every tool_width / 4 or closer, for the speed
//!   profile) are thinned to at most one per tool width (= the diameter here) where the path runs straight
//!   (within [`CHORD_TOL_M`] of the line between two targets), keeping every corner, every change of waypoint
//!   kind and the last one; a kept target carries the slowest speed of the stretch it ends
//!   ([`paper_targets`]). Without that, stop-and-go
//!   would brake for every 7.5 cm of a 0.3 m tool's lanes and measure the document's sampling, not the method.
//! - Random walk: the planner's random-walk baseline (straight at a seeded random heading until the next step
//!   would come closer than the robot radius to a wall, then a new seeded random heading), long enough to drive
//!   for the time budget, driven by the same follower and cut at the **time the "S" shape run took in the same
//!   case** (same scene, w, mu); its time column is therefore that budget. Same `--seed` in every case.
//! - Coverage is the simulator's measure of what the tool really swept along the driven trace (tool on over
//!   `cover` stretches), over the coverable cells of DESIGN §6 (free cells within tool_width / 2 of a cell
//!   reachable with the robot's radius from the start) — the paper divides by the environment's area instead.
//!   Time is the simulated time at which the robot reached the end of its plan (a run still going after ten
//!   times its profiled duration plus ten minutes is stopped there and marked `*`). Waypoints the robot gave up
//!   (its safety stop held it for 10 s, [`shift_sim::robot::GIVE_UP_S`]) are listed under the table.
//!
//! The paper's widths w = 3 and 5 are relative sizes (its grid cell is the robot's diameter); here they are
//! tool widths of 0.3 m and 0.5 m (ratio 3:5) on a robot whose radius is half its tool (0.15 m and 0.25 m).
//! The paper's own figures for the matching scenario are printed below each of our tables, then one JSON line
//! with every figure. It asserts nothing: it is a bench.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Parser;
use serde_json::{Value, json};
use shift_client::robot::RobotMessage;
use shift_planner::baseline::{Baseline, run_baseline};
use shift_planner::geom::Point2;
use shift_planner::map::OccupancyGrid;
use shift_planner::pipeline::{NoMonitor, PlanOutput, PlanParams, plan_shaped};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::{SpeedLimits, SpeedParams, SpeedProfile, profile_path};
use shift_proto::{PlanDocument, WaypointDoc};
use shift_sim::measure::measure;
use shift_sim::robot::SimRobot;
use shift_sim::sim::{SimConfig, Simulation};
use shift_sim::world::World;
use shift_sim::world::file::{RobotSpecFile, WorldFile};
use shiftd::scene_io::{LoadedScene, load_scene};

/// The paper's w (relative) and our tool width for it, metres; the robot's radius is half the tool.
const WIDTHS: [(u32, f64); 2] = [(3, 0.3), (5, 0.5)];
/// How far the path between two of the paper's targets may stray from the straight line between them, metres
/// (a straight stretch, not a curve round a wall; see [`paper_targets`]).
const CHORD_TOL_M: f64 = 0.005;
/// The following thresholds, metres (0: stop-and-go).
const MUS: [f64; 3] = [0.0, 0.1, 0.2];
/// A planned run that has not finished after this many times its profiled duration, plus [`TIMEOUT_EXTRA_S`],
/// is stopped and reported unfinished.
const TIMEOUT_FACTOR: f64 = 10.0;
/// See [`TIMEOUT_FACTOR`], seconds.
const TIMEOUT_EXTRA_S: f64 = 600.0;

/// Command line.
#[derive(Debug, Parser)]
#[command(about = "Seed 003's Tables 1-2 with SHIFT's planner and simulator, in-process")]
struct Args {
    /// Folder of scenes (default: the workspace's ../shared/scenarios).
    #[arg(long)]
    scenes: Option<PathBuf>,
    /// Seed of the planner and of the random walk.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// A scene to run (repeatable; default four-rooms and four-rooms-obstacles).
    #[arg(long = "scene")]
    scene: Vec<String>,
    /// Only this paper width, 3 or 5 (repeatable; default both).
    #[arg(long = "w")]
    w: Vec<u32>,
    /// Only this following threshold, metres (repeatable; default 0, 0.1 and 0.2).
    #[arg(long = "mu")]
    mu: Vec<f64>,
}

impl Args {
    /// The cases asked for, in table order.
    fn cases(&self) -> Vec<Case> {
        let mut cases = Vec::new();
        for (w, tool_m) in WIDTHS {
            for mu in MUS {
                let wanted = (self.w.is_empty() || self.w.contains(&w))
                    && (self.mu.is_empty() || self.mu.iter().any(|m| (m - mu).abs() < 1e-9));
                if wanted {
                    cases.push(Case { w, tool_m, mu });
                }
            }
        }
        cases
    }
}

/// The compared methods, in the paper's column order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Method {
    RandomWalk,
    SShape,
    Spiral,
    Ours,
}

impl Method {
    const ALL: [Self; 4] = [Self::RandomWalk, Self::SShape, Self::Spiral, Self::Ours];

    fn name(self) -> &'static str {
        match self {
            Self::RandomWalk => "random-walk",
            Self::SShape => "s-shape",
            Self::Spiral => "spiral",
            Self::Ours => "ours",
        }
    }
}

/// One case of a table: a width and a threshold.
#[derive(Debug, Clone, Copy)]
struct Case {
    w: u32,
    tool_m: f64,
    mu: f64,
}

impl Case {
    fn radius_m(&self) -> f64 {
        self.tool_m / 2.0
    }
}

/// A plan as the robot receives it, with what the planner says of it.
struct Planned {
    doc: PlanDocument,
    /// Decomposition and pattern the planner used (`auto` says which member won).
    strategy: String,
    coverage_pct: f64,
    duration_s: f64,
}

/// What one simulated run measured.
#[derive(Debug, Clone)]
struct Outcome {
    method: Method,
    coverage_pct: f64,
    time_s: f64,
    finished: bool,
    driven_m: f64,
    stops: u64,
    collisions: u64,
    skipped: u64,
    plan_coverage_pct: f64,
    plan_duration_s: f64,
    waypoints: usize,
    strategy: String,
}

/// Every method's outcome for one case.
struct Row {
    case: Case,
    outcomes: Vec<Outcome>,
}

fn main() -> Result<()> {
    // RUST_LOG=shift_sim=info shows the robots' give-ups and safety stops; nothing by default.
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .init();
    let args = Args::parse();
    let root = args.scenes.clone().unwrap_or_else(default_scenes);
    let names = if args.scene.is_empty() {
        vec!["four-rooms".to_owned(), "four-rooms-obstacles".to_owned()]
    } else {
        args.scene.clone()
    };
    check_names(&names)?;
    let cases = args.cases();
    if cases.is_empty() {
        bail!("--w / --mu: no case left (w is 3 or 5, mu 0, 0.1 or 0.2)");
    }
    let started = Instant::now();
    let mut all = Vec::new();
    for name in &names {
        let scene = load_scene(&root.join(name)).with_context(|| format!("scene {name} under {}", root.display()))?;
        let rows = run_scene(&scene, &cases, args.seed)?;
        print_table(name, &rows);
        if let Some((label, paper)) = paper_for(name) {
            print_paper(label, paper);
        }
        all.push((name.clone(), rows));
    }
    let wall_s = started.elapsed().as_secs_f64();
    println!("{}", json_line(&all, args.seed, wall_s));
    eprintln!("wall time {wall_s:.1} s");
    Ok(())
}

/// `../shared/scenarios` of the workspace (two levels above this crate).
fn default_scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenarios")
}

/// Every case of one scene: plans per width, runs per threshold.
fn run_scene(scene: &LoadedScene, cases: &[Case], seed: u64) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    for (w, tool_m) in WIDTHS {
        let mine: Vec<Case> = cases.iter().copied().filter(|c| c.w == w).collect();
        if mine.is_empty() {
            continue;
        }
        let space = coverage_space(scene, tool_m)?;
        let plans = [
            (Method::SShape, baseline_plan(&space, Baseline::SShape, seed, 0.0)?),
            (Method::Spiral, baseline_plan(&space, Baseline::Spiral, seed, 0.0)?),
            (Method::Ours, our_plan(&space, seed)?),
        ];
        for case in mine {
            eprintln!("{}: w = {w} ({tool_m} m), mu = {} m", scene.name, case.mu);
            rows.push(run_case(&space, case, &plans, seed)?);
        }
    }
    Ok(rows)
}

/// The planned methods, then the random walk for the "S" shape's time.
fn run_case(space: &CoverageSpace, case: Case, plans: &[(Method, Planned)], seed: u64) -> Result<Row> {
    let mut outcomes = Vec::new();
    for (method, planned) in plans {
        let limit = TIMEOUT_FACTOR * planned.duration_s + TIMEOUT_EXTRA_S;
        outcomes.push(drive(space, case, *method, planned, limit));
    }
    let budget_s = outcomes
        .iter()
        .find(|o| o.method == Method::SShape)
        .map_or(0.0, |o| o.time_s);
    let limits = SpeedLimits::default();
    let walk = baseline_plan(space, Baseline::RandomWalk, seed, budget_s * limits.v_max_mps + 1.0)?;
    let mut random = drive(space, case, Method::RandomWalk, &walk, budget_s);
    // Cut at the budget is the walk's end, not a failure to finish.
    random.finished = true;
    outcomes.insert(0, random);
    Ok(Row { case, outcomes })
}

/// The scene's map with the case's robot: radius half the tool, from the scene's start.
fn coverage_space(scene: &LoadedScene, tool_m: f64) -> Result<CoverageSpace> {
    let shape = RobotShape {
        radius_m: tool_m / 2.0,
        tool_width_m: tool_m,
    };
    let start = Point2::new(scene.scene.start[0], scene.scene.start[1]);
    CoverageSpace::new(scene.map.grid.clone(), shape, start).context("coverage space")
}

fn speed_params(space: &CoverageSpace) -> SpeedParams {
    SpeedParams::new(SpeedLimits::default(), space.robot.tool_width_m)
}

/// The default plan (`shiftd eval`'s `auto` row), profiled.
fn our_plan(space: &CoverageSpace, seed: u64) -> Result<Planned> {
    let params = PlanParams {
        seed,
        ..PlanParams::default()
    };
    let (out, profile) = plan_shaped(space, &params, None, &speed_params(space), &mut NoMonitor).context("planning")?;
    Ok(planned("ours", space, &out, &profile))
}

/// A planner baseline, profiled (`length_m`: the random walk's length).
fn baseline_plan(space: &CoverageSpace, which: Baseline, seed: u64, length_m: f64) -> Result<Planned> {
    let out = run_baseline(space, which, seed, length_m).with_context(|| format!("baseline {}", which.name()))?;
    let profile = profile_path(space, &out.waypoints, None, &speed_params(space))
        .with_context(|| format!("profiling {}", which.name()))?;
    Ok(planned(which.name(), space, &out, &profile))
}

fn planned(id: &str, space: &CoverageSpace, out: &PlanOutput, profile: &SpeedProfile) -> Planned {
    let mut doc = shift_engine::to_document(&format!("p-{id}"), (space, out), profile, false, 0.0);
    doc.waypoints = paper_targets(&doc.waypoints, space.robot.tool_width_m);
    Planned {
        doc,
        strategy: format!("{}/{}", out.decomposition.name(), out.pattern.name()),
        coverage_pct: profile.metrics.coverage_pct,
        duration_s: profile.dwell.duration_s,
    }
}

/// The document's waypoints thinned to the paper's targets (see the module docs): from each kept target the
/// next is the furthest waypoint within `spacing_m` of path such that the waypoints between stay within
/// [`CHORD_TOL_M`] of the straight line to it and share its kind; the last one is kept. Each kept target
/// carries the slowest speed since the previous one.
fn paper_targets(wps: &[WaypointDoc], spacing_m: f64) -> Vec<WaypointDoc> {
    let n = wps.len();
    if n <= 2 {
        return wps.to_vec();
    }
    let step = |i: usize| (wps[i].x - wps[i - 1].x).hypot(wps[i].y - wps[i - 1].y);
    let chord_holds = |k: usize, j: usize| {
        let (a, b) = (Point2::new(wps[k].x, wps[k].y), Point2::new(wps[j].x, wps[j].y));
        (k + 1..j).all(|m| {
            wps[m].kind == wps[j].kind
                && shift_planner::geom::point_segment_distance(Point2::new(wps[m].x, wps[m].y), a, b) <= CHORD_TOL_M
        })
    };
    let mut out = vec![wps[0]];
    let mut k = 0;
    while k + 1 < n {
        let (mut j, mut run) = (k + 1, step(k + 1));
        while j + 1 < n && run + step(j + 1) <= spacing_m + 1e-9 && chord_holds(k, j + 1) {
            j += 1;
            run += step(j);
        }
        let mut w = wps[j];
        w.v = wps[k + 1..=j].iter().map(|w| w.v).fold(f64::INFINITY, f64::min);
        out.push(w);
        k = j;
    }
    out
}

/// The robot of a case, at the plan's start (the scene's dock), facing +x.
fn robot_spec(space: &CoverageSpace, case: Case) -> RobotSpecFile {
    let limits = SpeedLimits::default();
    RobotSpecFile {
        id: "r1".into(),
        start: [space.start.x, space.start.y, 0.0],
        radius: case.radius_m(),
        tool_width: case.tool_m,
        v_max: Some(limits.v_max_mps),
        a_max: Some(limits.a_max_mps2),
        w_max: None,
        region: None,
    }
}

fn world(grid: &OccupancyGrid, spec: &RobotSpecFile) -> World {
    World::new(
        grid.clone(),
        WorldFile {
            map: "map.yaml".into(),
            obstacles: Vec::new(),
            movers: Vec::new(),
            robots: vec![spec.clone()],
        },
    )
}

/// Drives `planned` until the robot finishes or `limit_s` simulated seconds pass; measures the swept area.
fn drive(space: &CoverageSpace, case: Case, method: Method, planned: &Planned, limit_s: f64) -> Outcome {
    let spec = robot_spec(space, case);
    let world = world(&space.grid, &spec);
    let grid = world.static_grid();
    let mut robot = SimRobot::new(spec, world.grid.geometry, case.mu);
    robot.on_message(RobotMessage::Plan(planned.doc.clone()));
    let config = SimConfig {
        mu: case.mu,
        ..SimConfig::default()
    };
    let mut sim = Simulation::new(world, vec![robot], config);
    while sim.t < limit_s && !sim.all_finished() {
        sim.step();
    }
    let coverage = measure(&grid, &sim.robots);
    let r = &sim.robots[0];
    Outcome {
        method,
        coverage_pct: coverage.fleet,
        time_s: r.stats.finished_at_s.unwrap_or(sim.t),
        finished: r.finished(),
        driven_m: r.stats.driven_m,
        stops: r.stats.stops,
        collisions: r.stats.collisions,
        skipped: r.stats.skipped_waypoints,
        plan_coverage_pct: planned.coverage_pct,
        plan_duration_s: planned.duration_s,
        waypoints: planned.doc.waypoints.len(),
        strategy: planned.strategy.clone(),
    }
}

/// `12m34s`; a trailing `*` marks a run stopped unfinished.
fn minutes(o: &Outcome) -> String {
    let s = o.time_s.round() as u64;
    let mark = if o.finished { "" } else { "*" };
    format!("{}m{:02}s{mark}", s / 60, s % 60)
}

fn print_table(scene: &str, rows: &[Row]) {
    let scenario = paper_for(scene).map_or("", |(label, _)| label);
    println!();
    println!("Scene {scene} (seed 003 {scenario}): ours, simulated");
    println!(
        "{:>2} {:>6} | {:>11} {:>8} {:>8} {:>8} | {:>11} {:>9} {:>9} {:>9}",
        "w", "mu(m)", "coverage %", "", "", "", "time", "", "", ""
    );
    println!(
        "{:>2} {:>6} | {:>11} {:>8} {:>8} {:>8} | {:>11} {:>9} {:>9} {:>9}",
        "", "", "random", "S-shape", "spiral", "ours", "random", "S-shape", "spiral", "ours"
    );
    for row in rows {
        let cov: Vec<String> = row.outcomes.iter().map(|o| format!("{:.2}", o.coverage_pct)).collect();
        let time: Vec<String> = row.outcomes.iter().map(minutes).collect();
        println!(
            "{:>2} {:>6.1} | {:>11} {:>8} {:>8} {:>8} | {:>11} {:>9} {:>9} {:>9}",
            row.case.w, row.case.mu, cov[0], cov[1], cov[2], cov[3], time[0], time[1], time[2], time[3]
        );
    }
    println!(
        "(w = 3: tool 0.30 m, radius 0.15 m; w = 5: tool 0.50 m, radius 0.25 m; random walk cut at the S-shape's time; * = stopped unfinished)"
    );
    print_plans(rows);
    print_notes(rows);
}

/// The planner's own figures of each width's plans (the path as planned, before anyone drives it).
fn print_plans(rows: &[Row]) {
    for (w, _) in WIDTHS {
        let Some(row) = rows.iter().find(|r| r.case.w == w) else {
            continue;
        };
        let plans: Vec<String> = row
            .outcomes
            .iter()
            .filter(|o| o.method != Method::RandomWalk)
            .map(|o| {
                let s = o.plan_duration_s.round() as u64;
                format!(
                    "{} [{}] {:.2} % {}m{:02}s",
                    o.method.name(),
                    o.strategy,
                    o.plan_coverage_pct,
                    s / 60,
                    s % 60
                )
            })
            .collect();
        println!(
            "  plans, w {w} (planner's coverage and profiled time): {}",
            plans.join(", ")
        );
    }
}

/// Runs with collisions, given-up waypoints or no finish, and the stop-and-go count.
fn print_notes(rows: &[Row]) {
    for row in rows {
        for o in &row.outcomes {
            if o.collisions > 0 || o.skipped > 0 || !o.finished {
                println!(
                    "  note: w {} mu {} {}: collisions {}, waypoints given up {}, finished {}",
                    row.case.w,
                    row.case.mu,
                    o.method.name(),
                    o.collisions,
                    o.skipped,
                    o.finished
                );
            }
        }
    }
}

/// The paper's rows for one scenario: (w, mu, coverage % [random, S, spiral, ours], minutes [same]).
type PaperRows = [(u32, f64, [f64; 4], [f64; 4]); 6];

/// Seed 003, Tables 1 and 2, Scenario 1 (no obstacles).
const PAPER_SCENARIO_1: PaperRows = [
    (3, 0.0, [74.30, 96.74, 97.18, 97.1], [80.10, 53.20, 55.40, 51.10]),
    (3, 0.1, [75.00, 97.18, 97.21, 98.01], [77.70, 48.80, 49.90, 48.30]),
    (3, 0.2, [70.16, 88.23, 89.70, 91.37], [75.20, 39.40, 39.60, 30.20]),
    (5, 0.0, [70.59, 88.84, 87.47, 90.11], [68.30, 38.90, 50.40, 30.10]),
    (5, 0.1, [71.28, 89.06, 89.18, 91.28], [63.20, 34.10, 34.8, 25.30]),
    (5, 0.2, [68.43, 87.58, 87.63, 89.63], [57.10, 27.10, 28.0, 17.40]),
];

/// Seed 003, Tables 1 and 2, Scenario 2 (obstacles).
const PAPER_SCENARIO_2: PaperRows = [
    (3, 0.0, [71.89, 91.76, 92.48, 95.10], [93.70, 60.10, 59.90, 57.40]),
    (3, 0.1, [72.73, 92.49, 93.51, 95.51], [89.50, 52.50, 53.2, 48.20]),
    (3, 0.2, [69.84, 88.22, 88.72, 90.52], [57.50, 35.90, 37.9, 28.50]),
    (5, 0.0, [65.78, 83.96, 85.09, 85.48], [69.20, 39.70, 53.20, 31.70]),
    (5, 0.1, [66.48, 85.08, 85.18, 87.18], [55.10, 32.10, 33.00, 23.50]),
    (5, 0.2, [65.14, 86.55, 86.52, 88.59], [43.20, 27.40, 28.90, 17.30]),
];

/// Seed 003, Tables 1 and 2, Scenario 3 (more obstacles).
const PAPER_SCENARIO_3: PaperRows = [
    (3, 0.0, [65.14, 93.36, 93.01, 95.78], [98.20, 63.40, 65.30, 60.30]),
    (3, 0.1, [66.26, 94.10, 94.04, 96.04], [85.40, 59.80, 58.20, 49.20]),
    (3, 0.2, [64.63, 87.28, 87.18, 89.73], [56.30, 38.90, 37.30, 28.10]),
    (5, 0.0, [61.56, 83.69, 84.12, 87.88], [99.80, 42.10, 56.80, 33.50]),
    (5, 0.1, [62.35, 84.59, 84.53, 88.86], [42.40, 36.30, 35.80, 27.10]),
    (5, 0.2, [60.46, 84.37, 83.23, 87.78], [40.20, 30.40, 29.30, 18.20]),
];

/// The paper's scenario a shared scene stands for.
fn paper_for(scene: &str) -> Option<(&'static str, &'static PaperRows)> {
    match scene {
        "four-rooms" => Some(("Scenario 1", &PAPER_SCENARIO_1)),
        "four-rooms-obstacles" => Some(("Scenario 2", &PAPER_SCENARIO_2)),
        "four-rooms-cluttered" => Some(("Scenario 3", &PAPER_SCENARIO_3)),
        _ => None,
    }
}

fn print_paper(label: &str, rows: &PaperRows) {
    println!("Seed 003 {label}, the paper's Tables 1 and 2 (Gazebo, w relative, time in minutes):");
    for (w, mu, cov, min) in rows {
        println!(
            "{w:>2} {mu:>6.1} | {:>11.2} {:>8.2} {:>8.2} {:>8.2} | {:>11.1} {:>9.1} {:>9.1} {:>9.1}",
            cov[0], cov[1], cov[2], cov[3], min[0], min[1], min[2], min[3]
        );
    }
}

fn outcome_json(scene: &str, case: Case, o: &Outcome) -> Value {
    json!({
        "scene": scene,
        "w": case.w,
        "tool_m": case.tool_m,
        "radius_m": case.radius_m(),
        "mu_m": case.mu,
        "method": o.method.name(),
        "coverage_pct": o.coverage_pct,
        "time_s": o.time_s,
        "finished": o.finished,
        "driven_m": o.driven_m,
        "stops": o.stops,
        "collisions": o.collisions,
        "skipped_waypoints": o.skipped,
        "plan_coverage_pct": o.plan_coverage_pct,
        "plan_duration_s": o.plan_duration_s,
        "plan_waypoints": o.waypoints,
        "strategy": o.strategy,
    })
}

fn paper_json(label: &str, rows: &PaperRows) -> Value {
    let rows: Vec<Value> = rows
        .iter()
        .flat_map(|(w, mu, cov, min)| {
            Method::ALL.iter().enumerate().map(move |(i, m)| {
                json!({"w": w, "mu_m": mu, "method": m.name(), "coverage_pct": cov[i], "time_min": min[i]})
            })
        })
        .collect();
    json!({"scenario": label, "rows": rows})
}

fn json_line(all: &[(String, Vec<Row>)], seed: u64, wall_s: f64) -> String {
    let ours: Vec<Value> = all
        .iter()
        .flat_map(|(scene, rows)| {
            rows.iter()
                .flat_map(move |r| r.outcomes.iter().map(move |o| outcome_json(scene, r.case, o)))
        })
        .collect();
    let paper: Vec<Value> = all
        .iter()
        .filter_map(|(scene, _)| paper_for(scene))
        .map(|(label, rows)| paper_json(label, rows))
        .collect();
    let line = json!({
        "bench": "seed003_tables",
        "seed": seed,
        "random_walk_budget": "time of the s-shape run of the same case",
        "wall_s": wall_s,
        "rows": ours,
        "paper": paper,
    });
    line.to_string()
}

/// Refuses an empty scene name (`--scene ""` would run the whole folder's parent).
fn check_names(names: &[String]) -> Result<()> {
    if names.iter().any(|n| n.trim().is_empty()) {
        bail!("--scene: empty scene name");
    }
    Ok(())
}
