//! Footprint plans against disc plans: `cargo run --profile test -p shift-planner --example footprint_stats
//! -- [DIR ...]`. With scene folders (a `scene.json` naming `map` and `start`), or `rooms:D` (four rooms of
//! 8 m × 8 m whose doorways are D metres wide), plans each for a rectangle `FP=length,width` (metres, default
//! 0.6,0.4) with a tool as wide as the rectangle (`TOOL` overrides) and for the disc of its circumscribed
//! radius; without arguments, the two-rooms doorway (0.8 × 1.2 m rectangle, 1.0 m doorway) at 0°, 17°, 33°,
//! 45° and 71°. Prints coverage (of the inscribed space's coverable cells, and per room for the doorway),
//! footprint collisions (the disc plan's too), length, driving time and planning time. `LANES=disc|turning|
//! inscribed` forces where patterns go, `DECOMP` / `PATTERN` the strategy, `DUMP=DIR` writes PNGs.

use std::path::Path;
use std::time::Instant;

use shift_planner::footprint::{Footprint, FootprintCheck};
use shift_planner::geom::Point2;
use shift_planner::map::{OccupancyGrid, load_ros_map};
use shift_planner::metrics::CoverageRaster;
use shift_planner::pipeline::{LaneSpace, NoMonitor, PlanParams, plan_footprinted_with, plan_shaped};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::{SpeedLimits, SpeedParams};
use shift_planner::testing::two_rooms;

#[derive(serde::Deserialize)]
struct Scene {
    map: String,
    start: [f64; 2],
}

fn load(dir: &Path) -> Result<(OccupancyGrid, Point2), String> {
    let text = std::fs::read_to_string(dir.join("scene.json")).map_err(|e| e.to_string())?;
    let scene: Scene = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let yaml = std::fs::read_to_string(dir.join(&scene.map)).map_err(|e| e.to_string())?;
    let map = load_ros_map(&yaml, |img| std::fs::read(dir.join(img)).map_err(|e| e.to_string()))
        .map_err(|e| e.to_string())?;
    Ok((map.grid, Point2::new(scene.start[0], scene.start[1])))
}

