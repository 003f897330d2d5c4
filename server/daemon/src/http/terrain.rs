//! `POST /v1/sites/{site}/terrain` (issue 23): a point cloud (LAS, LAZ, PLY, PCD) becomes a ground robot's
//! site. The body is the file itself, read under `[http] max_body_bytes` (a larger body is refused with 413
//! before it is all read); the cloud is decoded and its surface extracted off the async workers, and only a
//! site that parses replaces what was there: a bad file leaves the site as it was.

use axum::body::Bytes;
use axum::extract::{Path, RawQuery, State};
use axum::http::StatusCode;
use shift_engine::terrain_site::TerrainSite;
use shift_engine::{MapSource, SiteRecord};
use shift_planner::terrain::{GroundLimits, TerrainParams, extract_surface};
use shift_proto::{ErrorBody, SiteSummary, TerrainUploadQuery};

use super::AppState;
use super::error::{ApiError, ApiJson};
use super::listings::query_pairs;
use crate::cloud::source::source_doc;
use crate::cloud::{CloudFormat, CloudLimits, GroundFilter, LengthUnit, LoadOptions, load_cloud};

/// Grid cells the API accepts (a 2 km × 2 km tile at 0.5 m).
const MAX_CELLS: f64 = 16e6;

fn number(key: &str, value: &str, range: std::ops::RangeInclusive<f64>) -> Result<f64, ApiError> {
    let v: f64 = value
        .parse()
        .map_err(|_| ApiError::bad_request(format!("{key}: {value:?} is not a number")))?;
    if !v.is_finite() || !range.contains(&v) {
        return Err(ApiError::bad_request(format!(
            "{key}: {v} is outside {}..={}",
            range.start(),
            range.end()
        )));
    }
    Ok(v)
}

fn parse_query(raw: &str) -> Result<TerrainUploadQuery, ApiError> {
    let mut q = TerrainUploadQuery::default();
    for (key, value) in query_pairs(raw)? {
        match key.as_str() {
            "format" => q.format = Some(value),
            "units" => q.units = Some(value),
            "grid_m" => q.grid_m = Some(number("grid_m", &value, 0.05..=10.0)?),
            "all_points" => {
                q.all_points = Some(
                    value
                        .parse()
                        .map_err(|_| ApiError::bad_request(format!("all_points: {value:?} is not true or false")))?,
                )
            }
            "max_slope_deg" => q.max_slope_deg = Some(number("max_slope_deg", &value, 0.0..=89.0)?),
            "max_step_m" => q.max_step_m = Some(number("max_step_m", &value, 0.0..=10.0)?),
            "max_roughness_m" => q.max_roughness_m = Some(number("max_roughness_m", &value, 0.0..=10.0)?),
            other => {
                return Err(ApiError::bad_request(format!(
                    "{other}: unknown parameter (format, units, grid_m, all_points, max_slope_deg, max_step_m, \
                     max_roughness_m)"
                )));
            }
        }
    }
    Ok(q)
}

fn load_options(q: &TerrainUploadQuery, max_bytes: usize) -> Result<LoadOptions, ApiError> {
    let format = match q.format.as_deref() {
        None => None,
        Some("las") => Some(CloudFormat::Las),
        Some("laz") => Some(CloudFormat::Laz),
        Some("ply") => Some(CloudFormat::Ply),
        Some("pcd") => Some(CloudFormat::Pcd),
        Some(other) => {
            return Err(ApiError::bad_request(format!(
                "format: {other:?} is not las, laz, ply or pcd"
            )));
        }
    };
    let units = match q.units.as_deref() {
        None => None,
        Some("metre") => Some(LengthUnit::Metre),
        Some("foot") => Some(LengthUnit::Foot),
        Some("us-survey-foot") => Some(LengthUnit::UsSurveyFoot),
        Some(other) => {
            return Err(ApiError::bad_request(format!(
                "units: {other:?} is not metre, foot or us-survey-foot"
            )));
        }
    };
    Ok(LoadOptions {
        format,
        units,
        ground_only: if q.all_points == Some(true) {
            GroundFilter::All
        } else {
            GroundFilter::Auto
        },
        limits: CloudLimits {
            max_bytes: max_bytes as u64,
            ..CloudLimits::default()
        },
    })
}

