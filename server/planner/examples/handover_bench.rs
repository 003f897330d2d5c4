//! Live re-division when a robot is lost (issue 20's bench):
//! `cargo run --release -p shift-planner --example handover_bench -- [SIDE_M | SCENE_DIR] [ROBOTS] [DRIVEN]`
//! (default the generated cluttered site of 224 m, 5 M cells, 4 robots docked round its rim, each 30 %
//! along its plan; a scene folder's robots get spread docks, [`spread_docks`]).
//! The fleet is planned, every robot drives its share of its plan (stamped covered with the tool), and the
//! second robot is lost. What the mission job does then is timed: the others' plans resumed with the lost
//! plan's unfinished lanes handed over ([`resume_fleet`] with a [`Lost`]), against dividing and planning the
//! remainder from scratch ([`plan_fleet_remainder`]). Prints, for both, the time, the planned durations
//! (longest, ratio), the union coverage of what is left, and the length of the new paths over the unfinished
//! length of the old ones (the lost robot's included). `REPEAT=N` hands over N times (the fastest is
//! reported); `HANDOVER_ONLY=1` skips the new division; `RENDER=file.png` draws the handover (the others'
//! new paths over the lost robot's unfinished path in red).

use std::path::Path;
use std::time::Instant;

use shift_planner::divide::FleetRobot;
use shift_planner::divide::docks::spread_docks;
use shift_planner::geom::{Point2, polyline_length};
use shift_planner::metrics::CoverageRaster;
use shift_planner::pipeline::fleet::{FleetMetrics, FleetParams, plan_fleet};
use shift_planner::pipeline::remainder::{plan_fleet_remainder, split_at_length};
use shift_planner::pipeline::resume::{FleetResume, Lost, Previous, ResumeParams, resume_fleet};
use shift_planner::pipeline::{NoMonitor, PlanParams, Waypoint};
use shift_planner::remainder::RemainderParams;
use shift_planner::space::RobotShape;
use shift_planner::speed::SpeedLimits;
use shift_planner::testing::{cluttered_site, rim_docks};

#[path = "common/scene.rs"]
mod common_scene;
use common_scene::scene;

fn json(name: &str, seconds: f64, m: &FleetMetrics, length_m: f64, unfinished_m: f64) -> String {
    format!(
        "\"{name}\": {{\"s\": {seconds:.3}, \"longest_s\": {:.0}, \"duration_ratio\": {:.3}, \"union_coverage_pct\": {:.2}, \"length_ratio\": {:.3}}}",
        m.durations_s.iter().copied().fold(0.0, f64::max),
        m.duration_ratio,
        m.union_coverage_pct,
        length_m / unfinished_m.max(1e-9)
    )
}

/// What `previous` had left: its path from the waypoint it reached.
fn paths_rest(previous: &Previous<'_>) -> Vec<Point2> {
    previous.path[previous.reached..].iter().map(|w| w.position).collect()
}

/// A picture of the handover (`RENDER=file.png`): walls black, swept ground grey, each new path in its
/// robot's colour over the lost robot's unfinished path in red.
fn render(
    grid: &shift_planner::map::OccupancyGrid,
    covered: &[bool],
    paths: &[Vec<Point2>],
    lost: &[Point2],
    out: &Path,
) -> Result<(), String> {
    let g = grid.geometry;
    let mut img = image::RgbImage::from_pixel(g.width as u32, g.height as u32, image::Rgb([255, 255, 255]));
    let put = |img: &mut image::RgbImage, i: usize, px: [u8; 3]| {
        let c = g.cell(i);
        img.put_pixel(c.x as u32, (g.height - 1 - c.y) as u32, image::Rgb(px));
    };
    for (i, (state, &swept)) in grid.cells.iter().zip(covered).enumerate() {
        if *state != shift_planner::map::CellState::Free {
            put(&mut img, i, [0, 0, 0]);
        } else if swept {
            put(&mut img, i, [200, 200, 200]);
        }
    }
    let draw = |img: &mut image::RgbImage, pts: &[Point2], px: [u8; 3]| {
        for w in pts.windows(2) {
            let n = ((w[1] - w[0]).norm() / (g.resolution / 2.0)).ceil().max(1.0) as usize;
            for k in 0..=n {
                let p = w[0] + (w[1] - w[0]) * (k as f64 / n as f64);
                if let Some(c) = g.locate(p) {
                    put(img, g.index(c), px);
                }
            }
        }
    };
    let colours = [
        [31, 119, 180],
        [44, 160, 44],
        [148, 103, 189],
        [255, 127, 14],
        [23, 190, 207],
    ];
    // Red under the new paths: what shows red is a stretch of the lost plan nobody drives now.
    draw(&mut img, lost, [214, 39, 40]);
    for (k, p) in paths.iter().enumerate() {
        draw(&mut img, p, colours[k % colours.len()]);
    }
    img.save(out).map_err(|e| e.to_string())
}

