//! Resume and replan of the remainder (issue 20's bench):
//! `cargo run --release -p shift-planner --example remainder_bench -- [SCENE_DIR | SIDE_M ...]` (default: the
//! malaga-telecom-hall scene and generated cluttered sites of 200 m and 224 m, 4 M and 5 M cells). Each
//! site is planned whole, the first half of the path (by length) is driven (stamped covered with the tool),
//! and the remainder is cleaned and replanned from where the robot stopped. Prints the cells, the pieces of
//! the uncovered area before and after cleaning, the area dropped and the area left, the time to clean and
//! to replan (split into building the replan's space, planning, and the speed profile, which together are
//! what `plan_remainder` does), the replanned length over the unfinished half's, and the replan's coverage of
//! what was kept. Then the same remainder is *resumed* ([`shift_planner::pipeline::resume`]): the whole plan's
//! profiled path (what a robot drives) walked for what still sweeps the remainder, timed whole and in its
//! steps (cleaning, space, the path walk; the rest is metrics and the speed profile), and once more as a
//! mission job runs it (`mission_resume_s`: `resume_fleet` from the site's grid, the robot's space built
//! too). `RESUME_ONLY=1` skips the replan from scratch. `STAGES=1` adds the replan's progress timeline
//! (progress, ms); `REPEAT=N` replans N times and reports the fastest (and makes the replan most of a
//! profiler's samples).

use std::path::Path;
use std::time::Instant;

use shift_planner::divide::FleetRobot;
use shift_planner::geom::{Point2, polyline_length};
use shift_planner::metrics::{CoverageRaster, evaluate};
use shift_planner::pipeline::remainder::{remainder_space, split_at_length};
use shift_planner::pipeline::resume::{FleetResume, Previous, ResumeParams, plan_resume, resume_fleet, resume_path};
use shift_planner::pipeline::{NoMonitor, PlanMonitor, PlanOutput, PlanParams, Waypoint, plan};
use shift_planner::remainder::{Remainder, RemainderParams, remainder};
use shift_planner::space::{CoverageSpace, RobotShape};

#[path = "common/scene.rs"]
mod common_scene;
use common_scene::scene;
use shift_planner::speed::{SpeedLimits, SpeedParams, profile_path};
use shift_planner::testing::cluttered_site;

fn generated(side: f64) -> Result<CoverageSpace, String> {
    let grid = cluttered_site(side, side, 0.1, (side * side / 100.0) as usize, 7).map_err(|e| e.to_string())?;
    let robot = RobotShape {
        radius_m: 0.3,
        tool_width_m: 0.6,
    };
    CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).map_err(|e| e.to_string())
}

/// Records elapsed milliseconds at every progress report.
struct Stages(Instant, Vec<(f64, u64)>);

impl PlanMonitor for Stages {
    fn progress(&mut self, fraction: f64) {
        self.1
            .push(((fraction * 100.0).round() / 100.0, self.0.elapsed().as_millis() as u64));
    }
}

/// One replan of the remainder, timed in its steps.
struct Replanned {
    rem: Remainder,
    out: PlanOutput,
    stages: Stages,
    remainder_s: f64,
    space_s: f64,
    plan_only_s: f64,
    profile_s: f64,
}

impl Replanned {
    fn total_s(&self) -> f64 {
        self.remainder_s + self.space_s + self.plan_only_s + self.profile_s
    }
}

fn replan_once(
    space: &CoverageSpace,
    params: &PlanParams,
    covered: &[bool],
    from: Point2,
) -> Result<Replanned, String> {
    let t = Instant::now();
    let rem = remainder(space, covered, &RemainderParams::default()).map_err(|e| e.to_string())?;
    let remainder_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let replan_space = remainder_space(space, &rem, from).map_err(|e| e.to_string())?;
    let space_s = t.elapsed().as_secs_f64();
    let speed = SpeedParams::new(SpeedLimits::default(), space.robot.tool_width_m);
    let mut stages = Stages(Instant::now(), Vec::new());
    // What `plan_shaped` does without an attribute map, timed in its two steps.
    let t = Instant::now();
    let out = plan(&replan_space, params, &mut stages).map_err(|e| e.to_string())?;
    let plan_only_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    profile_path(&replan_space, &out.waypoints, None, &speed).map_err(|e| e.to_string())?;
    let profile_s = t.elapsed().as_secs_f64();
    Ok(Replanned {
        rem,
        out,
        stages,
        remainder_s,
        space_s,
        plan_only_s,
        profile_s,
    })
}