/// Reads the cloud and extracts its surface: the record the site keeps. Pure CPU; run it off the async workers.
fn terrain_record(bytes: &[u8], q: &TerrainUploadQuery, opts: &LoadOptions) -> Result<TerrainSite, ApiError> {
    let cloud = load_cloud(bytes, opts).map_err(|e| ApiError::bad_request(format!("body: {e}")))?;
    let grid_m = q.grid_m.unwrap_or(0.5);
    let [lo, hi] = cloud.bounds;
    let cells = ((hi[0] - lo[0]) / grid_m + 1.0) * ((hi[1] - lo[1]) / grid_m + 1.0);
    if cells > MAX_CELLS {
        return Err(ApiError::bad_request(format!(
            "grid_m: the cloud spans {:.0} m × {:.0} m, {cells:.0} cells at {grid_m} m (at most {MAX_CELLS}); use a \
             coarser grid",
            hi[0] - lo[0],
            hi[1] - lo[1]
        )));
    }
    let mut params = TerrainParams::default();
    params.grid.cell_m = grid_m;
    let (surface, report) =
        extract_surface(&cloud.points, &params).map_err(|e| ApiError::bad_request(e.to_string()))?;
    let d = GroundLimits::default();
    let limits = GroundLimits {
        max_slope_rad: q.max_slope_deg.map_or(d.max_slope_rad, f64::to_radians),
        max_step_m: q.max_step_m.unwrap_or(d.max_step_m),
        max_roughness_m: q.max_roughness_m.unwrap_or(d.max_roughness_m),
    };
    Ok(TerrainSite::new(
        &surface,
        source_doc(&cloud, "upload"),
        &limits,
        report.interior_fill_rings,
    ))
}

/// Upload a point cloud (the file as the body: LAS, LAZ, PLY or PCD) as a ground robot's site. Units come from
/// the file's header (LAS in feet or US survey feet is converted to metres, and the site's warnings say so),
/// ground points by classification where the file has it. Slope, step and roughness over the limits are
/// obstacles; plans on the site carry each waypoint's ground height as z. Replaces the site's map.
#[utoipa::path(post, path = "/v1/sites/{site}/terrain", tag = "sites",
    params(("site" = String, Path, description = "site name: letters, digits, '-', '_'"), TerrainUploadQuery),
    request_body(content = Vec<u8>, description = "the cloud file", content_type = "application/octet-stream"),
    responses((status = 201, body = SiteSummary),
        (status = 400, description = "unreadable cloud or bad parameter (named in the message)", body = ErrorBody),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 413, description = "body over [http] max_body_bytes", body = ErrorBody)))]
pub async fn upload_terrain(
    State(state): State<AppState>,
    Path(site): Path<String>,
    RawQuery(raw): RawQuery,
    body: Bytes,
) -> Result<(StatusCode, ApiJson<SiteSummary>), ApiError> {
    shift_engine::site::validate_site_name(&site)?;
    let q = parse_query(raw.as_deref().unwrap_or(""))?;
    let opts = load_options(&q, state.body_limits.map_bytes)?;
    let terrain = tokio::task::spawn_blocking(move || terrain_record(&body, &q, &opts))
        .await
        .map_err(|_| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", "terrain reader stopped"))??;
    let record = SiteRecord {
        site,
        source: MapSource::Terrain {
            terrain: Box::new(terrain),
        },
        updated_ms: state.clock.now_ms(),
    };
    super::sites::store_site(&state, record, "terrain parser").await
}
