//! Fields in WGS84 (issue 23): `POST /v1/sites/{site}/field` (a GeoJSON field becomes a geo-referenced site),
//! `start_wgs84` in plan requests, and plans as GeoJSON in lon/lat (`GET /v1/plans/{id}/path?crs=wgs84`).
//! The projection is the engine's ([`shift_engine::field::frame::LocalFrame`]), rebuilt from the site's
//! `origin_wgs84`.

use axum::extract::{Path, State};
use axum::http::StatusCode;
use serde_json::{Value, json};
use shift_engine::field::frame::LocalFrame;
use shift_engine::{MapSource, SiteRecord};
use shift_proto::{ErrorBody, FieldRequest, PlanDocument, SiteSummary};

use super::AppState;
use super::error::{ApiError, ApiJson};

/// Upload a field drawn in GeoJSON (RFC 7946 `[lon, lat]`): its parts are free, holes and `no_go` polygons are
/// obstacles, the rest is outside. The site's map frame is a transverse Mercator centred on the field (metres,
/// x east, y north); the answer names it (`crs`, `origin_wgs84`). Replaces the site's map like a map upload.
#[utoipa::path(post, path = "/v1/sites/{site}/field", tag = "sites",
    params(("site" = String, Path, description = "site name: letters, digits, '-', '_'")),
    request_body = FieldRequest,
    responses((status = 201, body = SiteSummary),
        (status = 400, description = "invalid field (named in the message: field.coordinates[0][3] …)", body = ErrorBody),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 413, description = "body over [http] max_body_bytes", body = ErrorBody)))]
pub async fn upload_field(
    State(state): State<AppState>,
    Path(site): Path<String>,
    ApiJson(request): ApiJson<FieldRequest>,
) -> Result<(StatusCode, ApiJson<SiteSummary>), ApiError> {
    shift_engine::site::validate_site_name(&site)?;
    let record = SiteRecord {
        site,
        source: MapSource::Field { request },
        updated_ms: state.clock.now_ms(),
    };
    super::sites::store_site(&state, record, "field reader").await
}

/// The local frame of a geo-referenced site; `field` names the request field that needs it.
fn frame_of(state: &AppState, site: &str, field: &str) -> Result<LocalFrame, ApiError> {
    let summary = state
        .views
        .site(site)
        .ok_or_else(|| ApiError::not_found(format!("unknown site {site:?}")))?;
    let origin = summary.origin_wgs84.ok_or_else(|| {
        ApiError::bad_request(format!(
            "{field}: site {site:?} has no geo-reference (upload it with POST /v1/sites/{site}/field)"
        ))
    })?;
    Ok(LocalFrame::new(origin)?)
}

/// A plan request's `start_wgs84` turned into its `start` (map frame), in place.
pub fn resolve_start_wgs84(state: &AppState, body: &mut Value) -> Result<(), ApiError> {
    let Some(obj) = body.as_object_mut() else {
        return Ok(());
    };
    let Some(ll) = obj.remove("start_wgs84") else {
        return Ok(());
    };
    if obj.contains_key("start") {
        return Err(ApiError::bad_request(
            "start_wgs84: give start or start_wgs84, not both",
        ));
    }
    let pair = ll
        .as_array()
        .filter(|a| a.len() == 2)
        .and_then(|a| Some([a[0].as_f64()?, a[1].as_f64()?]))
        .ok_or_else(|| ApiError::bad_request("start_wgs84: [lon, lat] in degrees is expected"))?;
    let [lon, lat] = pair;
    if !(-180.0..=180.0).contains(&lon) || !(-90.0..=90.0).contains(&lat) {
        return Err(ApiError::bad_request(format!(
            "start_wgs84: [{lon}, {lat}] is not [lon, lat] (lon -180..180, lat -90..90)"
        )));
    }
    let site = obj.get("site").and_then(Value::as_str).unwrap_or_default().to_owned();
    let start = frame_of(state, &site, "start_wgs84")?.to_map(pair)?;
    obj.insert("start".into(), json!(start));
    Ok(())
}

/// A plan document as a GeoJSON Feature: a LineString of `[lon, lat]`, the waypoints' speeds, times and
/// kinds as properties.
pub fn plan_geojson(state: &AppState, site: &str, doc: &PlanDocument) -> Result<Value, ApiError> {
    let frame = frame_of(state, site, "crs")?;
    let coords = doc
        .waypoints
        .iter()
        .map(|w| frame.to_wgs84([w.x, w.y]))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(json!({
        "type": "Feature",
        "geometry": {"type": "LineString", "coordinates": coords},
        "properties": {
            "plan_id": doc.plan_id,
            "version": doc.version,
            "crs": "EPSG:4326",
            "map_crs": frame.proj_string(),
            "v": doc.waypoints.iter().map(|w| w.v).collect::<Vec<_>>(),
            "t": doc.waypoints.iter().map(|w| w.t).collect::<Vec<_>>(),
            "kind": doc.waypoints.iter().map(|w| w.kind).collect::<Vec<_>>(),
        }
    }))
}
