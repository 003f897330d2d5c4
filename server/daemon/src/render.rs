//! PNG rendering of a plan: the map, regions in colours, the path (cover dark, transit red), the dock. With a
//! speed profile, the regions turn pale and the path is coloured by speed (red slow, blue fast, like seed
//! 000 Fig. 12) with a colour bar labelled in m/s on the right.

use std::path::Path;

use crate::err;
use crate::error::Result;
use plotters::prelude::*;
use shift_planner::map::CellState;
use shift_planner::pipeline::{PlanOutput, WaypointKind};
use shift_planner::space::CoverageSpace;
use shift_planner::speed::{SpeedLimits, SpeedProfile};

/// Region (and fleet part) colours.
pub(crate) const PALETTE: [(u8, u8, u8); 10] = [
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

/// Width of the colour-bar strip on the right of speed renderings, pixels.
const BAR_STRIP_PX: u32 = 70;

/// Writes `path` (PNG) showing `plan` on `space`, at most `max_px` pixels on the long side; with `speed`, the
/// profiled path coloured by speed within the limits.
pub fn render_png(
    space: &CoverageSpace,
    plan: &PlanOutput,
    speed: Option<(&SpeedProfile, &SpeedLimits)>,
    path: &Path,
    max_px: u32,
) -> Result<()> {
    let g = space.geometry();
    let scale = (f64::from(max_px) / g.width.max(g.height) as f64).clamp(0.25, 8.0);
    let (map_w, h) = (
        ((g.width as f64) * scale).ceil() as u32,
        ((g.height as f64) * scale).ceil() as u32,
    );
    let w = map_w + if speed.is_some() { BAR_STRIP_PX } else { 0 };
    let mut buf = vec![255u8; (w * h * 3) as usize];
    // Background straight into the buffer: one colour per cell.
    for py in 0..h {
        for px in 0..map_w {
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
                    Some(&l) if l != u32::MAX => {
                        let (r, gg, b) = PALETTE[l as usize % PALETTE.len()];
                        if speed.is_some() { pale((r, gg, b)) } else { (r, gg, b) }
                    }
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
        match speed {
            None => {
                for pair in plan.waypoints.windows(2) {
                    let colour = if pair[1].kind == WaypointKind::Transit {
                        RGBColor(220, 20, 20)
                    } else {
                        RGBColor(20, 40, 120)
                    };
                    let a = to_px(pair[0].position.x, pair[0].position.y);
                    let b = to_px(pair[1].position.x, pair[1].position.y);
                    root.draw(&PathElement::new(vec![a, b], colour.stroke_width(1)))
                        .map_err(|e| err!("drawing: {e}"))?;
                }
            }
            Some((profile, limits)) => {
                let span = (limits.v_max_mps - limits.v_min_mps).max(1e-9);
                let width = if scale >= 3.0 { 2 } else { 1 };
                for pair in profile.waypoints.windows(2) {
                    let v = 0.5 * (pair[0].speed_mps + pair[1].speed_mps);
                    let colour = speed_colour((v - limits.v_min_mps) / span);
                    let (p, q) = (pair[0].waypoint.position, pair[1].waypoint.position);
                    let stroke = if pair[1].waypoint.kind == WaypointKind::Transit {
                        1
                    } else {
                        width
                    };
                    root.draw(&PathElement::new(
                        vec![to_px(p.x, p.y), to_px(q.x, q.y)],
                        colour.stroke_width(stroke),
                    ))
                    .map_err(|e| err!("drawing: {e}"))?;
                }
                colour_bar(&root, map_w, h, limits)?;
            }
        }
        let dock = to_px(space.start.x, space.start.y);
        root.draw(&Circle::new(dock, 4, RGBColor(0, 160, 0).filled()))
            .map_err(|e| err!("drawing: {e}"))?;
        root.present().map_err(|e| err!("drawing: {e}"))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| err!("image buffer size"))?;
    img.save(path).map_err(|e| err!("writing {}: {e}", path.display()))?;
    Ok(())
}

/// `colour` mixed three parts white to one.
pub(crate) fn pale((r, g, b): (u8, u8, u8)) -> (u8, u8, u8) {
    let mix = |c: u8| ((u16::from(c) + 3 * 255) / 4) as u8;
    (mix(r), mix(g), mix(b))
}

/// Red (slow, f = 0) through yellow and cyan to blue (fast, f = 1).
pub(crate) fn speed_colour(f: f64) -> RGBColor {
    let f = if f.is_finite() { f.clamp(0.0, 1.0) } else { 0.0 };
    let stops = [
        (200.0, 0.0, 0.0),
        (240.0, 200.0, 0.0),
        (0.0, 190.0, 200.0),
        (20.0, 40.0, 200.0),
    ];
    let x = f * (stops.len() - 1) as f64;
    let k = (x.floor() as usize).min(stops.len() - 2);
    let t = x - k as f64;
    let (a, b) = (stops[k], stops[k + 1]);
    let lerp = |p: f64, q: f64| (p + (q - p) * t).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// The colour bar right of the map: v_min at the bottom, v_max at the top, labelled in m/s.
pub(crate) fn colour_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    x0: u32,
    h: u32,
    limits: &SpeedLimits,
) -> Result<()> {
    let (top, bottom) = ((h / 10) as i32, (h - h / 10) as i32);
    let left = x0 as i32 + 8;
    let n = (bottom - top).max(1);
    for y in top..=bottom {
        let f = f64::from(bottom - y) / f64::from(n);
        root.draw(&PathElement::new(
            vec![(left, y), (left + 16, y)],
            speed_colour(f).stroke_width(1),
        ))
        .map_err(|e| err!("drawing: {e}"))?;
    }
    let k = (h / 120).clamp(2, 5) as i32;
    for (v, y) in [(limits.v_max_mps, top), (limits.v_min_mps, bottom - 2 * k)] {
        draw_number(root, &format!("{v:.2}"), left + 20, y, k)?;
    }
    Ok(())
}

/// Draws `text` (digits and '.') in seven-segment strokes `k` pixels per half digit height, top-left at
/// (x, y): the bitmap backend has no fonts.
fn draw_number<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    text: &str,
    x: i32,
    y: i32,
    k: i32,
) -> Result<()> {
    // Segments a..g as (x0, y0, x1, y1) in units of k, digit box 1 × 2.
    const SEG: [(i32, i32, i32, i32); 7] = [
        (0, 0, 1, 0),
        (1, 0, 1, 1),
        (1, 1, 1, 2),
        (0, 2, 1, 2),
        (0, 1, 0, 2),
        (0, 0, 0, 1),
        (0, 1, 1, 1),
    ];
    const DIGITS: [u8; 10] = [0x3f, 0x06, 0x5b, 0x4f, 0x66, 0x6d, 0x7d, 0x07, 0x7f, 0x6f];
    let mut cx = x;
    for ch in text.chars() {
        if ch == '.' {
            root.draw(&Circle::new((cx, y + 2 * k), 1, BLACK.filled()))
                .map_err(|e| err!("drawing: {e}"))?;
            cx += k / 2 + 2;
            continue;
        }
        let Some(d) = ch.to_digit(10) else { continue };
        for (bit, &(a, b, c, e)) in SEG.iter().enumerate() {
            if DIGITS[d as usize] & (1 << bit) != 0 {
                root.draw(&PathElement::new(
                    vec![(cx + a * k, y + b * k), (cx + c * k, y + e * k)],
                    BLACK.stroke_width(1),
                ))
                .map_err(|e| err!("drawing: {e}"))?;
            }
        }
        cx += k + 3;
    }
    Ok(())
}
