//! Differential geometry of the gridded surface (seed 000 §IV.A.1–3).
//!
//! The height field is the parametric surface **S**(u, v) = (u, v, z(u, v)) with u, v the map-frame x, y in
//! metres (eq. 1). Its partial derivatives come from finite differences on the grid: central differences
//! inside, second-order one-sided ones on the border (both exact for quadratics), and the mixed derivative as
//! the product of the two first-derivative stencils. From them, literally as in the paper:
//! **S**_u = (1, 0, z_u), **S**_v = (0, 1, z_v), **n** = **S**_u × **S**_v / ‖·‖ (eq. 6),
//! E, F, G = **S**_u·**S**_u, **S**_u·**S**_v, **S**_v·**S**_v (eq. 3),
//! L, M, N = **S**_uu·**n**, **S**_uv·**n**, **S**_vv·**n** (eq. 5),
//! K = (LN − M²) / (EG − F²) (eq. 7, 1/m²) and H = (EN + GL − 2FM) / (2(EG − F²)) (eq. 8, 1/m).
//! With the normal pointing up (+z), a dome has H < 0 and a bowl H > 0.

use nalgebra::Vector3;

use crate::error::{PlannerError, Result};
use crate::map::{Cell, GridGeometry};

/// Partial derivatives of z at a cell centre: z_u, z_v (dimensionless) and z_uu, z_uv, z_vv (1/m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Derivatives {
    /// ∂z/∂x.
    pub zu: f64,
    /// ∂z/∂y.
    pub zv: f64,
    /// ∂²z/∂x², 1/m.
    pub zuu: f64,
    /// ∂²z/∂x∂y, 1/m.
    pub zuv: f64,
    /// ∂²z/∂y², 1/m.
    pub zvv: f64,
}

/// How the stencils treat the border of the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Border {
    /// Second-order one-sided differences: exact for quadratics, for measuring the surface.
    OneSided,
    /// The grid mirrored at its border (z₋₁ = z₁): a spike on the border shows the curvature it would inside
    /// (its one-sided gradient would otherwise tilt it away), for finding outliers.
    Mirror,
}

/// Three grid indices along one axis and the first- and second-derivative weights on them (before division by
/// the cell size): central inside; on the border one-sided or mirrored. Needs `n ≥ 3`.
fn stencil(i: usize, n: usize, border: Border) -> ([usize; 3], [f64; 3], [f64; 3]) {
    const D1: [f64; 3] = [-0.5, 0.0, 0.5];
    const D2: [f64; 3] = [1.0, -2.0, 1.0];
    match (border, i == 0, i + 1 == n) {
        (Border::OneSided, true, _) => ([0, 1, 2], [-1.5, 2.0, -0.5], D2),
        (Border::OneSided, _, true) => ([n - 3, n - 2, n - 1], [0.5, -2.0, 1.5], D2),
        (Border::Mirror, true, _) => ([1, 0, 1], D1, D2),
        (Border::Mirror, _, true) => ([n - 2, n - 1, n - 2], D1, D2),
        _ => ([i - 1, i, i + 1], D1, D2),
    }
}

/// Derivatives of the height field at cell `c` with one-sided border stencils, or `None` when the grid is under
/// 3 × 3 or the stencil touches a gap (NaN height).
pub fn derivatives(heights: &[f64], geometry: &GridGeometry, c: Cell) -> Option<Derivatives> {
    derivatives_with(heights, geometry, c, Border::OneSided)
}

/// [`derivatives`] with the border treated as `border` says.
pub fn derivatives_with(heights: &[f64], geometry: &GridGeometry, c: Cell, border: Border) -> Option<Derivatives> {
    let (w, h) = (geometry.width, geometry.height);
    if w < 3 || h < 3 {
        return None;
    }
    let (xs, dx1, dx2) = stencil(c.x, w, border);
    let (ys, dy1, dy2) = stencil(c.y, h, border);
    let z = |x: usize, y: usize| heights[y * w + x];
    let g = geometry.resolution;
    let (mut zu, mut zv, mut zuu, mut zvv, mut zuv) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for a in 0..3 {
        let row = z(xs[a], c.y);
        zu += dx1[a] * row;
        zuu += dx2[a] * row;
        let col = z(c.x, ys[a]);
        zv += dy1[a] * col;
        zvv += dy2[a] * col;
        for b in 0..3 {
            zuv += dx1[a] * dy1[b] * z(xs[a], ys[b]);
        }
    }
    let d = Derivatives {
        zu: zu / g,
        zv: zv / g,
        zuu: zuu / (g * g),
        zuv: zuv / (g * g),
        zvv: zvv / (g * g),
    };
    [d.zu, d.zv, d.zuu, d.zuv, d.zvv]
        .iter()
        .all(|v| v.is_finite())
        .then_some(d)
}

