//! Plan routes: create, status, path, speed profile, corrections, cancel.

use axum::extract::{Path, RawQuery, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use shift_engine::Event;
use shift_proto::{
    CorrectionDoc, ErrorBody, PlanAccepted, PlanDocument, PlanRequest, PlanStatusResponse, SpeedProfileResponse,
    SpeedSample,
};

use super::AppState;
use super::error::{ApiError, ApiJson};
use crate::views::PlanView;

fn view(state: &AppState, plan_id: &str) -> Result<PlanView, ApiError> {
    state
        .views
        .plan(plan_id)
        .ok_or_else(|| ApiError::not_found(format!("unknown plan {plan_id:?}")))
}

fn ready_doc(state: &AppState, plan_id: &str) -> Result<std::sync::Arc<PlanDocument>, ApiError> {
    let v = view(state, plan_id)?;
    v.doc.ok_or_else(|| {
        ApiError::new(
            StatusCode::CONFLICT,
            "not_ready",
            format!(
                "plan {plan_id} is {}; its path is not computed",
                v.record.status.as_str()
            ),
        )
    })
}

/// Ask for a plan. Answers 202 at once, after the request is committed to the store; the job runs on the
/// worker pool. Poll `GET /v1/plans/{id}` or follow `/events`. The whole request is checked before anything
/// is stored (400 names the field); a full queue answers 429 with `Retry-After`. On a field site,
/// `"start_wgs84": [lon, lat]` may stand for `start`.
#[utoipa::path(post, path = "/v1/plans", tag = "plans", request_body = PlanRequest,
    responses((status = 202, body = PlanAccepted, headers(("Location" = String))),
        (status = 400, description = "invalid field (named in the message)", body = ErrorBody),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, description = "unknown site", body = ErrorBody),
        (status = 408, description = "request not received in time", body = ErrorBody),
        (status = 413, description = "body over [http] max_request_bytes", body = ErrorBody),
        (status = 429, description = "plan queue full", body = ErrorBody,
            headers(("Retry-After" = u64, description = "seconds to wait before asking again")))))]
pub async fn create_plan(
    State(state): State<AppState>,
    ApiJson(mut body): ApiJson<serde_json::Value>,
) -> Result<(StatusCode, HeaderMap, ApiJson<PlanAccepted>), ApiError> {
    // A start in lon/lat becomes the map-frame start before the request is read (a field site's frame).
    super::field::resolve_start_wgs84(&state, &mut body)?;
    let bytes = serde_json::to_vec(&body).map_err(|e| ApiError::bad_request(e.to_string()))?;
    let axum::Json(request): axum::Json<PlanRequest> = axum::Json::from_bytes(&bytes)?;
    let reply = state
        .engine
        .call(Event::PlanRequested { request })
        .await
        .map_err(|e| match ApiError::from(e) {
            full if full.status == StatusCode::TOO_MANY_REQUESTS => full.with_retry_after(state.retry_after_s),
            other => other,
        })?;
    let rec = reply
        .plans
        .into_iter()
        .next()
        .ok_or_else(|| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", "no plan record"))?;
    let mut headers = HeaderMap::new();
    if let Ok(v) = HeaderValue::from_str(&format!("/v1/plans/{}", rec.plan_id)) {
        headers.insert(header::LOCATION, v);
    }
    Ok((
        StatusCode::ACCEPTED,
        headers,
        ApiJson(PlanAccepted {
            plan_id: rec.plan_id,
            status: shift_proto::PlanStatus::Queued,
        }),
    ))
}

/// A plan's status, progress and metrics.
#[utoipa::path(get, path = "/v1/plans/{id}", tag = "plans", params(("id" = String, Path)),
    responses((status = 200, body = PlanStatusResponse), (status = 404, body = ErrorBody)))]
