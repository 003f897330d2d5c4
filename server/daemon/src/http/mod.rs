//! The HTTP API (DESIGN §5.3): one [`router`] built from an [`AppState`] of handles and snapshots (no
//! algorithm, no lock around the engine). Handlers are grouped by resource; errors in `error.rs`.

mod auth;
pub mod error;
mod events;
mod listings;
mod openapi;
mod ops;
mod plans;
mod robots;
mod sites;

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::StatusCode;
use axum::routing::{get, post};
use metrics_exporter_prometheus::PrometheusHandle;
use shift_proto::PlanEvent;
use tokio::sync::broadcast;
use tokio_util::sync::CancellationToken;
use tower_http::timeout::TimeoutLayer;
use tower_http::trace::TraceLayer;

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
    /// Cancelled on shutdown (ends event streams).
    pub shutdown: CancellationToken,
    /// Prometheus exposition.
    pub prometheus: PrometheusHandle,
    /// Bearer token for mutating routes; empty = none.
    pub auth_token: Arc<str>,
    /// Largest request body, bytes.
    pub max_body_bytes: usize,
    /// Per-request timeout.
    pub request_timeout: Duration,
}

/// The whole API.
pub fn router(state: AppState) -> Router {
    let api = Router::new()
        .route("/v1/sites", get(listings::list_sites))
        .route(
            "/v1/sites/{site}/map",
            post(sites::upload_map).get(listings::get_site_map),
        )
        .route("/v1/sites/{site}", get(sites::get_site))
        .route("/v1/plans", post(plans::create_plan).get(listings::list_plans))
        .route("/v1/plans/{id}", get(plans::get_plan).delete(plans::cancel_plan))
        .route("/v1/plans/{id}/path", get(plans::get_path))
        .route("/v1/plans/{id}/speed-profile", get(plans::get_speed_profile))
        .route("/v1/plans/{id}/assign", post(robots::assign_plan))
        .route("/v1/robots", get(robots::list_robots))
        .route("/v1/robots/{id}", get(robots::get_robot))
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            state.request_timeout,
        ))
        // Event streams live long: no timeout.
        .route("/v1/plans/{id}/events", get(events::plan_events))
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
        .fallback(|| async { error::ApiError::not_found("no such route") })
        .layer(axum::middleware::from_fn(ops::track))
        .layer(DefaultBodyLimit::max(state.max_body_bytes))
        .layer(TraceLayer::new_for_http())
        .with_state(state)
}
