//! Terrain surfaces from point clouds (issue 23; seed 000 §IV.A–B): pure, synchronous, deterministic.
//!
//! Pipeline, metres in the map frame throughout:
//!
//! 1. [`grid`] — the cloud `[[x, y, z]]` is gridded at `grid_m` into a height field: a robust height (a quantile
//!    of z) per cell, gaps where no point fell, non-finite points skipped and counted.
//! 2. [`curvature`] — §IV.A.1–3: the height field as the parametric surface **S**(u, v) = (u, v, z), its first
//!    (E, F, G) and second (L, M, N) fundamental forms by finite differences, Gaussian curvature K and mean
//!    curvature H.
//! 3. [`smooth`] — §IV.A.4: outliers where |K| > μ_K + α σ_K or |H| > μ_H + β σ_H, iterative curvature-adaptive
//!    Laplacian smoothing of the outliers only (spikes go, kerbs and ridges stay).
//! 4. [`fill`] — §IV.A.5: gaps filled by local plane fits, ring by ring from the data; [`surface`] holds the
//!    resulting elevation map and the continuous piecewise-linear surface through it.
//! 5. [`mesh`] — the surface as a `parry3d` triangle mesh: height under a point, altitude over the surface,
//!    distance to it, ray casts.
//! 6. Two uses:
//!    - ground robots — [`traverse`]: slope, step and roughness against [`GroundLimits`] → an
//!      [`OccupancyGrid`] the existing coverage pipeline plans on ([`ground_occupancy`]);
//!    - drones and sprayers — [`drone`], §IV.B: landmarks on the smoothed surface lifted by an elevation offset,
//!      boustrophedon lanes spaced by the tool width measured on the surface, 3-D waypoints
//!      ([`plan_drone`]), measured by [`drone_metrics`] (surface coverage, altitude error, path slope, lane
//!      spacing on the surface).
//!
//! Loading LAS/LAZ/PLY/PCD files (units, classification) belongs to the daemon; this module takes points.

pub mod curvature;
pub mod drone;
pub mod drone_metrics;
pub mod drone_speed;
pub mod fill;
pub mod grid;
pub mod mesh;
pub mod plane;
pub mod profile;
pub mod smooth;
pub mod surface;
pub mod traverse;

pub use curvature::{CurvatureMap, Derivatives, FundamentalForms};
pub use drone::{DroneParams, DronePlan, LaneChoice, plan_lanes};
pub use drone_metrics::{DroneMetrics, Quantiles, drone_metrics};
pub use drone_speed::{DroneProfile, VerticalLimits, profile_drone, vertical_speeds};
pub use fill::interior_fill_rings;
pub use grid::{ElevationGrid, GridParams};
pub use mesh::TerrainMesh;
pub use profile::LaneAxis;
pub use smooth::{CurvatureThresholds, SmoothParams, SmoothReport};
pub use surface::{SurfaceReport, TerrainSurface};
pub use traverse::{GroundLimits, Traversability};

use crate::error::Result;
use crate::map::OccupancyGrid;

/// How a cloud becomes a surface.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TerrainParams {
    /// Gridding.
    pub grid: GridParams,
    /// Protrusion removal.
    pub smooth: SmoothParams,
}

/// Grids a cloud and runs §IV.A on it: the smoothed, gap-free elevation map.
pub fn extract_surface(points: &[[f64; 3]], params: &TerrainParams) -> Result<(TerrainSurface, SurfaceReport)> {
    let grid = ElevationGrid::from_points(points, &params.grid)?;
    TerrainSurface::extract(&grid, &params.smooth)
}

/// A drone plan over a cloud and everything made on the way.
#[derive(Debug)]
pub struct DroneOutcome {
    /// The smoothed elevation map.
    pub surface: TerrainSurface,
    /// What smoothing and filling did.
    pub report: SurfaceReport,
    /// The plan: lanes and the 3-D path.
    pub plan: DronePlan,
    /// Its metrics.
    pub metrics: DroneMetrics,
}

/// §IV.A–B end to end: cloud → smoothed surface → drone lanes and 3-D waypoints → metrics.
pub fn plan_drone(points: &[[f64; 3]], terrain: &TerrainParams, drone: &DroneParams) -> Result<DroneOutcome> {
    drone.validate()?;
    let (surface, report) = extract_surface(points, terrain)?;
    let plan = plan_lanes(&surface, drone)?;
    let mesh = TerrainMesh::new(&surface)?;
    let metrics = drone_metrics(&surface, &mesh, &plan);
    Ok(DroneOutcome {
        surface,
        report,
        plan,
        metrics,
    })
}

/// What a ground robot may drive on, and everything made on the way.
#[derive(Debug)]
pub struct GroundOutcome {
    /// The smoothed elevation map.
    pub surface: TerrainSurface,
    /// What smoothing and filling did.
    pub report: SurfaceReport,
    /// Slope, step and roughness per cell.
    pub traversability: Traversability,
    /// Occupied over a limit, unknown where filled farther than `max_fill_m` from data, free elsewhere.
    pub occupancy: OccupancyGrid,
}

/// Cloud → smoothed surface → traversability → occupancy grid for the coverage pipeline. `max_fill_m`:
/// interpolated ground farther than this from any data is unknown; `None` takes the reach of the cloud's own
/// sampling gaps ([`SurfaceReport::interior_fill_rings`] cells).
pub fn ground_occupancy(
    points: &[[f64; 3]],
    terrain: &TerrainParams,
    limits: &GroundLimits,
    max_fill_m: Option<f64>,
) -> Result<GroundOutcome> {
    limits.validate()?;
    let (surface, report) = extract_surface(points, terrain)?;
    let traversability = Traversability::new(&surface, limits)?;
    let max_fill_m = max_fill_m.unwrap_or_else(|| f64::from(report.interior_fill_rings) * surface.geometry.resolution);
    let occupancy = traversability.occupancy(&surface, limits, max_fill_m)?;
    Ok(GroundOutcome {
        surface,
        report,
        traversability,
        occupancy,
    })
}

#[cfg(test)]
#[path = "tests.rs"]
mod tests;