pub async fn get_plan(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<ApiJson<PlanStatusResponse>, ApiError> {
    Ok(ApiJson(view(&state, &id)?.record.to_response()))
}

/// The plan document (DESIGN §5.1), current version. With `?crs=wgs84` (a plan on a field site): a GeoJSON
/// Feature whose LineString holds `[lon, lat]`, with the waypoints' `v`, `t` and `kind` as properties.
#[utoipa::path(get, path = "/v1/plans/{id}/path", tag = "plans",
    params(("id" = String, Path), ("crs" = Option<String>, Query, description = "`wgs84`: GeoJSON in lon/lat")),
    responses((status = 200, body = PlanDocument), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody),
        (status = 409, description = "not computed yet", body = ErrorBody)))]
pub async fn get_path(
    State(state): State<AppState>,
    Path(id): Path<String>,
    RawQuery(raw): RawQuery,
) -> Result<Response, ApiError> {
    let mut wgs84 = false;
    for (key, value) in super::listings::query_pairs(raw.as_deref().unwrap_or(""))? {
        match (key.as_str(), value.as_str()) {
            ("crs", "wgs84" | "WGS84" | "EPSG:4326") => wgs84 = true,
            ("crs", "map") => wgs84 = false,
            ("crs", other) => return Err(ApiError::bad_request(format!("crs: {other:?} is not wgs84 or map"))),
            (other, _) => return Err(ApiError::bad_request(format!("{other}: unknown parameter (crs)"))),
        }
    }
    let doc = ready_doc(&state, &id)?;
    if wgs84 {
        let site = view(&state, &id)?.record.request.site.clone();
        return Ok(ApiJson(super::field::plan_geojson(&state, &site, &doc)?).into_response());
    }
    Ok(ApiJson((*doc).clone()).into_response())
}

/// Per waypoint: arc length s (m), speed v (m/s), time t (s).
#[utoipa::path(get, path = "/v1/plans/{id}/speed-profile", tag = "plans", params(("id" = String, Path)),
    responses((status = 200, body = SpeedProfileResponse), (status = 404, body = ErrorBody),
        (status = 409, body = ErrorBody)))]
pub async fn get_speed_profile(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<ApiJson<SpeedProfileResponse>, ApiError> {
    let doc = ready_doc(&state, &id)?;
    let mut s = 0.0;
    let mut prev: Option<(f64, f64)> = None;
    let samples = doc
        .waypoints
        .iter()
        .map(|w| {
            if let Some((x, y)) = prev {
                s += (w.x - x).hypot(w.y - y);
            }
            prev = Some((w.x, w.y));
            SpeedSample { s, v: w.v, t: w.t }
        })
        .collect();
    Ok(ApiJson(SpeedProfileResponse {
        plan_id: id,
        version: doc.version,
        samples,
    }))
}

/// The corrections that made the plan's current document, oldest first (the last 200; a replan of a mission
/// starts a new line and drops them). Each replaced `waypoints[from..to)` of `base_version`.
#[utoipa::path(get, path = "/v1/plans/{id}/corrections", tag = "plans", params(("id" = String, Path)),
    responses((status = 200, body = [CorrectionDoc]), (status = 404, body = ErrorBody)))]
pub async fn get_corrections(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<ApiJson<Vec<CorrectionDoc>>, ApiError> {
    view(&state, &id)?;
    Ok(ApiJson(
        state.views.corrections(&id).iter().map(|c| (**c).clone()).collect(),
    ))
}

/// Cancel a queued or planning plan (409 once it finished).
#[utoipa::path(delete, path = "/v1/plans/{id}", tag = "plans", params(("id" = String, Path)),
    responses((status = 200, body = PlanStatusResponse),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn cancel_plan(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<ApiJson<PlanStatusResponse>, ApiError> {
    let reply = state.engine.call(Event::CancelRequested { plan_id: id }).await?;
    let rec = reply
        .plans
        .into_iter()
        .next()
        .ok_or_else(|| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", "no plan record"))?;
    Ok(ApiJson(rec.to_response()))
}