/// First (E, F, G) and second (L, M, N) fundamental forms at a point of the surface (eq. 2–6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FundamentalForms {
    /// E = **S**_u · **S**_u.
    pub e: f64,
    /// F = **S**_u · **S**_v.
    pub f: f64,
    /// G = **S**_v · **S**_v.
    pub g: f64,
    /// L = **S**_uu · **n**, 1/m.
    pub l: f64,
    /// M = **S**_uv · **n**, 1/m.
    pub m: f64,
    /// N = **S**_vv · **n**, 1/m.
    pub n: f64,
}

impl FundamentalForms {
    /// The forms of **S**(u, v) = (u, v, z(u, v)) from z's derivatives.
    pub fn new(d: &Derivatives) -> Self {
        let su = Vector3::new(1.0, 0.0, d.zu);
        let sv = Vector3::new(0.0, 1.0, d.zv);
        let cross = su.cross(&sv);
        let normal = cross / cross.norm();
        let (suu, suv, svv) = (
            Vector3::new(0.0, 0.0, d.zuu),
            Vector3::new(0.0, 0.0, d.zuv),
            Vector3::new(0.0, 0.0, d.zvv),
        );
        Self {
            e: su.dot(&su),
            f: su.dot(&sv),
            g: sv.dot(&sv),
            l: suu.dot(&normal),
            m: suv.dot(&normal),
            n: svv.dot(&normal),
        }
    }

    /// Gaussian curvature K = (LN − M²) / (EG − F²), 1/m² (eq. 7).
    pub fn gaussian(&self) -> f64 {
        (self.l * self.n - self.m * self.m) / (self.e * self.g - self.f * self.f)
    }

    /// Mean curvature H = (EN + GL − 2FM) / (2(EG − F²)), 1/m (eq. 8); negative on a dome.
    pub fn mean(&self) -> f64 {
        (self.e * self.n + self.g * self.l - 2.0 * self.f * self.m) / (2.0 * (self.e * self.g - self.f * self.f))
    }
}

/// Gaussian and mean curvature of every cell; NaN where the stencil touches a gap.
#[derive(Debug, Clone, PartialEq)]
pub struct CurvatureMap {
    /// Raster geometry (that of the height field).
    pub geometry: GridGeometry,
    /// Gaussian curvature K per cell, 1/m².
    pub gaussian: Vec<f64>,
    /// Mean curvature H per cell, 1/m.
    pub mean: Vec<f64>,
}

impl CurvatureMap {
    /// Curvature of a height field (row-major, NaN = gap). Refuses a grid under 3 × 3 and a length that does
    /// not match the geometry.
    pub fn new(heights: &[f64], geometry: &GridGeometry) -> Result<Self> {
        Self::with_border(heights, geometry, Border::OneSided)
    }

    /// [`Self::new`] with the border treated as `border` says.
    pub fn with_border(heights: &[f64], geometry: &GridGeometry, border: Border) -> Result<Self> {
        check_grid("elevation grid", heights, geometry)?;
        let (mut gaussian, mut mean) = (vec![f64::NAN; geometry.len()], vec![f64::NAN; geometry.len()]);
        for i in 0..geometry.len() {
            if let Some(d) = derivatives_with(heights, geometry, geometry.cell(i), border) {
                let forms = FundamentalForms::new(&d);
                gaussian[i] = forms.gaussian();
                mean[i] = forms.mean();
            }
        }
        Ok(Self {
            geometry: *geometry,
            gaussian,
            mean,
        })
    }
}

