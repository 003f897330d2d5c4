//! The smoothed elevation map (seed 000 §IV.A.5): a complete height field and the continuous surface through it.
//!
//! [`TerrainSurface::extract`] runs the §IV.A pipeline on a gridded cloud: provisional gap filling (so that
//! curvature is defined next to gaps), protrusion removal on the measured cells ([`super::smooth`]), then the
//! gaps are filled again from the cleaned data ([`super::fill`]). Between cell centres the surface is piecewise
//! linear on two triangles per square of centres, split along the (i, j)–(i+1, j+1) diagonal — the very
//! triangles of [`super::mesh::TerrainMesh`], so a height read here and a ray cast on the mesh agree. The
//! surface's domain is the rectangle spanned by the cell centres.

use super::curvature::{self, check_grid};
use super::fill::fill_gaps;
use super::grid::ElevationGrid;
use super::smooth::{SmoothParams, SmoothReport, smooth_outliers};
use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use crate::map::{Cell, GridGeometry};

/// A complete height field over a grid (no gaps), with where each height came from.
#[derive(Debug, Clone, PartialEq)]
pub struct TerrainSurface {
    /// Raster geometry; heights sit at cell centres.
    pub geometry: GridGeometry,
    /// Row-major heights, metres, all finite.
    pub heights: Vec<f64>,
    /// Per cell: 0 where the cell held data, k where it was filled k cells away from data.
    pub fill_ring: Vec<u32>,
}

/// What [`TerrainSurface::extract`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceReport {
    /// The protrusion removal.
    pub smooth: SmoothReport,
    /// Cells filled by interpolation.
    pub filled_cells: usize,
    /// Largest fill ring (distance to data, in cells).
    pub max_fill_ring: u32,
    /// The fill ring the cloud's own sampling gaps reach inside its data ([`super::fill::interior_fill_rings`]).
    pub interior_fill_rings: u32,
}

impl TerrainSurface {
    /// Runs §IV.A on a gridded cloud. Refuses a grid under 3 × 3 cells.
    pub fn extract(grid: &ElevationGrid, params: &SmoothParams) -> Result<(Self, SurfaceReport)> {
        let geometry = grid.geometry;
        check_grid("elevation grid", &grid.heights, &geometry)?;
        params.validate()?;
        let measured: Vec<bool> = grid.heights.iter().map(|h| h.is_finite()).collect();
        let interior_fill_rings = super::fill::interior_fill_rings(&grid.counts, &grid.heights);
        let mut heights = grid.heights.clone();
        fill_gaps(&mut heights, &geometry);
        let smooth = smooth_outliers(&mut heights, &measured, &geometry, params)?;
        for (h, &m) in heights.iter_mut().zip(&measured) {
            if !m {
                *h = f64::NAN;
            }
        }
        let fill_ring = fill_gaps(&mut heights, &geometry);
        let report = SurfaceReport {
            smooth,
            filled_cells: measured.iter().filter(|&&m| !m).count(),
            max_fill_ring: fill_ring.iter().copied().max().unwrap_or(0),
            interior_fill_rings,
        };
        Ok((
            Self {
                geometry,
                heights,
                fill_ring,
            },
            report,
        ))
    }

    /// A surface from complete heights (all finite, at least 3 × 3 cells), every cell counted as data.
    pub fn from_heights(geometry: GridGeometry, heights: Vec<f64>) -> Result<Self> {
        check_grid("elevation grid", &heights, &geometry)?;
        if let Some(&value) = heights.iter().find(|h| !h.is_finite()) {
            return Err(PlannerError::NonFinite {
                field: "heights",
                value,
            });
        }
        Ok(Self {
            fill_ring: vec![0; heights.len()],
            geometry,
            heights,
        })
    }

    /// A surface sampled from `z(x, y)` at the cell centres (tests and synthetic terrain).
    pub fn from_fn(geometry: GridGeometry, z: impl Fn(f64, f64) -> f64) -> Result<Self> {
        Self::from_heights(geometry, ElevationGrid::from_fn(geometry, z).heights)
    }

    /// Smallest and largest (x, y) of the domain (the outermost cell centres), metres.
    pub fn domain(&self) -> ([f64; 2], [f64; 2]) {
        let g = &self.geometry;
        let lo = g.center(Cell::new(0, 0));
        let hi = g.center(Cell::new(g.width - 1, g.height - 1));
        ([lo.x, lo.y], [hi.x, hi.y])
    }

