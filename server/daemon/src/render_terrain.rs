//! Terrain renderings (issue 23): the elevation map hill-shaded with the plan on it coloured by speed, and the
//! Gaussian and mean curvature maps of seed 000 §IV.A. North (+y) is up; one pixel per cell, scaled up for
//! small grids.

use std::path::Path;

use plotters::prelude::*;
use shift_planner::map::GridGeometry;
use shift_planner::terrain::{CurvatureMap, TerrainSurface};
use shift_proto::WaypointDoc;

use crate::err;
use crate::error::Result;
use crate::render::{colour_bar, speed_colour};
use shift_planner::speed::SpeedLimits;

/// Width of the colour-bar strip on the right of the plan rendering, pixels.
const BAR_STRIP_PX: u32 = 70;

/// Pixels per cell so the long side is about `max_px` (at least one pixel per cell, at most 8).
fn scale_for(g: &GridGeometry, max_px: u32) -> u32 {
    ((f64::from(max_px) / g.width.max(g.height) as f64).round() as u32).clamp(1, 8)
}

/// A raster of one RGB colour per cell, `scale` pixels per cell, `extra_w` blank pixels on the right.
fn raster(g: &GridGeometry, scale: u32, extra_w: u32, colour: impl Fn(usize) -> [u8; 3]) -> (u32, u32, Vec<u8>) {
    let (map_w, h) = (g.width as u32 * scale, g.height as u32 * scale);
    let w = map_w + extra_w;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    for py in 0..h {
        let cy = (h - 1 - py) / scale;
        for px in 0..map_w {
            let i = cy as usize * g.width + (px / scale) as usize;
            let o = ((py * w + px) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&colour(i));
        }
    }
    (w, h, buf)
}

/// Hypsometric tint (green low, brown, white high) with a hill shade from the north-west.
fn elevation_colours(s: &TerrainSurface) -> Vec<[u8; 3]> {
    let g = &s.geometry;
    let z = &s.heights;
    let (lo, hi) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let span = (hi - lo).max(1e-9);
    let stops = [
        (60.0, 120.0, 60.0),
        (170.0, 160.0, 90.0),
        (140.0, 100.0, 60.0),
        (245.0, 245.0, 245.0),
    ];
    (0..g.len())
        .map(|i| {
            let c = g.cell(i);
            let at = |dx: isize, dy: isize| g.offset(c, dx, dy).map_or(z[i], |n| z[g.index(n)]);
            let dzdx = (at(1, 0) - at(-1, 0)) / (2.0 * g.resolution);
            let dzdy = (at(0, 1) - at(0, -1)) / (2.0 * g.resolution);
            // Lambert shading against a light from the north-west, 45° up.
            let n = [-dzdx, -dzdy, 1.0];
            let l = [-0.5, 0.5, std::f64::consts::FRAC_1_SQRT_2];
            let shade =
                ((n[0] * l[0] + n[1] * l[1] + n[2] * l[2]) / (n[0] * n[0] + n[1] * n[1] + 1.0).sqrt()).clamp(0.0, 1.0);
            let f = ((z[i] - lo) / span).clamp(0.0, 1.0) * (stops.len() - 1) as f64;
            let k = (f.floor() as usize).min(stops.len() - 2);
            let t = f - k as f64;
            let (a, b) = (stops[k], stops[k + 1]);
            let lit = 0.45 + 0.55 * shade;
            let mix = |p: f64, q: f64| ((p + (q - p) * t) * lit).round().clamp(0.0, 255.0) as u8;
            [mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2)]
        })
        .collect()
}

