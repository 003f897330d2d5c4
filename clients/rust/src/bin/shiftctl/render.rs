//! `render PLAN out.png`: the plan on its site's map. The map (free white, occupied black, unknown grey)
//! underneath, each region outlined in its own colour, the path coloured by speed (red slow → blue fast) with a
//! colour bar labelled in m/s, a scale bar in metres, the start (green disc) and the dock the tour returns to
//! (black ring). The bitmap backend has no fonts: labels are drawn with a small stroke font.

use plotters::prelude::*;
use shift_client::Client;
use shift_client::proto::{OccupancyGridDoc, PlanDocument};

use crate::cli::RenderArgs;
use crate::input::bad;
use crate::show;

/// Width of the colour-bar strip right of the map, pixels.
const BAR_STRIP_PX: u32 = 90;

const REGION_COLOURS: [(u8, u8, u8); 8] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
];

/// Runs the command.
pub async fn run(client: &Client, args: RenderArgs, json: bool) -> anyhow::Result<()> {
    let status = client.plan(&args.plan).await?;
    let doc = client.path(&args.plan).await?;
    let grid = client.site_map(&status.site).await?;
    let png = draw(&grid, &doc, args.size)?;
    png.save_with_format(&args.out, image::ImageFormat::Png)
        .map_err(|e| bad(format!("{}: {e}", args.out.display())))?;
    let (w, h) = png.dimensions();
    if json {
        show::json(
            &serde_json::json!({"file": args.out, "width": w, "height": h, "plan_id": doc.plan_id,
            "version": doc.version}),
        )
    } else {
        println!(
            "wrote {} ({w} × {h} px, plan {} v{})",
            args.out.display(),
            doc.plan_id,
            doc.version
        );
        Ok(())
    }
}

/// Map-frame metres → pixels.
#[derive(Debug, Clone, Copy)]
struct View {
    origin: [f64; 2],
    /// Pixels per metre.
    ppm: f64,
    /// Height of the map part, pixels.
    h: u32,
}

impl View {
    fn px(&self, x: f64, y: f64) -> (i32, i32) {
        let cx = (x - self.origin[0]) * self.ppm;
        let cy = (y - self.origin[1]) * self.ppm;
        (cx.round() as i32, (f64::from(self.h) - cy).round() as i32)
    }
}

/// Draws the picture; `size` is the long side of the map part, pixels.
pub fn draw(grid: &OccupancyGridDoc, doc: &PlanDocument, size: u32) -> anyhow::Result<image::RgbImage> {
    let (gw, gh) = (grid.width, grid.height);
    let cells_ok = gw.checked_mul(gh).is_some_and(|n| n == grid.cells.len() as u64);
    if gw == 0 || gh == 0 || !cells_ok || !grid.resolution.is_finite() || grid.resolution <= 0.0 {
        anyhow::bail!("the site's map is malformed ({gw} × {gh}, {} cells)", grid.cells.len());
    }
    let scale = (f64::from(size) / gw.max(gh) as f64).min(16.0);
    let map_w = ((gw as f64) * scale).ceil().max(1.0) as u32;
    let h = ((gh as f64) * scale).ceil().max(1.0) as u32;
    let w = map_w + BAR_STRIP_PX;
    let h_total = h.max(160);
    let mut buf = vec![255u8; (w as usize) * (h_total as usize) * 3];
    for py in 0..h {
        for px in 0..map_w {
            let cx = ((f64::from(px) + 0.5) / scale) as u64;
            let cy = ((f64::from(h - 1 - py) + 0.5) / scale) as u64;
            let shade = match grid.cell(cx, cy) {
                Some(0) | None => 255,
                Some(-1) => 170,
                Some(v) if v >= 50 => 35,
                Some(_) => 215,
            };
            let o = ((py * w + px) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&[shade; 3]);
        }
    }
    let view = View {
        origin: grid.origin,
        ppm: scale / grid.resolution,
        h,
    };
    let (v_lo, v_hi) = speed_range(doc);
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h_total)).into_drawing_area();
        let e = |err: DrawingAreaErrorKind<_>| anyhow::anyhow!("drawing: {err}");
        for (i, region) in doc.regions.iter().enumerate() {
            let (r, g, b) = REGION_COLOURS[i % REGION_COLOURS.len()];
            let mut ring: Vec<(i32, i32)> = region.polygon.iter().map(|p| view.px(p[0], p[1])).collect();
            if let Some(&first) = ring.first() {
                ring.push(first);
            }
            root.draw(&PathElement::new(ring, RGBColor(r, g, b).stroke_width(2)))
                .map_err(e)?;
        }
        let stroke = if view.ppm >= 40.0 { 3 } else { 2 };
        for pair in doc.waypoints.windows(2) {
            let v = 0.5 * (pair[0].v + pair[1].v);
            let f = if v_hi > v_lo { (v - v_lo) / (v_hi - v_lo) } else { 1.0 };
            root.draw(&PathElement::new(
                vec![view.px(pair[0].x, pair[0].y), view.px(pair[1].x, pair[1].y)],
                speed_colour(f).stroke_width(stroke),
            ))
            .map_err(e)?;
        }
        if let (Some(first), Some(last)) = (doc.waypoints.first(), doc.waypoints.last()) {
            let dock = view.px(last.x, last.y);
            root.draw(&Circle::new(dock, 8, BLACK.stroke_width(2))).map_err(e)?;
            root.draw(&Circle::new(view.px(first.x, first.y), 5, RGBColor(0, 170, 0).filled()))
                .map_err(e)?;
        }
        scale_bar(&root, &view, map_w)?;
        colour_bar(&root, map_w, h_total, v_lo, v_hi)?;
        root.present().map_err(e)?;
    }
    image::RgbImage::from_raw(w, h_total, buf).ok_or_else(|| anyhow::anyhow!("image buffer size"))
}

