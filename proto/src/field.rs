//! `POST /v1/sites/{site}/field` (issue 23): a field drawn in GeoJSON, in `[lon, lat]` degrees (RFC 7946),
//! becomes a site whose map frame is a local metric projection centred on the field.

use serde::{Deserialize, Serialize};

/// The body of a field upload.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct FieldRequest {
    /// A GeoJSON Polygon, MultiPolygon, Feature or FeatureCollection: the field's parts; holes are obstacles.
    #[cfg_attr(feature = "openapi", schema(value_type = Object))]
    pub field: serde_json::Value,
    /// Areas not to enter (GeoJSON polygons, as `field`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    #[cfg_attr(feature = "openapi", schema(value_type = Vec<Object>))]
    pub no_go: Vec<serde_json::Value>,
    /// Metres per cell of the site's grid. Absent: a quarter of `tool_width` (5 cm to 1 m), or 0.25 m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution_m: Option<f64>,
    /// The tool width the site will mostly be planned with, metres (chooses the resolution).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_width: Option<f64>,
}

/// Where a geo-referenced site's map frame lies on the earth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct GeoReference {
    /// The map frame as a PROJ string: a transverse Mercator on WGS84 centred on `origin_wgs84`, metres.
    pub crs: String,
    /// The map frame's (0, 0), `[lon, lat]` degrees.
    pub origin_wgs84: [f64; 2],
}