    /// Height of the surface at map-frame (x, y), metres, or `None` outside the domain (beyond 1e-9 cells).
    pub fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        let g = &self.geometry;
        let fx = (x - g.origin.x) / g.resolution - 0.5;
        let fy = (y - g.origin.y) / g.resolution - 0.5;
        let (wmax, hmax) = ((g.width - 1) as f64, (g.height - 1) as f64);
        const EPS: f64 = 1e-9;
        if !(fx >= -EPS && fy >= -EPS && fx <= wmax + EPS && fy <= hmax + EPS) {
            return None;
        }
        let (fx, fy) = (fx.clamp(0.0, wmax), fy.clamp(0.0, hmax));
        let i = (fx as usize).min(g.width - 2);
        let j = (fy as usize).min(g.height - 2);
        let (u, v) = (fx - i as f64, fy - j as f64);
        let z = |a: usize, b: usize| self.heights[(j + b) * g.width + i + a];
        Some(if u >= v {
            z(0, 0) + u * (z(1, 0) - z(0, 0)) + v * (z(1, 1) - z(1, 0))
        } else {
            z(0, 0) + v * (z(0, 1) - z(0, 0)) + u * (z(1, 1) - z(0, 1))
        })
    }

    /// Height of the surface at map-frame (x, y), metres, taking a point beyond the domain to its nearest edge;
    /// `None` only for a non-finite point.
    pub fn height_clamped(&self, x: f64, y: f64) -> Option<f64> {
        let (lo, hi) = self.domain();
        self.height_at(x.clamp(lo[0], hi[0]), y.clamp(lo[1], hi[1]))
    }

    /// Surface area of cell `i`'s share of the surface, m²: the dual cell around its centre (halved on the
    /// border of the domain, quartered at its corners) times √(1 + z_u² + z_v²).
    pub fn cell_area(&self, i: usize) -> f64 {
        let g = &self.geometry;
        let c = g.cell(i);
        let edge = |k: usize, n: usize| if k == 0 || k + 1 == n { 0.5 } else { 1.0 };
        let plan = g.resolution * g.resolution * edge(c.x, g.width) * edge(c.y, g.height);
        let stretch =
            curvature::derivatives(&self.heights, g, c).map_or(1.0, |d| (1.0 + d.zu * d.zu + d.zv * d.zv).sqrt());
        plan * stretch
    }

    /// Map-frame centre of cell `i` with its height: a landmark point of §IV.B (eq. 13), metres.
    pub fn landmark(&self, i: usize) -> [f64; 3] {
        let p: Point2 = self.geometry.center_of(i);
        [p.x, p.y, self.heights[i]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_between_centres_are_linear_on_the_mesh_triangles() {
        let geometry = GridGeometry::new(3, 3, 1.0, Point2::origin()).expect("geometry");
        let s =
            TerrainSurface::from_heights(geometry, vec![0.0, 1.0, 2.0, 0.0, 1.0, 2.0, 4.0, 5.0, 6.0]).expect("surface");
        assert_eq!(s.domain(), ([0.5, 0.5], [2.5, 2.5]));
        assert_eq!(s.height_at(0.5, 0.5), Some(0.0));
        assert_eq!(s.height_at(2.5, 2.5), Some(6.0));
        // Lower triangle of the first square (u ≥ v): a plane through (0,0)=0, (1,0)=1, (1,1)=1.
        assert!((s.height_at(1.25, 0.75).unwrap_or(f64::NAN) - 0.75).abs() < 1e-12);
        // Upper triangle of the top-left square (u < v): through (0,1)=0, (0,2)=4, (1,2)=5.
        assert!((s.height_at(0.75, 2.25).unwrap_or(f64::NAN) - (0.0 + 0.75 * 4.0 + 0.25 * 1.0)).abs() < 1e-12);
        assert_eq!(s.height_at(0.4, 1.0), None);
        assert_eq!(s.height_at(f64::NAN, 1.0), None);
    }

    #[test]
    fn extract_fills_gaps_and_removes_a_spike() {
        let geometry = GridGeometry::new(30, 30, 0.5, Point2::origin()).expect("geometry");
        let plane = |x: f64, y: f64| 1.0 + 0.1 * x + 0.05 * y;
        let mut grid = ElevationGrid::from_fn(geometry, plane);
        grid.heights[5 * 30 + 5] = f64::NAN;
        grid.heights[20 * 30 + 12] += 2.0;
        let (s, report) = TerrainSurface::extract(&grid, &SmoothParams::default()).expect("surface");
        assert_eq!(report.filled_cells, 1);
        assert_eq!(s.fill_ring[5 * 30 + 5], 1);
        let worst = (0..geometry.len())
            .map(|i| {
                let c = geometry.center_of(i);
                (s.heights[i] - plane(c.x, c.y)).abs()
            })
            .fold(0.0, f64::max);
        // The 2 m spike is brought down until ρ < release: under release · min_spike_cells · g = 1.25 cm.
        assert!(worst < 0.0125, "worst {worst}");
        let area: f64 = (0..geometry.len()).map(|i| s.cell_area(i)).sum();
        let want = 14.5 * 14.5 * (1.0f64 + 0.01 + 0.0025).sqrt();
        assert!((area / want - 1.0).abs() < 1e-6, "area {area} vs {want}");
    }

    #[test]
    fn bad_heights_are_refused() {
        let geometry = GridGeometry::new(3, 3, 1.0, Point2::origin()).expect("geometry");
        assert!(matches!(
            TerrainSurface::from_heights(geometry, vec![f64::NAN; 9]),
            Err(PlannerError::NonFinite { field: "heights", .. })
        ));
        let thin = GridGeometry::new(2, 9, 1.0, Point2::origin()).expect("geometry");
        assert!(matches!(
            TerrainSurface::from_heights(thin, vec![0.0; 18]),
            Err(PlannerError::TerrainTooSmall { .. })
        ));
    }
}
