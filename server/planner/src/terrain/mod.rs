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
pub mod fill;
pub mod grid;
pub mod plane;
pub mod smooth;
pub mod surface;

pub use curvature::{CurvatureMap, Derivatives, FundamentalForms};
pub use grid::{ElevationGrid, GridParams};
pub use smooth::{CurvatureThresholds, SmoothParams, SmoothReport};
pub use surface::{SurfaceReport, TerrainSurface};