fn bench(name: &str, space: &CoverageSpace) -> Result<(), String> {
    let params = PlanParams::default();
    let t = Instant::now();
    let whole = plan(space, &params, &mut NoMonitor).map_err(|e| e.to_string())?;
    let plan_s = t.elapsed().as_secs_f64();
    let path = whole.points();
    let (driven, rest) = split_at_length(&path, polyline_length(&path) / 2.0);
    let mut raster = CoverageRaster::new(*space.geometry(), space.robot.tool_width_m / 2.0);
    raster.stamp_polyline(&driven);
    let from = rest.first().copied().unwrap_or(space.start);

    // `REPEAT=N` replans N times (for profiling the replan alone) and reports the fastest run.
    let repeat = std::env::var("REPEAT")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(1)
        .max(1);
    resume_bench(name, space, &whole, repeat)?;
    if std::env::var("RESUME_ONLY").is_ok() {
        return Ok(());
    }
    let mut runs = Vec::with_capacity(repeat);
    for _ in 0..repeat {
        runs.push(replan_once(space, &params, raster.covered(), from)?);
    }
    runs.sort_by(|a, b| a.total_s().total_cmp(&b.total_s()));
    let best = runs.swap_remove(0);
    let (rem, out, stages) = (&best.rem, &best.out, &best.stages);
    let (remainder_s, space_s, plan_only_s, profile_s) =
        (best.remainder_s, best.space_s, best.plan_only_s, best.profile_s);
    let replan_s = space_s + plan_only_s + profile_s;
    if std::env::var("STAGES").is_ok() {
        eprintln!("{name} replan stages (progress, ms): {:?}", stages.1);
    }
    let unfinished = polyline_length(&rest);
    let m = out.metrics;
    println!(
        "{{\"scene\": \"{name}\", \"cells\": {}, \"whole_plan_s\": {plan_s:.2}, \"whole_length_m\": {:.0}, \
         \"uncovered_pieces_before\": {}, \"pieces_after\": {}, \"work_pieces\": {}, \"uncovered_m2\": {:.1}, \
         \"dropped_m2\": {:.2}, \"remainder_m2\": {:.1}, \"remainder_s\": {remainder_s:.3}, \"space_s\": {space_s:.3}, \"plan_s\": {plan_only_s:.3}, \"profile_s\": {profile_s:.3}, \"replan_s\": {replan_s:.3}, \
         \"total_s\": {:.3}, \"regions\": {}, \"replan_length_m\": {:.0}, \"unfinished_length_m\": {unfinished:.0}, \
         \"length_ratio\": {:.3}, \"coverage_pct\": {:.2}, \"collisions\": {}, \"chose\": \"{}/{}\"}}",
        space.geometry().len(),
        polyline_length(&path),
        rem.pieces_before,
        rem.pieces_after,
        rem.work_pieces,
        rem.uncovered_area_m2(),
        rem.dropped_area_m2(),
        rem.area_m2(),
        remainder_s + replan_s,
        out.regions.len(),
        m.length_m,
        m.length_m / unfinished.max(1e-9),
        m.coverage_pct,
        m.collisions,
        out.decomposition.name(),
        out.pattern.name(),
    );
    Ok(())
}