/// Slowest and fastest waypoint speeds, m/s.
fn speed_range(doc: &PlanDocument) -> (f64, f64) {
    let vs = doc.waypoints.iter().map(|w| w.v).filter(|v| v.is_finite());
    let lo = vs.clone().fold(f64::INFINITY, f64::min);
    let hi = vs.fold(f64::NEG_INFINITY, f64::max);
    if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) }
}

/// Red (slow, f = 0) through yellow and cyan to blue (fast, f = 1).
fn speed_colour(f: f64) -> RGBColor {
    let f = if f.is_finite() { f.clamp(0.0, 1.0) } else { 0.0 };
    let stops = [
        (210.0, 20.0, 20.0),
        (240.0, 200.0, 0.0),
        (0.0, 190.0, 200.0),
        (20.0, 40.0, 210.0),
    ];
    let x = f * (stops.len() - 1) as f64;
    let k = (x.floor() as usize).min(stops.len() - 2);
    let t = x - k as f64;
    let (a, b) = (stops[k], stops[k + 1]);
    let lerp = |p: f64, q: f64| (p + (q - p) * t).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// A scale bar of a round length (1, 2 or 5 × 10^k m, about a fifth of the map's width) at the bottom left,
/// on a white box, labelled in metres.
fn scale_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    view: &View,
    map_w: u32,
) -> anyhow::Result<()> {
    let e = |err: DrawingAreaErrorKind<_>| anyhow::anyhow!("drawing: {err}");
    let target_m = f64::from(map_w) / 5.0 / view.ppm;
    let exp = 10f64.powf(target_m.log10().floor());
    let metres = [5.0, 2.0, 1.0]
        .into_iter()
        .map(|k| k * exp)
        .find(|&m| m <= target_m)
        .unwrap_or(exp);
    let len = (metres * view.ppm).round().max(1.0) as i32;
    let label = format_metres(metres);
    let k = 5;
    let label_w = text_width(&label, k);
    let (x0, y0) = (10, view.h as i32 - 12);
    root.draw(&Rectangle::new(
        [(x0 - 6, y0 - 2 * k - 14), (x0 + len.max(label_w) + 6, y0 + 6)],
        WHITE.mix(0.85).filled(),
    ))
    .map_err(e)?;
    root.draw(&PathElement::new(vec![(x0, y0), (x0 + len, y0)], BLACK.stroke_width(3)))
        .map_err(e)?;
    for x in [x0, x0 + len] {
        root.draw(&PathElement::new(vec![(x, y0 - 5), (x, y0 + 3)], BLACK.stroke_width(2)))
            .map_err(e)?;
    }
    draw_text(root, &label, x0, y0 - 2 * k - 8, k)
}

fn format_metres(m: f64) -> String {
    let text = if m >= 1.0 { format!("{m:.0}") } else { format!("{m}") };
    format!("{text}m")
}

/// The colour bar right of the map: slowest at the bottom, fastest at the top, labelled in m/s.
fn colour_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    x0: u32,
    h: u32,
    v_lo: f64,
    v_hi: f64,
) -> anyhow::Result<()> {
    let e = |err: DrawingAreaErrorKind<_>| anyhow::anyhow!("drawing: {err}");
    let k = 4;
    let (top, bottom) = ((h / 10) as i32 + 2 * k + 6, (h - h / 10) as i32 - 2 * k - 6);
    let left = x0 as i32 + 12;
    let n = (bottom - top).max(1);
    for y in top..=bottom {
        let f = f64::from(bottom - y) / f64::from(n);
        root.draw(&PathElement::new(
            vec![(left, y), (left + 18, y)],
            speed_colour(f).stroke_width(1),
        ))
        .map_err(e)?;
    }
    draw_text(root, &format!("{v_hi:.2}"), left, top - 2 * k - 5, k)?;
    draw_text(root, &format!("{v_lo:.2}"), left, bottom + 5, k)?;
    draw_text(root, "m/s", left + 24, (top + bottom) / 2 - k, k)
}

