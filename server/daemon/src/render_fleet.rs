//! PNG rendering of a fleet's plans: each robot's part in a pale colour (a cell in the seam shows its
//! owner's), each robot's path in a darker shade of the same colour, docks as green discs.

use std::path::Path;

use crate::err;
use crate::error::Result;
use crate::render::{PALETTE, pale};
use plotters::prelude::*;
use shift_planner::divide::NO_OWNER;
use shift_planner::map::{CellState, OccupancyGrid};
use shift_planner::pipeline::fleet::FleetPlan;

/// Writes `path` (PNG) showing `fleet` on `grid`, at most `max_px` pixels on the long side.
pub fn render_fleet_png(grid: &OccupancyGrid, fleet: &FleetPlan, path: &Path, max_px: u32) -> Result<()> {
    let g = grid.geometry;
    let scale = (f64::from(max_px) / g.width.max(g.height) as f64).clamp(0.25, 8.0);
    let (w, h) = (
        ((g.width as f64) * scale).ceil() as u32,
        ((g.height as f64) * scale).ceil() as u32,
    );
    let mut buf = vec![255u8; (w * h * 3) as usize];
    for py in 0..h {
        for px in 0..w {
            let cx = ((f64::from(px) + 0.5) / scale) as usize;
            let cy = ((f64::from(h - 1 - py) + 0.5) / scale) as usize;
            if cx >= g.width || cy >= g.height {
                continue;
            }
            let i = cy * g.width + cx;
            let (r, gg, b) = match grid.cells[i] {
                CellState::Occupied => (30, 30, 30),
                CellState::Unknown => (150, 150, 150),
                CellState::Free => match fleet.division.owner[i] {
                    NO_OWNER => (255, 255, 255),
                    o => pale(PALETTE[o as usize % PALETTE.len()]),
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
        for (k, (_, profile)) in fleet.plans.iter().enumerate() {
            let (r, gg, b) = PALETTE[k % PALETTE.len()];
            // The part's colour at half brightness: strong enough over its pale fill.
            let colour = RGBColor(r / 2, gg / 2, b / 2);
            let pts: Vec<(i32, i32)> = profile
                .waypoints
                .iter()
                .map(|w| to_px(w.waypoint.position.x, w.waypoint.position.y))
                .collect();
            root.draw(&PathElement::new(pts, colour.stroke_width(1)))
                .map_err(|e| err!("drawing: {e}"))?;
        }
        for part in &fleet.division.parts {
            let dock = to_px(part.space.start.x, part.space.start.y);
            root.draw(&Circle::new(dock, 5, RGBColor(0, 160, 0).filled()))
                .map_err(|e| err!("drawing: {e}"))?;
        }
        root.present().map_err(|e| err!("drawing: {e}"))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| err!("image buffer size"))?;
    img.save(path).map_err(|e| err!("writing {}: {e}", path.display()))?;
    Ok(())
}