fn main() -> Result<(), String> {
    let raw: Vec<String> = std::env::args().skip(1).collect();
    let site = raw.first().cloned().unwrap_or_else(|| "224".into());
    let args: Vec<f64> = raw.iter().skip(1).filter_map(|a| a.parse().ok()).collect();
    let n = args.first().map_or(4, |&n| n as usize).max(2);
    let share = args.get(1).copied().unwrap_or(0.3).clamp(0.0, 1.0);
    let (name, grid, shape, docks) = match site.parse::<f64>() {
        Ok(side) => {
            let grid = cluttered_site(side, side, 0.1, (side * side / 100.0) as usize, 7).map_err(|e| e.to_string())?;
            let shape = RobotShape {
                radius_m: 0.3,
                tool_width_m: 0.6,
            };
            (format!("generated {side} m"), grid, shape, rim_docks(side, n))
        }
        Err(_) => {
            let dir = Path::new(&site);
            let space = scene(dir)?;
            let name = dir
                .file_name()
                .map_or(site.clone(), |n| n.to_string_lossy().into_owned());
            (name, space.grid.clone(), space.robot, spread_docks(&space, n))
        }
    };
    let robots: Vec<FleetRobot> = (docks.into_iter())
        .map(|start| FleetRobot::disc(start, shape, SpeedLimits::default()))
        .collect();
    let t = Instant::now();
    let fleet =
        plan_fleet(&grid, &robots, &PlanParams::default(), None, &FleetParams::default()).map_err(|e| e.to_string())?;
    let plan_s = t.elapsed().as_secs_f64();
    let paths: Vec<Vec<Waypoint>> = (fleet.plans.iter())
        .map(|(_, p)| p.waypoints.iter().map(|w| w.waypoint).collect())
        .collect();
    // Every robot drives `share` of its plan.
    let mut raster = CoverageRaster::new(grid.geometry, shape.tool_width_m / 2.0);
    let mut previous = Vec::new();
    let mut unfinished_m = 0.0;
    for path in &paths {
        let pts: Vec<Point2> = path.iter().map(|w| w.position).collect();
        let at = share * polyline_length(&pts);
        let (driven, rest) = split_at_length(&pts, at);
        raster.stamp_polyline(&driven);
        unfinished_m += polyline_length(&rest);
        previous.push(Previous {
            path,
            reached: driven.len().saturating_sub(2),
            from: rest[0],
        });
    }
    let covered = raster.covered().to_vec();
    let lost_k = 1;
    let lost = [Lost {
        robot: &robots[lost_k],
        previous: previous[lost_k],
    }];
    let going: Vec<FleetRobot> = (robots.iter().zip(&previous).enumerate())
        .filter(|&(k, _)| k != lost_k)
        .map(|(_, (r, p))| FleetRobot {
            start: p.from,
            ..r.clone()
        })
        .collect();
    let going_prev: Vec<Previous<'_>> = (previous.iter().enumerate())
        .filter(|&(k, _)| k != lost_k)
        .map(|(_, p)| *p)
        .collect();
    let rp = RemainderParams::default();
    // `REPEAT=N` hands over N times and reports the fastest (and makes it most of a profiler's samples).
    let repeat = std::env::var("REPEAT")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(1)
        .max(1);
    let mut handover_s = f64::INFINITY;
    let mut handed = None;
    for _ in 0..repeat {
        let t = Instant::now();
        let once = resume_fleet(
            &grid,
            &going,
            (&going_prev, &lost),
            &covered,
            &rp,
            None,
            &ResumeParams::default(),
        )
        .map_err(|e| e.to_string())?;
        handover_s = handover_s.min(t.elapsed().as_secs_f64());
        handed = Some(once);
    }
    let handed = handed.ok_or("no run")?;
    let handover = match &handed {
        FleetResume::Resumed(r) => {
            let len: f64 = r.fleet.plans.iter().map(|(o, _)| o.metrics.length_m).sum();
            json("handover", handover_s, &r.fleet.metrics, len, unfinished_m)
        }
        FleetResume::Refused(why) => format!("\"handover\": {{\"s\": {handover_s:.3}, \"refused\": {why:?}}}"),
    };
    if let (Ok(png), FleetResume::Resumed(r)) = (std::env::var("RENDER"), &handed) {
        let paths: Vec<Vec<Point2>> = r.fleet.plans.iter().map(|(_, p)| p.points()).collect();
        let lost_rest: Vec<Point2> = paths_rest(&previous[lost_k]);
        render(&grid, &covered, &paths, &lost_rest, Path::new(&png))?;
    }
    if std::env::var("HANDOVER_ONLY").is_ok() {
        println!("{{\"site\": {name:?}, \"robots\": {n}, {handover}}}");
        return Ok(());
    }
    let t = Instant::now();
    let scratch = plan_fleet_remainder(
        &grid,
        &going,
        &covered,
        (&PlanParams::default(), &rp),
        None,
        &FleetParams::default(),
        &mut NoMonitor,
    )
    .map_err(|e| e.to_string())?;
    let scratch_s = t.elapsed().as_secs_f64();
    let len: f64 = scratch.fleet.plans.iter().map(|(o, _)| o.metrics.length_m).sum();
    println!(
        "{{\"site\": {name:?}, \"cells\": {}, \"robots\": {n}, \"driven\": {share}, \"fleet_plan_s\": {plan_s:.1}, \"covered_pct\": {:.1}, {handover}, {}}}",
        grid.cells.len(),
        {
            let coverable = &fleet.division.coverable;
            let total = coverable.iter().filter(|&&c| c).count().max(1);
            (covered.iter().zip(coverable)).filter(|&(&a, &c)| a && c).count() as f64 / total as f64 * 100.0
        },
        json("new_division", scratch_s, &scratch.fleet.metrics, len, unfinished_m)
    );
    Ok(())
}
