//! Plans over point-cloud terrain (issue 23): the plan JSON of `shiftd plan --terrain` is a [`PlanDocument`]
//! (its fields at the top level, so every reader of plans reads it) plus a `terrain` object saying where the
//! metres came from and how the plan measures on the surface.

use serde::{Deserialize, Serialize};

use crate::PlanDocument;

/// A plan over terrain: the plan (waypoints with `z` filled, metres) and what it stands on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct TerrainPlanDocument {
    /// The plan, flattened: `plan_id`, `waypoints` (x, y, z in metres), `metrics`…
    #[serde(flatten)]
    pub plan: PlanDocument,
    /// Source, units, surface and metrics.
    pub terrain: TerrainDoc,
}

/// The robot a terrain plan is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "lowercase")]
pub enum RobotKindDoc {
    /// Flies over the surface at an offset: lanes spaced on the surface, 3-D waypoints.
    Drone,
    /// Drives on it: too steep, too high a step or too rough is an obstacle; z is the ground height.
    Ground,
}

/// Where a terrain plan's metres came from and how it measures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct TerrainDoc {
    /// Drone or ground.
    pub robot_kind: RobotKindDoc,
    /// The cloud that was read.
    pub source: CloudSourceDoc,
    /// Gridding cell size, metres.
    pub grid_m: f64,
    /// Height over the surface flown at (drones), metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub altitude_offset_m: Option<f64>,
    /// What the surface extraction did (seed 000 §IV.A).
    pub surface: SurfaceDoc,
    /// Drone plans: the surface metrics.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drone: Option<DroneMetricsDoc>,
    /// Ground plans: what the limits made of the surface.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<GroundDoc>,
}

/// The point cloud a plan was made from, and the conversion to metres that was applied.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CloudSourceDoc {
    /// File name (or "upload").
    pub name: String,
    /// `las`, `laz`, `ply` or `pcd`.
    pub format: String,
    /// The file's coordinate reference system when it names one (`EPSG:2992`, a WKT name), else absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crs: Option<String>,
    /// Horizontal unit of the file: `metre`, `foot`, `us-survey-foot`.
    pub horizontal_unit: String,
    /// Vertical unit of the file.
    pub vertical_unit: String,
    /// Where the units were read (header keys, WKT, assumed, an override).
    pub unit_source: String,
    /// The conversion applied, in words: x and y scaled by …, z by …, origin kept (no recentring).
    pub conversion: String,
    /// Points in the file.
    pub points_read: u64,
    /// Points used (after the ground filter and dropping non-finite ones).
    pub points_used: u64,
    /// The classification filter that was applied.
    pub ground_filter: String,
}

/// What the surface extraction did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SurfaceDoc {
    /// Grid columns.
    pub width: u64,
    /// Grid rows.
    pub height: u64,
    /// Lowest and highest smoothed height, metres.
    pub z_range_m: [f64; 2],
    /// Cells found outliers by curvature and smoothed.
    pub outlier_cells: u64,
    /// Cells without points, filled by interpolation.
    pub filled_cells: u64,
}

/// p5/p50/p95/max of a quantity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct QuantilesDoc {
    /// 5th percentile.
    pub p5: f64,
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

/// Drone plan metrics on the surface (DESIGN §6 extended; README "Terrain").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct DroneMetricsDoc {
    /// Covered surface area over the total surface area of the region, percent.
    pub surface_coverage_pct: f64,
    /// Surface area of the region, m².
    pub surface_area_m2: f64,
    /// |height over the surface − offset| along the path, metres.
    pub altitude_error_m: QuantilesDoc,
    /// Steepest path segment, degrees from the horizontal.
    pub max_path_slope_deg: f64,
    /// Arc length on the surface between neighbouring lanes, metres.
    pub lane_spacing_m: QuantilesDoc,
    /// Swath width on the surface, metres.
    pub tool_width_m: f64,
    /// Lanes flown.
    pub lanes: u64,
    /// Fastest climb along the timed path, m/s.
    #[serde(default)]
    pub max_climb_mps: f64,
    /// Fastest descent along the timed path, m/s (positive).
    #[serde(default)]
    pub max_descent_mps: f64,
}

/// What a ground robot's limits made of the surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct GroundDoc {
    /// Steepest slope allowed, degrees.
    pub max_slope_deg: f64,
    /// Highest step allowed, metres.
    pub max_step_m: f64,
    /// Roughest patch allowed (RMS over 3 × 3 cells), metres.
    pub max_roughness_m: f64,
    /// Share of the surface's cells that are obstacles under them, percent.
    pub blocked_pct: f64,
    /// Steepest slope under the planned path, degrees.
    pub max_path_slope_deg: f64,
}

/// Query of `POST /v1/sites/{site}/terrain` (the body is the cloud file itself).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::IntoParams))]
#[cfg_attr(feature = "openapi", into_params(parameter_in = Query))]
#[serde(deny_unknown_fields)]
pub struct TerrainUploadQuery {
    /// `las`, `laz`, `ply` or `pcd` (default: recognised from the bytes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<String>,
    /// The file's unit when its header is wrong or silent: `metre`, `foot`, `us-survey-foot` (PLY and PCD have
    /// none: metres are assumed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<String>,
    /// Elevation grid cell, metres (default 0.5, 0.05 to 10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid_m: Option<f64>,
    /// Use every point, not only the ground class (LAS class 2, used by default when the file has any).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub all_points: Option<bool>,
    /// Steepest slope a robot drives, degrees (default 15).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_slope_deg: Option<f64>,
    /// Highest step, metres (default 0.10).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_step_m: Option<f64>,
    /// Roughest patch (RMS over 3 × 3 cells), metres (default 0.05).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_roughness_m: Option<f64>,
}
