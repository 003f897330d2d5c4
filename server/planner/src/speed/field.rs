//! The Gaussian deposition field of seed 000 eq. 21 on the map grid: each segment's duration is laid along
//! it (bilinear splats every half cell), then blurred by a separable, normalised Gaussian. Values are
//! tool-seconds per m² (the kernel integrates to 1), map frame, row-major like the occupancy grid.

use crate::geom::Point2;
use crate::map::GridGeometry;

/// Kernels are cut at this many standard deviations (the tail beyond holds < 0.01 % of the mass).
const TRUNCATE_SIGMAS: f64 = 4.0;

/// Seconds per cell of `durations[k]` (segment `points[k]`–`points[k+1]`) laid along the path. Mass that
/// falls off the grid is dropped.
pub fn splat_durations(g: &GridGeometry, points: &[Point2], durations: &[f64]) -> Vec<f64> {
    let mut field = vec![0.0; g.len()];
    let step = g.resolution * 0.5;
    for (k, w) in points.windows(2).enumerate() {
        let Some(&dt) = durations.get(k) else { break };
        if !(dt.is_finite() && dt > 0.0) {
            continue;
        }
        let len = (w[1] - w[0]).norm();
        let n = (len / step).ceil().max(1.0) as usize;
        let share = dt / n as f64;
        for j in 0..n {
            let p = w[0] + (w[1] - w[0]) * ((j as f64 + 0.5) / n as f64);
            splat(g, &mut field, p, share);
        }
    }
    field
}

/// Adds `mass` at `p`, shared bilinearly among the four nearest cell centres.
fn splat(g: &GridGeometry, field: &mut [f64], p: Point2, mass: f64) {
    let (cx, cy) = g.to_cell_coords(p);
    let (fx, fy) = (cx - 0.5, cy - 0.5);
    if !(fx > -1.0 && fy > -1.0 && fx < g.width as f64 && fy < g.height as f64) {
        return;
    }
    let (x0, y0) = (fx.floor() as isize, fy.floor() as isize);
    let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
    for (dx, dy, wgt) in [
        (0, 0, (1.0 - tx) * (1.0 - ty)),
        (1, 0, tx * (1.0 - ty)),
        (0, 1, (1.0 - tx) * ty),
        (1, 1, tx * ty),
    ] {
        let (x, y) = (x0 + dx, y0 + dy);
        if x >= 0 && y >= 0 && (x as usize) < g.width && (y as usize) < g.height {
            field[y as usize * g.width + x as usize] += mass * wgt;
        }
    }
}

/// Separable Gaussian blur of a per-cell field with standard deviation `sigma_m` (metres); the kernel sums to
/// one, so mass is kept except what spills off the grid.
pub fn gaussian_blur(g: &GridGeometry, field: &[f64], sigma_m: f64) -> Vec<f64> {
    let sigma = sigma_m / g.resolution;
    if !(sigma > 1e-3 && sigma.is_finite()) {
        return field.to_vec();
    }
    let r = (TRUNCATE_SIGMAS * sigma).ceil() as usize;
    let mut kernel: Vec<f64> = (0..=2 * r)
        .map(|k| {
            let d = k as f64 - r as f64;
            (-d * d / (2.0 * sigma * sigma)).exp()
        })
        .collect();
    let sum: f64 = kernel.iter().sum();
    kernel.iter_mut().for_each(|k| *k /= sum);
    let (w, h) = (g.width, g.height);
    let mut tmp = vec![0.0; field.len()];
    // Rows: scatter each non-zero value (deposits are sparse away from the path).
    for y in 0..h {
        let row = &field[y * w..(y + 1) * w];
        let out = &mut tmp[y * w..(y + 1) * w];
        for (x, &v) in row.iter().enumerate() {
            if v == 0.0 {
                continue;
            }
            let lo = x.saturating_sub(r);
            let hi = (x + r).min(w - 1);
            for (xx, o) in out.iter_mut().enumerate().take(hi + 1).skip(lo) {
                *o += v * kernel[xx + r - x];
            }
        }
    }
    // Columns: gather row by row so memory is read in order.
    let mut out = vec![0.0; field.len()];
    for y in 0..h {
        let lo = y.saturating_sub(r);
        let hi = (y + r).min(h - 1);
        let dst = &mut out[y * w..(y + 1) * w];
        for yy in lo..=hi {
            let k = kernel[yy + r - y];
            let src = &tmp[yy * w..(yy + 1) * w];
            for (d, s) in dst.iter_mut().zip(src) {
                *d += k * s;
            }
        }
    }
    out
}