/// Resumes the whole plan's profiled path driven half-way (see the module docs), `repeat` times; prints the
/// fastest run's figures.
fn resume_bench(name: &str, space: &CoverageSpace, whole: &PlanOutput, repeat: usize) -> Result<(), String> {
    let speed = SpeedParams::new(SpeedLimits::default(), space.robot.tool_width_m);
    let profile = profile_path(space, &whole.waypoints, None, &speed).map_err(|e| e.to_string())?;
    let driven_path: Vec<Waypoint> = profile.waypoints.iter().map(|w| w.waypoint).collect();
    let pts: Vec<Point2> = driven_path.iter().map(|w| w.position).collect();
    let half = polyline_length(&pts) / 2.0;
    let (driven, rest) = split_at_length(&pts, half);
    let mut raster = CoverageRaster::new(*space.geometry(), space.robot.tool_width_m / 2.0);
    raster.stamp_polyline(&driven);
    let previous = Previous {
        path: &driven_path,
        reached: driven.len().saturating_sub(2),
        from: rest[0],
    };
    let mut best: Option<(f64, f64, f64, f64)> = None;
    let mut last = None;
    for _ in 0..repeat {
        let t = Instant::now();
        let rem = remainder(space, raster.covered(), &RemainderParams::default()).map_err(|e| e.to_string())?;
        let remainder_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let rspace = remainder_space(space, &rem, previous.from).map_err(|e| e.to_string())?;
        let space_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let walked = resume_path(
            space,
            &rem.keep,
            &driven_path,
            (previous.reached, rspace.start),
            RemainderParams::default().min_new_share,
        );
        let path_s = t.elapsed().as_secs_f64();
        drop(walked);
        let t = Instant::now();
        let resumed = plan_resume(
            space,
            raster.covered(),
            previous,
            &RemainderParams::default(),
            None,
            &speed,
        )
        .map_err(|e| e.to_string())?
        .ok_or("the plan could not be resumed")?;
        let total_s = t.elapsed().as_secs_f64();
        if best.is_none_or(|b| total_s < b.0) {
            best = Some((total_s, remainder_s, space_s, path_s));
        }
        last = Some(resumed);
    }
    let (Some((total_s, remainder_s, space_s, path_s)), Some((out, walked))) = (best, last) else {
        return Ok(());
    };
    // What a mission job runs (shift_engine's mission_job): the fleet resume from the site's grid, its
    // robot's space (clearance, reachable set) built first.
    let robot = FleetRobot::disc(space.start, space.robot, SpeedLimits::default());
    let t = Instant::now();
    let rebuilt = CoverageSpace::new(space.grid.clone(), space.robot, previous.from).map_err(|e| e.to_string())?;
    let space_build_s = t.elapsed().as_secs_f64();
    drop(rebuilt);
    let t = Instant::now();
    let fleet = resume_fleet(
        &space.grid,
        &[robot],
        (&[previous], &[]),
        raster.covered(),
        &RemainderParams::default(),
        None,
        &ResumeParams::default(),
    )
    .map_err(|e| e.to_string())?;
    let fleet_s = t.elapsed().as_secs_f64();
    if let FleetResume::Refused(why) = fleet {
        return Err(why);
    }
    let unfinished = polyline_length(&rest);
    let m = out.plan.metrics;
    // The two steps after the walk, timed apart on the result.
    let t = Instant::now();
    let _ = evaluate(&out.space, &out.plan.points());
    let metrics_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    profile_path(&out.space, &out.plan.waypoints, None, &speed).map_err(|e| e.to_string())?;
    let profile_s = t.elapsed().as_secs_f64();
    println!(
        "{{\"scene\": \"{name}\", \"resume_total_s\": {total_s:.3}, \"remainder_s\": {remainder_s:.3}, \"space_s\": {space_s:.3}, \
         \"path_s\": {path_s:.3}, \"mission_resume_s\": {fleet_s:.3}, \"of_which_space_s\": {space_build_s:.3}, \"metrics_s\": {metrics_s:.3}, \"profile_s\": {profile_s:.3}, \"runs\": {}, \"reused_m\": {:.0}, \"resumed_length_m\": {:.0}, \"unfinished_length_m\": {unfinished:.0}, \
         \"length_ratio\": {:.3}, \"coverage_pct\": {:.2}, \"unswept_m2\": {:.2}, \"collisions\": {}, \"profile_collisions\": {}, \"driven_plan_collisions\": {}}}",
        walked.runs,
        walked.reused_m,
        m.length_m,
        m.length_m / unfinished.max(1e-9),
        m.coverage_pct,
        (out.remainder.keep.iter().zip(&walked.swept))
            .filter(|&(&k, &s)| k && !s)
            .count() as f64
            * space.geometry().resolution.powi(2),
        m.collisions,
        out.profile.metrics.collisions,
        profile.metrics.collisions,
    );
    Ok(())
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() {
        let hall = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenarios/malaga-telecom-hall");
        args = vec![hall.display().to_string(), "200".into(), "224".into()];
    }
    for a in args {
        let (name, space) = match a.parse::<f64>() {
            Ok(side) => (format!("generated {side} m"), generated(side)),
            Err(_) => (
                Path::new(&a)
                    .file_name()
                    .map_or(a.clone(), |n| n.to_string_lossy().into_owned()),
                scene(Path::new(&a)),
            ),
        };
        if let Err(e) = space.and_then(|s| bench(&name, &s)) {
            eprintln!("{name}: {e}");
        }
    }
}
