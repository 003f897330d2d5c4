//! Plans shared scenes with one decomposition and prints metrics and where the length goes:
//! `cargo run --release -p shift-planner --example scene_stats -- DIR [DIR ...]`.
//! Environment: `DECOMP` (auto, bcd, walls, …; default auto), `PATTERN` (lanes, spiral), `ORDER` (two-opt,
//! rrt, anneal), `PASSES=0` to skip targeted passes, `TARGET` / `MINY` (pass selection), `PLACE` (lattice,
//! fit, framed), `DUMP=DIR` to write a PNG per scene (`CROP=x0,y0,x1,y1` in metres, `REGION=id` to draw only
//! that region's route, red to blue in driving order), `LONG=1` for cover length per region and the long
//! steps.

use std::path::Path;
use std::time::Instant;

use shift_planner::geom::Point2;
use shift_planner::pipeline::{NoMonitor, PlanParams, plan};
use shift_planner::space::CoverageSpace;

#[path = "common/scene.rs"]
mod common_scene;
use common_scene::scene as load;

fn main() {
    let mut params = PlanParams::default();
    if let Ok(d) = std::env::var("DECOMP") {
        params.decomposition = d.parse().unwrap_or(params.decomposition);
    }
    if let Ok(p) = std::env::var("PATTERN") {
        params.pattern = p.parse().unwrap_or(params.pattern);
    }
    if let Some(o) = std::env::var("ORDER").ok().and_then(|o| o.parse().ok()) {
        params.order = o;
    }
    if std::env::var("PASSES").is_ok_and(|v| v == "0") {
        params.targeted_passes = false;
    }
    if let Some(t) = std::env::var("TARGET").ok().and_then(|v| v.parse().ok()) {
        params.passes.coverage_target_pct = t;
    }
    if let Some(t) = std::env::var("MINY").ok().and_then(|v| v.parse().ok()) {
        params.passes.min_yield = t;
    }
    if let Ok(p) = std::env::var("PLACE") {
        use shift_planner::pattern::lanes::Placement;
        params.lanes.placement = match p.as_str() {
            "lattice" => Some(Placement::Lattice),
            "fit" => Some(Placement::Fit),
            "framed" => Some(Placement::Framed),
            _ => None,
        };
    }
    for dir in std::env::args().skip(1) {
        let space = match load(Path::new(&dir)) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{dir}: {e}");
                continue;
            }
        };
        let t = Instant::now();
        let out = match plan(&space, &params, &mut NoMonitor) {
            Ok(o) => o,
            Err(e) => {
                eprintln!("{dir}: {e}");
                continue;
            }
        };
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if let Ok(dump) = std::env::var("DUMP") {
            dump_png(
                &space,
                &out.points(),
                &out.waypoints.iter().map(|w| w.region).collect::<Vec<_>>(),
                &out.labels,
                &format!(
                    "{dump}/{}.png",
                    Path::new(&dir)
                        .file_name()
                        .map_or("x".into(), |n| n.to_string_lossy().into_owned())
                ),
            );
        }
        if std::env::var("LONG").is_ok() {
            let w = &out.waypoints;
            let mut hist = [0.0f64; 6];
            for s in w.windows(2) {
                if s[1].kind != shift_planner::pipeline::WaypointKind::Cover {
                    continue;
                }
                let d = s[1].position - s[0].position;
                let len = d.norm();
                let horiz = d.y.abs() < 1e-6 * len.max(1e-9) || d.x.abs() < 1e-6 * len.max(1e-9);
                if horiz {
                    continue;
                }
                let b = if len < 0.2 {
                    0
                } else if len < 0.4 {
                    1
                } else if len < 0.8 {
                    2
                } else if len < 1.6 {
                    3
                } else if len < 3.2 {
                    4
                } else {
                    5
                };
                hist[b] += len;
                if len > 1.6 {
                    println!(
                        "  long {:.2} m {:?} -> {:?} r{:?}",
                        len, s[0].position, s[1].position, s[1].region
                    );
                }
            }
            let mut per: std::collections::BTreeMap<u32, (f64, f64, usize)> = Default::default();
            for s in w.windows(2) {
                if s[1].kind != shift_planner::pipeline::WaypointKind::Cover {
                    continue;
                }
                let Some(r) = s[1].region else { continue };
                let ang = out.regions.iter().find(|x| x.id == r).map_or(0.0, |x| x.angle_rad);
                let d = s[1].position - s[0].position;
                let len = d.norm();
                let along = (d.x * ang.cos() + d.y * ang.sin()).abs();
                let e = per.entry(r).or_default();
                e.0 += len;
                if along > 0.999 * len && len > 0.7 {
                    e.1 += len;
                    e.2 += 1;
                }
            }
            for (r, (c, l, n)) in &per {
                let area = out.regions.iter().find(|x| x.id == *r).map_or(0.0, |x| x.area_m2);
                println!(
                    "  region {r:3} area {area:6.1} cover {c:7.1} lanes {l:7.1} ({n:3}) other {:6.1}",
                    c - l
                );
            }
            println!(
                "  non-axis cover segments by length <0.2 <0.4 <0.8 <1.6 <3.2 >3.2: {:?}",
                hist.map(|h| (h * 10.0).round() / 10.0)
            );
        }
        let m = out.metrics;
        let s = out.stats;
        let name = Path::new(&dir)
            .file_name()
            .map_or(dir.clone(), |n| n.to_string_lossy().into_owned());
        println!(
            "{name:22} {:>6}/{:<7} cov {:6.2} ovl {:6.2} len {:7.1} turns {:5} coll {} regions {:3} ms {:7.0} | pattern {:6.1} passes {:6.1} steps {:6.1} transit {:6.1}",
            out.decomposition.name(),
            out.pattern.name(),
            m.coverage_pct,
            m.overlap_pct,
            m.length_m,
            m.turns,
            m.collisions,
            out.regions.len(),
            ms,
            s.pattern_m,
            s.passes_m,
            s.steps_m,
            s.transit_m
        );
    }
}

