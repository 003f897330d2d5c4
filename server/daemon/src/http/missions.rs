//! Missions (issue 20): create, status, assign every part, cancel, follow as SSE; and a site's measured
//! coverage raster (`GET /v1/sites/{site}/coverage`, JSON like nav_msgs/OccupancyGrid or `?format=png`).

use std::collections::HashMap;
use std::convert::Infallible;
use std::io::Cursor;

use axum::body::Body;
use axum::extract::{Path, Query, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::sse::{Event as SseEvent, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use futures_util::stream::{self, Stream, StreamExt};
use shift_engine::Event;
use shift_planner::map::CellState;
use shift_proto::{
    ErrorBody, MissionAccepted, MissionRequest, MissionRobot, MissionStatus, MissionView, OccupancyGridDoc,
};
use tokio_stream::wrappers::BroadcastStream;
use tokio_stream::wrappers::errors::BroadcastStreamRecvError;

use super::AppState;
use super::error::{ApiError, ApiJson};
use crate::engine_loop::handle::Reply;

fn internal(what: &str) -> ApiError {
    ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", what.to_owned())
}

/// Ask for a mission: the site divided among the robots (balanced by the time each part takes, every part
/// connected and holding its robot's dock) and every part planned. Answers 202 once the mission and its plans
/// are committed; each part is an ordinary plan (`/v1/plans/{plan_id}`). The whole request is checked first
/// (400 names the field: `robots[i].…`); nothing is stored on a refusal.
#[utoipa::path(post, path = "/v1/missions", tag = "missions", request_body = MissionRequest,
    responses((status = 202, body = MissionAccepted, headers(("Location" = String))),
        (status = 400, description = "invalid field (named in the message)", body = ErrorBody),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, description = "unknown site", body = ErrorBody),
        (status = 413, description = "body over [http] max_request_bytes", body = ErrorBody),
        (status = 429, description = "job queue full", body = ErrorBody,
            headers(("Retry-After" = u64, description = "seconds to wait before asking again")))))]
pub async fn create_mission(
    State(state): State<AppState>,
    ApiJson(request): ApiJson<MissionRequest>,
) -> Result<(StatusCode, HeaderMap, ApiJson<MissionAccepted>), ApiError> {
    let reply = state
        .engine
        .call(Event::MissionRequested { request })
        .await
        .map_err(|e| match ApiError::from(e) {
            full if full.status == StatusCode::TOO_MANY_REQUESTS => full.with_retry_after(state.retry_after_s),
            other => other,
        })?;
    let view = reply
        .missions
        .into_iter()
        .next()
        .ok_or_else(|| internal("no mission record"))?;
    let mut headers = HeaderMap::new();
    if let Ok(v) = HeaderValue::from_str(&format!("/v1/missions/{}", view.mission_id)) {
        headers.insert(header::LOCATION, v);
    }
    Ok((
        StatusCode::ACCEPTED,
        headers,
        ApiJson(MissionAccepted {
            mission_id: view.mission_id,
            status: MissionStatus::Queued,
        }),
    ))
}

fn mission_view(state: &AppState, id: &str) -> Result<MissionView, ApiError> {
    state
        .views
        .mission(id)
        .ok_or_else(|| ApiError::not_found(format!("unknown mission {id:?}")))
}

/// The mission's view the engine's answer carries (its latest), else the read model's.
fn answered(state: &AppState, reply: Reply, id: &str) -> Result<MissionView, ApiError> {
    match reply.missions.into_iter().last() {
        Some(v) => Ok(v),
        None => mission_view(state, id),
    }
}

/// A mission's status, its plans (one per robot), planned and measured coverage, progress and ETA.
#[utoipa::path(get, path = "/v1/missions/{id}", tag = "missions", params(("id" = String, Path)),
    responses((status = 200, body = MissionView), (status = 404, body = ErrorBody)))]
pub async fn get_mission(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<ApiJson<MissionView>, ApiError> {
    Ok(ApiJson(mission_view(&state, &id)?))
}

/// Assign every plan of a planned mission to its robot, all or none (409 when a plan is not ready). Each robot
/// gets its plan as with `POST /v1/plans/{id}/assign`.
#[utoipa::path(post, path = "/v1/missions/{id}/assign", tag = "missions", params(("id" = String, Path)),
    responses((status = 200, body = MissionView),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, description = "not planned", body = ErrorBody)))]