/// Plans `grid` for `fp` and for its circumscribed disc; prints both. `rooms`: coverage per part.
fn compare(
    name: &str,
    grid: &OccupancyGrid,
    start: Point2,
    fp: &Footprint,
    tool: f64,
    parts: &[(&str, &dyn Fn(Point2) -> bool)],
) {
    let res = grid.geometry.resolution;
    let speed = SpeedParams::new(SpeedLimits::default(), tool);
    let mut params = PlanParams::default();
    if let Some(d) = std::env::var("DECOMP").ok().and_then(|d| d.parse().ok()) {
        params.decomposition = d;
    }
    if let Some(p) = std::env::var("PATTERN").ok().and_then(|p| p.parse().ok()) {
        params.pattern = p;
    }
    let robot = RobotShape {
        radius_m: fp.planning_radius_m(res),
        tool_width_m: tool,
    };
    let space = match CoverageSpace::new(grid.clone(), robot, start) {
        Ok(s) => s,
        Err(e) => return println!("{name}: {e}"),
    };
    let t = Instant::now();
    let lanes = match std::env::var("LANES").as_deref() {
        Ok("disc") => LaneSpace::Disc,
        Ok("turning") => LaneSpace::Turning,
        Ok("inscribed") => LaneSpace::Inscribed,
        _ => LaneSpace::Auto,
    };
    match plan_footprinted_with(&space, fp, lanes, &params, None, &speed, &mut NoMonitor) {
        Ok((out, profile)) => {
            let secs = t.elapsed().as_secs_f64();
            let exact = FootprintCheck::new(&space.grid, &space.clearance, fp).expect("check");
            let pts = profile.points();
            if let Ok(dir) = std::env::var("DUMP") {
                let file = format!("{dir}/{}.png", name.replace(['/', ' ', '°'], "_"));
                dump_png(&space, &pts, &file);
            }
            let mut raster = CoverageRaster::new(*space.geometry(), tool / 2.0);
            raster.stamp_polyline(&pts);
            let g = space.geometry();
            let share: Vec<String> = parts
                .iter()
                .map(|(label, inside)| {
                    let cells: Vec<usize> = (0..g.len())
                        .filter(|&i| space.coverable[i] && inside(g.center_of(i)))
                        .collect();
                    let hit = cells.iter().filter(|&&i| raster.is_covered(i)).count();
                    format!("{label} {:.1} %", 100.0 * hit as f64 / cells.len().max(1) as f64)
                })
                .collect();
            println!(
                "{name} footprint {:?}: coverage {:.1} % [{}], collisions {}, length {:.1} m, duration {:.1} s, \
                 planned in {:.2} s; corners rounded {} sharp {}{}, turns {}; {:?}/{:?}; {}",
                fp.vertices().iter().map(|v| (v.x, v.y)).collect::<Vec<_>>(),
                profile.metrics.coverage_pct,
                share.join(", "),
                exact.count_collisions(&pts),
                profile.metrics.length_m,
                profile.dwell.duration_s,
                secs,
                profile.rounded_corners,
                profile.sharp_corners,
                if profile.smoothing_reverted { " (reverted)" } else { "" },
                profile.metrics.turns,
                out.decomposition,
                out.pattern,
                out.warnings.last().map_or("", String::as_str)
            );
        }
        Err(e) => println!("{name} footprint: {e}"),
    }
    let disc = RobotShape {
        radius_m: fp.circumscribed_radius_m(),
        tool_width_m: tool,
    };
    let t = Instant::now();
    match CoverageSpace::new(grid.clone(), disc, start)
        .and_then(|s| plan_shaped(&s, &params, None, &speed, &mut NoMonitor).map(|r| (s, r)))
    {
        Ok((disc_space, (out, profile))) => {
            // Coverage of the footprint's coverable cells, to compare like with like.
            let mut raster = CoverageRaster::new(*space.geometry(), tool / 2.0);
            raster.stamp_polyline(&profile.points());
            let g = space.geometry();
            let cells = (0..g.len()).filter(|&i| space.coverable[i]).count();
            let hit = (0..g.len())
                .filter(|&i| space.coverable[i] && raster.is_covered(i))
                .count();
            let exact = FootprintCheck::new(&space.grid, &space.clearance, fp).expect("check");
            println!(
                "{name} disc r {:.3} m: coverage {:.1} % of its own coverable, {:.1} % of the footprint's, \
                 footprint collisions {}, length {:.1} m, duration {:.1} s, planned in {:.2} s; corners rounded {} \
                 sharp {}, turns {}; {:?}/{:?}",
                disc_space.robot.radius_m,
                profile.metrics.coverage_pct,
                100.0 * hit as f64 / cells.max(1) as f64,
                exact.count_collisions(&profile.points()),
                profile.metrics.length_m,
                profile.dwell.duration_s,
                t.elapsed().as_secs_f64(),
                profile.rounded_corners,
                profile.sharp_corners,
                profile.metrics.turns,
                out.decomposition,
                out.pattern
            );
        }
        Err(e) => println!("{name} disc r {:.3} m: {e}", fp.circumscribed_radius_m()),
    }
}

