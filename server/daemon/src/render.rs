//! PNG rendering of a plan: the map, regions in colours, the path (cover dark, transit red), the dock.

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use shift_planner::map::CellState;
use shift_planner::pipeline::{PlanOutput, WaypointKind};
use shift_planner::space::CoverageSpace;

const PALETTE: [(u8, u8, u8); 10] = [
    (166, 206, 227),
    (178, 223, 138),
    (251, 154, 153),
    (253, 191, 111),
    (202, 178, 214),
    (255, 255, 153),
    (141, 211, 199),
    (190, 186, 218),
    (252, 205, 229),
    (204, 235, 197),
];

/// Writes `path` (PNG) showing `plan` on `space`, at most `max_px` pixels on the long side.
pub fn render_png(space: &CoverageSpace, plan: &PlanOutput, path: &Path, max_px: u32) -> Result<()> {
    let g = space.geometry();
    let scale = (f64::from(max_px) / g.width.max(g.height) as f64).clamp(0.25, 8.0);
    let (w, h) = (
        ((g.width as f64) * scale).ceil() as u32,
        ((g.height as f64) * scale).ceil() as u32,
    );
    let mut buf = vec![255u8; (w * h * 3) as usize];
    // Background straight into the buffer: one colour per cell.
    for py in 0..h {
        for px in 0..w {
            let cx = ((f64::from(px) + 0.5) / scale) as usize;
            let cy = ((f64::from(h - 1 - py) + 0.5) / scale) as usize;
            if cx >= g.width || cy >= g.height {
                continue;
            }
            let i = cy * g.width + cx;
            let (r, gg, b) = match space.grid.cells[i] {
                CellState::Occupied => (30, 30, 30),
                CellState::Unknown => (150, 150, 150),
                CellState::Free => match plan.labels.get(i) {
                    Some(&l) if l != u32::MAX => PALETTE[l as usize % PALETTE.len()],
                    _ => (255, 255, 255),
                },
            };
            let o = ((py * w + px) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&[r, gg, b]);
        }
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let to_px = |x: f64, y: f64| -> (i32, i32) {
            let cx = (x - g.origin.x) / g.resolution * scale;
            let cy = (y - g.origin.y) / g.resolution * scale;
            (cx.round() as i32, (f64::from(h) - cy).round() as i32)
        };
        for pair in plan.waypoints.windows(2) {
            let colour = if pair[1].kind == WaypointKind::Transit {
                RGBColor(220, 20, 20)
            } else {
                RGBColor(20, 40, 120)
            };
            let a = to_px(pair[0].position.x, pair[0].position.y);
            let b = to_px(pair[1].position.x, pair[1].position.y);
            root.draw(&PathElement::new(vec![a, b], colour.stroke_width(1)))
                .map_err(|e| anyhow!("drawing: {e}"))?;
        }
        let dock = to_px(space.start.x, space.start.y);
        root.draw(&Circle::new(dock, 4, RGBColor(0, 160, 0).filled()))
            .map_err(|e| anyhow!("drawing: {e}"))?;
        root.present().map_err(|e| anyhow!("drawing: {e}"))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| anyhow!("image buffer size"))?;
    img.save(path).map_err(|e| anyhow!("writing {}: {e}", path.display()))?;
    Ok(())
}