/// Strokes of a glyph in a 1 × 2 box (units of k), y down.
fn glyph(ch: char) -> &'static [(f32, f32, f32, f32)] {
    const D: [&[(f32, f32, f32, f32)]; 10] = [
        &[(0., 0., 1., 0.), (1., 0., 1., 2.), (1., 2., 0., 2.), (0., 2., 0., 0.)],
        &[(1., 0., 1., 2.)],
        &[
            (0., 0., 1., 0.),
            (1., 0., 1., 1.),
            (1., 1., 0., 1.),
            (0., 1., 0., 2.),
            (0., 2., 1., 2.),
        ],
        &[(0., 0., 1., 0.), (1., 0., 1., 2.), (1., 2., 0., 2.), (0., 1., 1., 1.)],
        &[(0., 0., 0., 1.), (0., 1., 1., 1.), (1., 0., 1., 2.)],
        &[
            (1., 0., 0., 0.),
            (0., 0., 0., 1.),
            (0., 1., 1., 1.),
            (1., 1., 1., 2.),
            (1., 2., 0., 2.),
        ],
        &[
            (1., 0., 0., 0.),
            (0., 0., 0., 2.),
            (0., 2., 1., 2.),
            (1., 2., 1., 1.),
            (1., 1., 0., 1.),
        ],
        &[(0., 0., 1., 0.), (1., 0., 1., 2.)],
        &[
            (0., 0., 1., 0.),
            (1., 0., 1., 2.),
            (1., 2., 0., 2.),
            (0., 2., 0., 0.),
            (0., 1., 1., 1.),
        ],
        &[
            (1., 1., 0., 1.),
            (0., 1., 0., 0.),
            (0., 0., 1., 0.),
            (1., 0., 1., 2.),
            (1., 2., 0., 2.),
        ],
    ];
    match ch {
        '0'..='9' => D[ch as usize - '0' as usize],
        'm' => &[(0., 2., 0., 1.), (0., 1., 1., 1.), (1., 1., 1., 2.), (0.5, 1., 0.5, 2.)],
        's' => &[
            (1., 1., 0., 1.),
            (0., 1., 0., 1.5),
            (0., 1.5, 1., 1.5),
            (1., 1.5, 1., 2.),
            (1., 2., 0., 2.),
        ],
        '/' => &[(0., 2., 1., 0.)],
        '-' => &[(0., 1., 1., 1.)],
        _ => &[],
    }
}

fn text_width(text: &str, k: i32) -> i32 {
    text.chars().map(|c| if c == '.' { k / 2 + 3 } else { k + 3 }).sum()
}

/// Draws `text` (digits, '.', '-', 'm', 's', '/') with its top-left at (x, y), `k` pixels per half height.
fn draw_text<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    text: &str,
    x: i32,
    y: i32,
    k: i32,
) -> anyhow::Result<()> {
    let e = |err: DrawingAreaErrorKind<_>| anyhow::anyhow!("drawing: {err}");
    let at = |cx: i32, a: f32, b: f32| (cx + (a * k as f32).round() as i32, y + (b * k as f32).round() as i32);
    let mut cx = x;
    for ch in text.chars() {
        if ch == '.' {
            root.draw(&Circle::new((cx + 1, y + 2 * k), 1, BLACK.filled()))
                .map_err(e)?;
            cx += k / 2 + 3;
            continue;
        }
        for &(a, b, c, d) in glyph(ch) {
            root.draw(&PathElement::new(
                vec![at(cx, a, b), at(cx, c, d)],
                BLACK.stroke_width(1),
            ))
            .map_err(e)?;
        }
        cx += k + 3;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use shift_client::proto::{PlanMetricsDoc, RegionDoc, WaypointDoc, WaypointKindDoc};

    #[test]
    fn a_small_plan_renders_with_every_part() {
        let grid = OccupancyGridDoc {
            resolution: 0.1,
            origin: [0.0, 0.0],
            width: 40,
            height: 30,
            cells: (0..1200).map(|i| if i % 40 == 0 || i < 40 { 100 } else { 0 }).collect(),
            free_thresh: None,
            occupied_thresh: None,
        };
        let wp = |x: f64, y: f64, v: f64| WaypointDoc {
            x,
            y,
            z: 0.0,
            v,
            t: 0.0,
            kind: WaypointKindDoc::Cover,
            region: Some(0),
        };
        let doc = PlanDocument {
            plan_id: "p-1".into(),
            version: 1,
            frame: "map".into(),
            waypoints: vec![
                wp(0.5, 0.5, 0.1),
                wp(3.5, 0.5, 1.0),
                wp(3.5, 2.5, 0.5),
                wp(0.5, 2.5, 0.2),
            ],
            regions: vec![RegionDoc {
                id: 0,
                polygon: vec![[0.2, 0.2], [3.8, 0.2], [3.8, 2.8], [0.2, 2.8]],
            }],
            metrics: PlanMetricsDoc::default(),
        };
        let img = draw(&grid, &doc, 400).expect("draws");
        assert_eq!(img.dimensions(), (400 + BAR_STRIP_PX, 300));
        let colours: std::collections::HashSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
        assert!(colours.len() > 30, "{} colours", colours.len());
        assert_eq!(format_metres(0.5), "0.5m");
        assert_eq!(format_metres(2.0), "2m");
    }
}
