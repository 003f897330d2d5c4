//! The plan document (DESIGN §5.1): `shiftd plan` output, `GET /v1/plans/{id}/path`, Zenoh plan messages.

use serde::{Deserialize, Serialize};

/// A plan as it goes over the wire. Positions in metres in `frame`, speeds in m/s, times in seconds from the
/// plan's start.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct PlanDocument {
    /// Plan id (`p-…`).
    pub plan_id: String,
    /// Version, incremented by every correction.
    pub version: u64,
    /// Coordinate frame of every position (`map`).
    pub frame: String,
    /// The path; straight segments between consecutive waypoints are the path.
    pub waypoints: Vec<WaypointDoc>,
    /// Regions in visiting order.
    pub regions: Vec<RegionDoc>,
    /// Figures of merit (DESIGN §6).
    pub metrics: PlanMetricsDoc,
}

/// What a waypoint does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "lowercase")]
pub enum WaypointKindDoc {
    /// Sweeping.
    Cover,
    /// Moving between regions.
    Transit,
}

/// One waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct WaypointDoc {
    /// x, metres, map frame.
    pub x: f64,
    /// y, metres, map frame.
    pub y: f64,
    /// z, metres, map frame.
    pub z: f64,
    /// Speed at this waypoint, m/s.
    pub v: f64,
    /// Time from the plan's start, seconds.
    pub t: f64,
    /// Cover or transit.
    pub kind: WaypointKindDoc,
    /// Region being covered (cover waypoints).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub region: Option<u32>,
}

/// One region.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct RegionDoc {
    /// Region id.
    pub id: u32,
    /// Outer contour `[[x, y], …]`, metres, map frame.
    pub polygon: Vec<[f64; 2]>,
}

/// Plan metrics (DESIGN §6).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct PlanMetricsDoc {
    /// Covered share of coverable cells, percent.
    pub coverage_pct: f64,
    /// Overlap, percent of the covered area.
    pub overlap_pct: f64,
    /// Path length, metres.
    pub length_m: f64,
    /// Heading changes ≥ 30°.
    pub turns: u64,
    /// Path points closer than the robot radius to a non-free cell.
    pub collisions: u64,
    /// Time to drive the plan, seconds.
    pub duration_s: f64,
    /// Dwell uniformity (DESIGN §6): CV of deposit / attribute over coverable cells with the planned speeds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dwell_cv: Option<f64>,
    /// The same for constant speed over the same path and total time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dwell_cv_const_speed: Option<f64>,
    /// Time to compute the plan, milliseconds.
    pub compute_ms: f64,
    /// Where the robot's centre can go from the start (DESIGN §6 reachable), m².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reachable_area_m2: Option<f64>,
    /// What a complete plan covers from the start (DESIGN §6 coverable), m².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverable_area_m2: Option<f64>,
    /// Free cells of the whole map (within the request's region), m²: set against `coverable_area_m2`, how
    /// much of the site the start leads to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_area_m2: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn design_example_round_trips() {
        let text = r#"{
          "plan_id": "p-1", "version": 3, "frame": "map",
          "waypoints": [ {"x": 1.0, "y": 2.0, "z": 0.0, "v": 0.4, "t": 12.5, "kind": "cover", "region": 2} ],
          "regions": [ {"id": 2, "polygon": [[0,0],[3,0],[3,3],[0,3]]} ],
          "metrics": {"coverage_pct": 99.6, "overlap_pct": 3.1, "length_m": 201.0, "turns": 80,
                      "collisions": 0, "duration_s": 640.0, "compute_ms": 42.0}
        }"#;
        let doc: PlanDocument = serde_json::from_str(text).expect("parses");
        assert_eq!(doc.waypoints[0].kind, WaypointKindDoc::Cover);
        assert_eq!(doc.regions[0].polygon[2], [3.0, 3.0]);
        let back: PlanDocument = serde_json::from_str(&serde_json::to_string(&doc).expect("ser")).expect("de");
        assert_eq!(back, doc);
    }
}