/// Four rooms of 4 m × 4 m at 5 cm (walls 0.1 m), each wall between two rooms holding a doorway `door_m`
/// wide at its middle.
fn four_rooms(door_m: f64) -> OccupancyGrid {
    use shift_planner::map::{CellState, GridGeometry};
    let g = GridGeometry::new(164, 164, 0.05, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    let (lo, hi, mid) = (0.1, 8.1, 4.1);
    grid.fill_rect(0.0, 0.0, 8.2, lo, CellState::Occupied);
    grid.fill_rect(0.0, hi, 8.2, 8.2, CellState::Occupied);
    grid.fill_rect(0.0, 0.0, lo, 8.2, CellState::Occupied);
    grid.fill_rect(hi, 0.0, 8.2, 8.2, CellState::Occupied);
    grid.fill_rect(mid - 0.05, 0.0, mid + 0.05, 8.2, CellState::Occupied);
    grid.fill_rect(0.0, mid - 0.05, 8.2, mid + 0.05, CellState::Occupied);
    for c in [2.1, 6.1] {
        let (a, b) = (c - door_m / 2.0, c + door_m / 2.0);
        grid.fill_rect(mid - 0.06, a, mid + 0.06, b, CellState::Free);
        grid.fill_rect(a, mid - 0.06, b, mid + 0.06, CellState::Free);
    }
    grid
}

/// The site (walls grey, covered green, missed coverable red) and the path (blue), 4 pixels a cell.
fn dump_png(space: &CoverageSpace, path: &[Point2], file: &str) {
    let g = *space.geometry();
    let mut raster = CoverageRaster::new(g, space.robot.tool_width_m / 2.0);
    raster.stamp_polyline(path);
    let mut img = image::RgbImage::new(g.width as u32, g.height as u32);
    for i in 0..g.len() {
        let c = g.cell(i);
        let px = match (space.grid.is_free(i), raster.is_covered(i), space.coverable[i]) {
            (false, ..) => [60, 60, 60],
            (true, true, _) => [150, 220, 150],
            (true, false, true) => [230, 0, 0],
            (true, false, false) => [255, 255, 255],
        };
        img.put_pixel(c.x as u32, (g.height - 1 - c.y) as u32, image::Rgb(px));
    }
    for w in path.windows(2) {
        let n = ((w[1] - w[0]).norm() / (g.resolution * 0.5)).ceil().max(1.0) as usize;
        for k in 0..=n {
            if let Some(c) = g.locate(w[0] + (w[1] - w[0]) * (k as f64 / n as f64)) {
                img.put_pixel(c.x as u32, (g.height - 1 - c.y) as u32, image::Rgb([0, 0, 200]));
            }
        }
    }
    let big = image::imageops::resize(
        &img,
        img.width() * 4,
        img.height() * 4,
        image::imageops::FilterType::Nearest,
    );
    let _ = big.save(file);
}

fn main() {
    let dirs: Vec<String> = std::env::args().skip(1).collect();
    if dirs.is_empty() {
        let fp = Footprint::rectangle(1.2, 0.8).expect("valid");
        for deg in [0.0_f64, 17.0, 33.0, 45.0, 71.0] {
            let rooms = two_rooms((4.0, 4.0), 0.2, 1.0, deg.to_radians(), 0.05).expect("scene");
            let near = |p: Point2| rooms.in_near_room(p);
            let far = |p: Point2| rooms.in_far_room(p);
            let parts: [(&str, &dyn Fn(Point2) -> bool); 2] = [("near", &near), ("far", &far)];
            compare(&format!("doorway {deg}°"), &rooms.grid, rooms.start, &fp, 0.8, &parts);
        }
        return;
    }
    let (l, w) = std::env::var("FP")
        .ok()
        .and_then(|s| {
            let (a, b) = s.split_once(',')?;
            Some((a.parse().ok()?, b.parse().ok()?))
        })
        .unwrap_or((0.6, 0.4));
    let tool = std::env::var("TOOL").ok().and_then(|t| t.parse().ok()).unwrap_or(w);
    let fp = Footprint::rectangle(l, w).expect("valid footprint");
    for dir in dirs {
        if let Some(door) = dir.strip_prefix("rooms:").and_then(|d| d.parse::<f64>().ok()) {
            let grid = four_rooms(door);
            compare(&dir, &grid, Point2::new(1.0, 1.0), &fp, tool, &[]);
            continue;
        }
        match load(Path::new(&dir)) {
            Ok((grid, start)) => compare(&dir, &grid, start, &fp, tool, &[]),
            Err(e) => println!("{dir}: {e}"),
        }
    }
}