pub async fn assign_mission(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<ApiJson<MissionView>, ApiError> {
    let view = mission_view(&state, &id)?;
    let mut docs = Vec::with_capacity(view.plans.len());
    for p in &view.plans {
        let doc = state.views.plan(&p.plan_id).and_then(|v| v.doc).ok_or_else(|| {
            ApiError::new(
                StatusCode::CONFLICT,
                "invalid_state",
                format!(
                    "mission {id} is {}; plan {} of robot {} is not computed",
                    view.status.as_str(),
                    p.plan_id,
                    p.robot
                ),
            )
        })?;
        docs.push(doc);
    }
    let reply = state
        .engine
        .call(Event::MissionAssignRequested {
            mission_id: id.clone(),
            docs,
        })
        .await?;
    Ok(ApiJson(answered(&state, reply, &id)?))
}

/// Replan what the mission has left: the cells its robots' tools swept are left out, the rest (cleaned of
/// slivers not worth a pass) is divided among its robots that are not lost, each from where it is, and each
/// plan gets its next version (delivered to the robot driving it). Answers 202 at once; the view's plans show
/// the new versions when the job ends. The daemon does the same by itself when a robot is lost or comes back
/// and after a restart with the mission under way. 409 before the mission is planned or once it is done.
#[utoipa::path(post, path = "/v1/missions/{id}/replan", tag = "missions", params(("id" = String, Path)),
    responses((status = 202, body = MissionView),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn replan_mission(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<(StatusCode, ApiJson<MissionView>), ApiError> {
    let reply = state
        .engine
        .call(Event::MissionReplanRequested { mission_id: id.clone() })
        .await?;
    Ok((StatusCode::ACCEPTED, ApiJson(answered(&state, reply, &id)?)))
}

/// A robot joins a mission: checked as the mission's robots are (`robots[n]` in messages, n its place after
/// the others), given a plan of the mission, and a replan divides what is left among all of them, the new
/// robot included (each from where it stands). Under way, it gets its share at once; a mission not yet assigned
/// gives it at assignment; a queued mission plans with it. 409 while the mission is being planned or once it
/// ended.
#[utoipa::path(post, path = "/v1/missions/{id}/robots", tag = "missions", params(("id" = String, Path)),
    request_body = MissionRobot,
    responses((status = 202, body = MissionView),
        (status = 400, description = "invalid field (named in the message)", body = ErrorBody),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn join_mission(
    State(state): State<AppState>,
    Path(id): Path<String>,
    ApiJson(robot): ApiJson<MissionRobot>,
) -> Result<(StatusCode, ApiJson<MissionView>), ApiError> {
    let reply = state
        .engine
        .call(Event::MissionRobotJoined {
            mission_id: id.clone(),
            robot,
        })
        .await?;
    Ok((StatusCode::ACCEPTED, ApiJson(answered(&state, reply, &id)?)))
}

/// Cancel a mission: its plans not yet driven are cancelled; a robot already driving its part finishes it
/// (stopping it is the backend's call). 409 once the mission is done, failed or cancelled.
#[utoipa::path(delete, path = "/v1/missions/{id}", tag = "missions", params(("id" = String, Path)),
    responses((status = 200, body = MissionView),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody)))]
pub async fn cancel_mission(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<ApiJson<MissionView>, ApiError> {
    let reply = state
        .engine
        .call(Event::MissionCancelRequested { mission_id: id })
        .await?;
    let view = reply
        .missions
        .into_iter()
        .last()
        .ok_or_else(|| internal("no mission view"))?;
    Ok(ApiJson(view))
}

/// Follow a mission: `mission` events carrying its view, the current one first, then on every change (at most
/// about once a second while only progress and measured coverage move). Ends after `done`, `failed` or
/// `cancelled`, and on shutdown.
#[utoipa::path(get, path = "/v1/missions/{id}/events", tag = "missions", params(("id" = String, Path)),
    responses((status = 200, description = "text/event-stream of `mission` events", body = MissionView),
        (status = 404, body = ErrorBody)))]