/// Checks a height field against its geometry: the length matches and both sides hold at least 3 cells.
pub(crate) fn check_grid(field: &'static str, heights: &[f64], geometry: &GridGeometry) -> Result<()> {
    if heights.len() != geometry.len() {
        return Err(PlannerError::SizeMismatch {
            width: geometry.width,
            height: geometry.height,
            expected: geometry.len(),
            got: heights.len(),
        });
    }
    if geometry.width < 3 || geometry.height < 3 {
        return Err(PlannerError::TerrainTooSmall {
            field,
            width: geometry.width,
            height: geometry.height,
            min: 3,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;
    use crate::terrain::ElevationGrid;

    /// A square grid of `n × n` cells of `g` metres centred on the origin.
    fn square(n: usize, g: f64) -> GridGeometry {
        let half = n as f64 * g / 2.0;
        GridGeometry::new(n, n, g, Point2::new(-half, -half)).expect("geometry")
    }

    fn interior(geometry: &GridGeometry, i: usize) -> bool {
        let c = geometry.cell(i);
        c.x > 0 && c.y > 0 && c.x + 1 < geometry.width && c.y + 1 < geometry.height
    }

    #[test]
    fn a_tilted_plane_has_no_curvature() {
        let geometry = square(21, 0.5);
        let grid = ElevationGrid::from_fn(geometry, |x, y| 1.0 + 0.3 * x - 0.7 * y);
        let k = CurvatureMap::new(&grid.heights, &geometry).expect("curvature");
        let worst = k.gaussian.iter().chain(&k.mean).fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(worst < 1e-12, "plane curvature {worst}");
    }

    /// Saddle z = (x² − y²)/(2a): K = −1/(a² w⁴) and H = (q² − p²)/(2a w³) with p = x/a, q = −y/a and
    /// w² = 1 + p² + q²; at the origin K = −1/a², H = 0. The stencils are exact for quadratics, border
    /// included, so only rounding is left.
    #[test]
    fn a_saddle_matches_its_analytic_curvature_everywhere() {
        let (a, geometry) = (5.0, square(41, 0.25));
        let grid = ElevationGrid::from_fn(geometry, |x, y| (x * x - y * y) / (2.0 * a));
        let k = CurvatureMap::new(&grid.heights, &geometry).expect("curvature");
        let (mut err_k, mut err_h) = (0.0f64, 0.0f64);
        for i in 0..geometry.len() {
            let c = geometry.center_of(i);
            let (p, q) = (c.x / a, -c.y / a);
            let w2 = 1.0 + p * p + q * q;
            err_k = err_k.max((k.gaussian[i] + 1.0 / (a * a * w2 * w2)).abs());
            err_h = err_h.max((k.mean[i] - (q * q - p * p) / (2.0 * a * w2.powf(1.5))).abs());
        }
        assert!(err_k < 1e-12 && err_h < 1e-12, "saddle errors K {err_k:e} H {err_h:e}");
        let centre = geometry.index(Cell::new(20, 20));
        assert!((k.gaussian[centre] + 1.0 / 25.0).abs() < 1e-12);
        assert!(k.mean[centre].abs() < 1e-12);
    }

    /// Sphere cap of radius R (a dome): K = 1/R², H = −1/R. Central differences are second order, so the
    /// interior error shrinks with g²: at R = 10 m over ±4 m, measured 2.0e-6 1/m² (K) and 1.0e-5 1/m (H) at
    /// g = 0.2 m, 5.0e-7 and 2.5e-6 at g = 0.1 m: halving g divides it by 4.
    #[test]
    fn a_sphere_cap_converges_to_one_over_r() {
        let r = 10.0;
        let errors = |g: f64| {
            let geometry = square((8.0 / g).round() as usize, g);
            let grid = ElevationGrid::from_fn(geometry, |x, y| (r * r - x * x - y * y).sqrt());
            let k = CurvatureMap::new(&grid.heights, &geometry).expect("curvature");
            let (mut ek, mut eh) = (0.0f64, 0.0f64);
            for i in (0..geometry.len()).filter(|&i| interior(&geometry, i)) {
                ek = ek.max((k.gaussian[i] - 1.0 / (r * r)).abs());
                eh = eh.max((k.mean[i] + 1.0 / r).abs());
            }
            (ek, eh)
        };
        let (ek1, eh1) = errors(0.2);
        let (ek2, eh2) = errors(0.1);
        eprintln!("sphere cap R=10: g=0.2 K err {ek1:.3e} H err {eh1:.3e}; g=0.1 K err {ek2:.3e} H err {eh2:.3e}");
        assert!(ek1 < 3e-6 && eh1 < 1.5e-5, "g = 0.2: K {ek1:e}, H {eh1:e}");
        assert!(ek2 < 3e-6 / 4.0 && eh2 < 1.5e-5 / 4.0, "g = 0.1: K {ek2:e}, H {eh2:e}");
        assert!(
            ek1 / ek2 > 3.5 && eh1 / eh2 > 3.5,
            "second order: {} {}",
            ek1 / ek2,
            eh1 / eh2
        );
    }

    #[test]
    fn a_mirrored_border_shows_a_border_spike_as_inside() {
        let geometry = square(9, 0.5);
        let mut heights = vec![0.0; 81];
        heights[4] = 1.0; // (4, 0): on the bottom border
        heights[4 * 9 + 4] = 1.0; // (4, 4): inside
        let one_sided = CurvatureMap::new(&heights, &geometry).expect("curvature");
        let mirror = CurvatureMap::with_border(&heights, &geometry, Border::Mirror).expect("curvature");
        let inside = mirror.mean[40];
        assert!(
            (inside + 8.0).abs() < 1e-12,
            "H of a 1 m spike on 0.5 m cells: −2h/g² = −8, got {inside}"
        );
        assert_eq!(one_sided.mean[40], inside);
        assert_eq!(mirror.mean[4], inside);
        assert!(
            one_sided.mean[4].abs() < 0.5 * inside.abs(),
            "one-sided: {}",
            one_sided.mean[4]
        );
    }

    #[test]
    fn gaps_leave_curvature_undefined_and_small_grids_are_refused() {
        let geometry = square(7, 1.0);
        let mut heights = vec![0.0; 49];
        heights[24] = f64::NAN;
        let k = CurvatureMap::new(&heights, &geometry).expect("curvature");
        assert!(k.mean[24].is_nan() && k.mean[23].is_nan() && k.gaussian[16].is_nan());
        assert_eq!(k.mean[0], 0.0);
        let tiny = GridGeometry::new(2, 5, 1.0, Point2::origin()).expect("geometry");
        assert!(matches!(
            CurvatureMap::new(&[0.0; 10], &tiny),
            Err(PlannerError::TerrainTooSmall { width: 2, .. })
        ));
    }
}