/// Grey: not free; white: free; green tint: covered; red: coverable but uncovered; blue: path vertices.
fn dump_png(space: &CoverageSpace, path: &[Point2], regions: &[Option<u32>], labels: &[u32], file: &str) {
    let g = *space.geometry();
    let mut raster = shift_planner::metrics::CoverageRaster::new(g, space.robot.tool_width_m / 2.0);
    raster.stamp_polyline(path);
    let mut img = image::RgbImage::new(g.width as u32, g.height as u32);
    for (i, &l) in labels.iter().enumerate() {
        let c = g.cell(i);
        let px = if space.coverable[i] && !raster.is_covered(i) {
            [230, 0, 0]
        } else if raster.is_covered(i) {
            if l == u32::MAX {
                [150, 220, 150]
            } else {
                [
                    120 + (l * 53 % 120) as u8,
                    170 + (l * 31 % 80) as u8,
                    120 + (l * 97 % 120) as u8,
                ]
            }
        } else if space.grid.is_free(i) {
            [255, 255, 255]
        } else {
            [60, 60, 60]
        };
        img.put_pixel(c.x as u32, (g.height - 1 - c.y) as u32, image::Rgb(px));
    }
    let only: Option<u32> = std::env::var("REGION").ok().and_then(|r| r.parse().ok());
    let segs: Vec<usize> = (1..path.len())
        .filter(|&k| only.is_none() || regions.get(k).copied().flatten() == only)
        .collect();
    for (j, &k) in segs.iter().enumerate() {
        let w = [path[k - 1], path[k]];
        // With REGION, the colour runs from red (first) to blue (last) along the route.
        let t = j as f64 / segs.len().max(1) as f64;
        let colour = if only.is_some() {
            [(230.0 * (1.0 - t)) as u8, 0, (230.0 * t) as u8]
        } else {
            [0, 0, 200]
        };
        let n = ((w[1] - w[0]).norm() / (g.resolution * 0.5)).ceil().max(1.0) as usize;
        for k in 0..=n {
            let p = w[0] + (w[1] - w[0]) * (k as f64 / n as f64);
            if let Some(c) = g.locate(p) {
                img.put_pixel(c.x as u32, (g.height - 1 - c.y) as u32, image::Rgb(colour));
            }
        }
    }
    // Crop to the reachable cells' bounding box (plus a margin) and scale up so details show.
    let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
    for i in (0..g.len()).filter(|&i| space.reachable[i]) {
        let c = g.cell(i);
        let (x, y) = (c.x as u32, (g.height - 1 - c.y) as u32);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    if let Some(v) = std::env::var("CROP")
        .ok()
        .map(|c| c.split(',').filter_map(|x| x.parse::<f64>().ok()).collect::<Vec<f64>>())
        .filter(|v| v.len() == 4)
        && let (Some(a), Some(b)) = (g.locate(Point2::new(v[0], v[1])), g.locate(Point2::new(v[2], v[3])))
    {
        (x0, x1) = (a.x as u32, b.x as u32);
        (y0, y1) = ((g.height - 1 - b.y) as u32, (g.height - 1 - a.y) as u32);
    }
    let m = 10;
    let (x0, y0) = (x0.saturating_sub(m), y0.saturating_sub(m));
    let (x1, y1) = ((x1 + m).min(img.width() - 1), (y1 + m).min(img.height() - 1));
    let crop = image::imageops::crop_imm(&img, x0, y0, x1 - x0 + 1, y1 - y0 + 1).to_image();
    let scale = (1400 / crop.width().max(crop.height())).max(1);
    let big = image::imageops::resize(
        &crop,
        crop.width() * scale,
        crop.height() * scale,
        image::imageops::FilterType::Nearest,
    );
    let _ = big.save(file);
}