pub async fn mission_events(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<SseEvent, Infallible>>>, ApiError> {
    // Subscribe before reading the snapshot so nothing falls between the two.
    let rx = state.mission_events.subscribe();
    let first = mission_view(&state, &id)?;
    let views = state.views.clone();
    let mission_id = id.clone();
    let live = BroadcastStream::new(rx).filter_map(move |item| {
        std::future::ready(match item {
            Ok(v) if v.mission_id == mission_id => Some(v),
            Ok(_) => None,
            Err(BroadcastStreamRecvError::Lagged(_)) => views.mission(&mission_id),
        })
    });
    let done_already = first.status.is_settled();
    let mut finished = false;
    let events = stream::once(std::future::ready(first))
        .chain(live.take(if done_already { 0 } else { usize::MAX }))
        .take_while(move |v| {
            let go = !finished;
            finished = v.status.is_settled();
            std::future::ready(go)
        })
        .map(|v| {
            Ok(SseEvent::default()
                .event("mission")
                .data(serde_json::to_string(&v).unwrap_or_else(|_| "{}".into())))
        })
        .take_until(state.shutdown.clone().cancelled_owned());
    Ok(Sse::new(events).keep_alive(KeepAlive::new().interval(state.sse_keep_alive)))
}

/// What the robots' tools swept on a site while driving plans (issue 20), over the site's map: `100` swept,
/// `0` free and not swept, `-1` not free on the map. `?format=png`: the map in greys, swept cells green, row 0
/// of the image the map's top (largest y). Refreshed about once a second while robots sweep.
#[utoipa::path(get, path = "/v1/sites/{site}/coverage", tag = "sites",
    params(("site" = String, Path), ("format" = Option<String>, Query, description = "`json` (default) or `png`")),
    responses((status = 200, body = OccupancyGridDoc, description = "JSON grid; with `?format=png` an image/png"),
        (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn get_site_coverage(
    State(state): State<AppState>,
    Path(site): Path<String>,
    Query(query): Query<HashMap<String, String>>,
) -> Result<Response, ApiError> {
    let format = query.get("format").map_or("json", String::as_str);
    if let Some(k) = query.keys().find(|k| k.as_str() != "format") {
        return Err(ApiError::bad_request(format!("{k}: unknown parameter (only format)")));
    }
    let grid = state
        .views
        .site_map(&site)
        .ok_or_else(|| ApiError::not_found(format!("unknown site {site:?}")))?;
    let g = grid.geometry;
    let swept = match state.views.coverage(&site) {
        Some(rec) if rec.fits(&g) => rec.covered.decode(g.len()).map_err(|e| internal(&e.to_string()))?,
        _ => vec![false; g.len()],
    };
    let cells: Vec<i16> = (grid.cells.iter().zip(&swept))
        .map(|(c, &s)| match (c, s) {
            (_, true) => 100,
            (CellState::Free, false) => 0,
            _ => -1,
        })
        .collect();
    match format {
        "json" => Ok(ApiJson(OccupancyGridDoc {
            resolution: g.resolution,
            origin: [g.origin.x, g.origin.y],
            width: g.width as u64,
            height: g.height as u64,
            cells,
            free_thresh: None,
            occupied_thresh: None,
        })
        .into_response()),
        "png" => {
            let png = coverage_png(&grid.cells, &cells, g.width, g.height).map_err(|e| internal(&e))?;
            Ok(([(header::CONTENT_TYPE, "image/png")], Body::from(png)).into_response())
        }
        other => Err(ApiError::bad_request(format!("format: {other:?} is not json or png"))),
    }
}

/// The map in greys (free white, occupied black, unknown grey) with swept cells green; image row 0 is the
/// map's top row.
fn coverage_png(map: &[CellState], cells: &[i16], width: usize, height: usize) -> Result<Vec<u8>, String> {
    let (w, h) = (
        u32::try_from(width).map_err(|e| e.to_string())?,
        u32::try_from(height).map_err(|e| e.to_string())?,
    );
    let mut img = image::RgbImage::new(w, h);
    for (row, pixels) in (0..height).rev().zip(img.rows_mut()) {
        for (col, px) in pixels.enumerate() {
            let i = row * width + col;
            *px = image::Rgb(match (cells[i], map[i]) {
                (100, _) => [46, 160, 67],
                (_, CellState::Free) => [250, 250, 250],
                (_, CellState::Occupied) => [20, 20, 20],
                _ => [160, 160, 160],
            });
        }
    }
    let mut out = Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(out.into_inner())
}