/// Writes the elevation map with `path` on it coloured by speed within `limits` (and `blocked` cells of a
/// ground robot in dark grey) to `out`.
pub fn render_terrain_plan(
    s: &TerrainSurface,
    blocked: Option<&[bool]>,
    path: &[WaypointDoc],
    limits: &SpeedLimits,
    out: &Path,
    max_px: u32,
) -> Result<()> {
    let g = s.geometry;
    let scale = scale_for(&g, max_px);
    let colours = elevation_colours(s);
    let (w, h, mut buf) = raster(&g, scale, BAR_STRIP_PX, |i| match blocked {
        // Obstacles to a ground robot: the relief kept, darkened to grey (red means slow on the path).
        Some(b) if b[i] => {
            let [r, gg, bb] = colours[i];
            let grey = ((u16::from(r) + u16::from(gg) + u16::from(bb)) / 3) as u8;
            [grey / 3 + 20, grey / 3 + 20, grey / 3 + 20]
        }
        _ => colours[i],
    });
    let map_w = w - BAR_STRIP_PX;
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let k = f64::from(scale) / g.resolution;
        let to_px = |x: f64, y: f64| -> (i32, i32) {
            let cx = (x - g.origin.x) * k;
            let cy = (y - g.origin.y) * k;
            (cx.round() as i32, (f64::from(h) - cy).round() as i32)
        };
        let span = (limits.v_max_mps - limits.v_min_mps).max(1e-9);
        for pair in path.windows(2) {
            let v = 0.5 * (pair[0].v + pair[1].v);
            let stroke = if pair[1].kind == shift_proto::WaypointKindDoc::Transit {
                1
            } else {
                2
            };
            root.draw(&PathElement::new(
                vec![to_px(pair[0].x, pair[0].y), to_px(pair[1].x, pair[1].y)],
                speed_colour((v - limits.v_min_mps) / span).stroke_width(stroke),
            ))
            .map_err(|e| err!("drawing: {e}"))?;
        }
        if let Some(first) = path.first() {
            root.draw(&Circle::new(to_px(first.x, first.y), 5, RGBColor(0, 160, 0).filled()))
                .map_err(|e| err!("drawing: {e}"))?;
        }
        colour_bar(&root, map_w, h, limits)?;
        root.present().map_err(|e| err!("drawing: {e}"))?;
    }
    save(w, h, buf, out)
}

/// Writes the elevation map alone (hill-shaded) to `out`.
pub fn render_elevation(s: &TerrainSurface, out: &Path, max_px: u32) -> Result<()> {
    let g = s.geometry;
    let colours = elevation_colours(s);
    let (w, h, buf) = raster(&g, scale_for(&g, max_px), 0, |i| colours[i]);
    save(w, h, buf, out)
}

/// Writes a curvature map (`values` per cell: K in 1/m² or H in 1/m) to `out`: blue negative, white zero, red
/// positive, saturated at the 98th percentile of |value| so that a few spikes do not wash out the rest.
pub fn render_curvature(c: &CurvatureMap, values: &[f64], out: &Path, max_px: u32) -> Result<()> {
    let g = c.geometry;
    let mut mags: Vec<f64> = values.iter().filter(|v| v.is_finite()).map(|v| v.abs()).collect();
    mags.sort_by(f64::total_cmp);
    let sat = mags
        .get((mags.len().saturating_sub(1)) * 98 / 100)
        .copied()
        .unwrap_or(1.0)
        .max(1e-12);
    let (w, h, buf) = raster(&g, scale_for(&g, max_px), 0, |i| {
        let v = values[i];
        if !v.is_finite() {
            return [128, 128, 128];
        }
        let f = (v / sat).clamp(-1.0, 1.0);
        let fade = |x: f64| (255.0 * (1.0 - x.abs())).round() as u8;
        if f >= 0.0 {
            [255, fade(f), fade(f)]
        } else {
            [fade(f), fade(f), 255]
        }
    });
    save(w, h, buf, out)
}

fn save(w: u32, h: u32, buf: Vec<u8>, out: &Path) -> Result<()> {
    let img = image::RgbImage::from_raw(w, h, buf).ok_or_else(|| err!("image buffer size"))?;
    img.save(out).map_err(|e| err!("writing {}: {e}", out.display()))
}