/// Value of a per-cell field at a map-frame point, bilinear between cell centres (clamped at the border).
pub fn sample_bilinear(g: &GridGeometry, field: &[f64], p: Point2) -> f64 {
    let (cx, cy) = g.to_cell_coords(p);
    if !(cx.is_finite() && cy.is_finite()) {
        return 0.0;
    }
    let fx = (cx - 0.5).clamp(0.0, (g.width - 1) as f64);
    let fy = (cy - 0.5).clamp(0.0, (g.height - 1) as f64);
    let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(g.width - 1), (y0 + 1).min(g.height - 1));
    let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
    let v = |x: usize, y: usize| field[y * g.width + x];
    (v(x0, y0) * (1.0 - tx) + v(x1, y0) * tx) * (1.0 - ty) + (v(x0, y1) * (1.0 - tx) + v(x1, y1) * tx) * ty
}

/// The deposit field (s/m²) of a path whose segment `k` takes `durations[k]` seconds: eq. 21 integrated over
/// the plan's time with σ = `sigma_m`.
pub fn deposit_field(g: &GridGeometry, points: &[Point2], durations: &[f64], sigma_m: f64) -> Vec<f64> {
    let mut d = gaussian_blur(g, &splat_durations(g, points, durations), sigma_m);
    let cell_area = g.resolution * g.resolution;
    d.iter_mut().for_each(|v| *v /= cell_area);
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blur_keeps_mass_and_spreads_like_a_gaussian() {
        let g = GridGeometry::new(41, 41, 0.1, Point2::origin()).expect("valid");
        let mut f = vec![0.0; g.len()];
        f[20 * 41 + 20] = 1.0;
        let b = gaussian_blur(&g, &f, 0.3);
        let total: f64 = b.iter().sum();
        assert!((total - 1.0).abs() < 1e-9);
        // Second moment along x ≈ σ² (in cells: 3² = 9).
        let m2: f64 = (0..g.len()).map(|i| b[i] * ((i % 41) as f64 - 20.0).powi(2)).sum();
        assert!((m2 - 9.0).abs() < 0.05, "{m2}");
    }

    #[test]
    fn lanes_at_tool_spacing_deposit_a_flat_field() {
        // Lanes 0.6 m apart at 0.5 m/s: deposit 1 / (v w) = 3.33 s/m² away from the ends.
        let g = GridGeometry::new(100, 100, 0.1, Point2::origin()).expect("valid");
        let mut pts = Vec::new();
        for k in 0..16 {
            let y = 0.3 + 0.6 * f64::from(k);
            let (a, b) = (Point2::new(0.0, y), Point2::new(10.0, y));
            if k % 2 == 0 {
                pts.extend([a, b]);
            } else {
                pts.extend([b, a]);
            }
        }
        let durations: Vec<f64> = pts.windows(2).map(|w| (w[1] - w[0]).norm() / 0.5).collect();
        // Only the lanes deposit (zero time on the connecting steps).
        let durations: Vec<f64> = durations
            .iter()
            .enumerate()
            .map(|(k, d)| if k % 2 == 0 { *d } else { 0.0 })
            .collect();
        let d = deposit_field(&g, &pts, &durations, 0.3);
        for y in 30..70 {
            for x in 30..70 {
                let v = d[y * 100 + x];
                assert!((v - 1.0 / (0.5 * 0.6)).abs() < 0.06, "({x}, {y}) {v}");
            }
        }
        assert!((sample_bilinear(&g, &d, Point2::new(5.0, 5.0)) - 3.333).abs() < 0.06);
    }
}
