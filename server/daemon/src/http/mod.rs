//! The HTTP API (DESIGN §5.3): one [`router`] built from an [`AppState`] of handles and snapshots (no
//! algorithm, no lock around the engine). Handlers are grouped by resource; errors in `error.rs`.
//!
//! The doors (DESIGN §8), outermost first: the connection loop (`serve.rs`: header read timeout, connection
//! cap, write stalls), uniform error bodies (`json_errors.rs`), the request timeout, the bearer token
//! (`auth.rs`, `token.rs`), then per route the body limit (tower-http's `RequestBodyLimitLayer`: a declared
//! `Content-Length` over it is refused before the body is read, a chunked body is cut at it).

mod auth;
mod dashboard;
pub mod error;
mod events;
mod field;
mod json_errors;
mod listings;
mod live;
mod missions;
mod openapi;
mod ops;
mod plans;
mod robots;
pub mod serve;
mod site_events;
mod sites;
pub mod stall;
mod terrain;
pub mod token;

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::StatusCode;
use axum::routing::{MethodRouter, get, post};
use metrics_exporter_prometheus::PrometheusHandle;
use shift_proto::PlanEvent;
use tokio::sync::broadcast;
use tokio_util::sync::CancellationToken;
use tower_http::limit::RequestBodyLimitLayer;
use tower_http::timeout::TimeoutLayer;
use tower_http::trace::TraceLayer;

pub use json_errors::{BodyLimit, BodyLimits};
pub use openapi::ApiDoc;

use shift_engine::LiveMaps;
use shift_engine::sensors::SensorHub;

use crate::clock::SharedClock;
use crate::engine_loop::handle::EngineHandle;
use crate::views::Views;

/// What handlers hold: channel handles and read snapshots.
#[derive(Clone)]
pub struct AppState {
    /// The engine loop.
    pub engine: EngineHandle,
    /// Read model of plans and sites.
    pub views: Arc<Views>,
    /// Live site maps (ikd-trees fed by the fleet).
    pub live: Arc<LiveMaps>,
    /// The fleet's sensor pipeline (per-robot figures for `GET /v1/robots`).
    pub sensors: Arc<std::sync::Mutex<SensorHub>>,
    /// The time.
    pub clock: SharedClock,
    /// Plan events, for SSE subscribers.
    pub events: broadcast::Sender<PlanEvent>,
    /// Mission views, for SSE subscribers.
    pub mission_events: broadcast::Sender<shift_proto::MissionView>,
    /// Cancelled on shutdown (ends event streams).
    pub shutdown: CancellationToken,
    /// Prometheus exposition.
    pub prometheus: PrometheusHandle,
    /// Bearer token for mutating routes; empty = none.
    pub auth_token: Arc<token::Secret>,
    /// Largest request bodies, bytes, per route.
    pub body_limits: BodyLimits,
    /// Per-request timeout.
    pub request_timeout: Duration,
    /// Keep-alive interval of event streams.
    pub sse_keep_alive: Duration,
    /// `Retry-After` of a full plan queue, seconds.
    pub retry_after_s: u64,
}

/// A route whose body may hold at most `limit.bytes`: tower-http's limit (a `Content-Length` over it is refused
/// before the body is read; a chunked body is cut at it), and axum's own extractor limit off, so the
/// extractors see tower-http's `LengthLimitError` directly (multipart maps it to 413 only then). Its 413 names
/// the limit and the key that sets it.
fn limited(route: MethodRouter<AppState>, limit: BodyLimit) -> MethodRouter<AppState> {
    route
        .layer::<_, std::convert::Infallible>(RequestBodyLimitLayer::new(limit.bytes))
        .layer::<_, std::convert::Infallible>(DefaultBodyLimit::disable())
        .layer::<_, std::convert::Infallible>(axum::middleware::map_response(move |res: axum::response::Response| {
            limit.name_in_413(res)
        }))
}

/// The whole API.
pub fn router(state: AppState) -> Router {
    let api = Router::new()
        .route("/v1/sites", get(listings::list_sites))
        .route(
            "/v1/sites/{site}/map",
            limited(post(sites::upload_map), state.body_limits.map()).get(listings::get_site_map),
        )
        .route("/v1/sites/{site}", get(sites::get_site))
        .route(
            "/v1/sites/{site}/field",
            limited(post(field::upload_field), state.body_limits.map()),
        )
        .route(
            "/v1/sites/{site}/terrain",
            limited(post(terrain::upload_terrain), state.body_limits.map()),
        )
        .route(
            "/v1/plans",
            limited(post(plans::create_plan), state.body_limits.request()).get(listings::list_plans),
        )
        .route("/v1/plans/{id}", get(plans::get_plan).delete(plans::cancel_plan))
        .route("/v1/plans/{id}/path", get(plans::get_path))
        .route("/v1/plans/{id}/speed-profile", get(plans::get_speed_profile))
        .route("/v1/plans/{id}/corrections", get(plans::get_corrections))
        .route("/v1/sites/{site}/live", get(live::get_live))
        .route(
            "/v1/plans/{id}/assign",
            limited(post(robots::assign_plan), state.body_limits.request()),
        )
        .route("/v1/sites/{site}/coverage", get(missions::get_site_coverage))
        .route(
            "/v1/missions",
            limited(post(missions::create_mission), state.body_limits.request()),
        )
        .route(
            "/v1/missions/{id}",
            get(missions::get_mission).delete(missions::cancel_mission),
        )
        .route("/v1/missions/{id}/assign", post(missions::assign_mission))
        .route("/v1/missions/{id}/replan", post(missions::replan_mission))
        .route(
            "/v1/missions/{id}/robots",
            limited(post(missions::join_mission), state.body_limits.request()),
        )
        .route("/v1/robots", get(robots::list_robots))
        .route("/v1/robots/{id}", get(robots::get_robot))
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            state.request_timeout,
        ))
        // Event streams live long: no timeout (a reader that stops reading is cut by `serve`'s write stall).
        .route("/v1/plans/{id}/events", get(events::plan_events))
        .route("/v1/missions/{id}/events", get(missions::mission_events))
        .route("/v1/sites/{site}/events", get(site_events::site_events))
        .route_layer(axum::middleware::from_fn_with_state(
            state.auth_token.clone(),
            auth::require_token,
        ));
    Router::new()
        .merge(api)
        .route("/healthz", get(ops::healthz))
        .route("/readyz", get(ops::readyz))
        .route("/metrics", get(ops::metrics_text))
        .route("/openapi.json", get(openapi::openapi_json))
        .route("/docs", get(openapi::docs_page))
        // The operator's page: static, embedded, open (its API calls carry the token where one is needed).
        .route("/", get(dashboard::index))
        .route("/dashboard/{file}", get(dashboard::file))
        .fallback(|| async { error::ApiError::not_found("no such route") })
        .layer(axum::middleware::from_fn(ops::track))
        // The routes' own limits decide; this is the backstop of any body-reading route without one.
        .layer(DefaultBodyLimit::max(state.body_limits.map_bytes))
        .layer(axum::middleware::from_fn_with_state(
            state.body_limits,
            json_errors::json_errors,
        ))
        .layer(TraceLayer::new_for_http())
        .with_state(state)
}
