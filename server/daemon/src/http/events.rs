//! `GET /v1/plans/{id}/events`: Server-Sent Events of one plan. The first event is the current status; then
//! progress, region-ready and status events in the order the engine published them. The stream ends after a
//! failed / cancelled / done status, and on shutdown (otherwise graceful shutdown would wait forever).

use std::convert::Infallible;

use axum::extract::{Path, State};
use axum::response::sse::{Event as SseEvent, KeepAlive, Sse};
use futures_util::stream::{self, Stream, StreamExt};
use shift_proto::{ErrorBody, PlanEvent, PlanStatus};
use tokio_stream::wrappers::BroadcastStream;
use tokio_stream::wrappers::errors::BroadcastStreamRecvError;

use super::AppState;
use super::error::ApiError;

fn to_sse(e: &PlanEvent) -> SseEvent {
    SseEvent::default()
        .event(e.name())
        .data(serde_json::to_string(e).unwrap_or_else(|_| "{}".into()))
}

fn ends_stream(e: &PlanEvent) -> bool {
    matches!(e, PlanEvent::Status(s) if matches!(s.status, PlanStatus::Failed | PlanStatus::Cancelled | PlanStatus::Done))
}

/// Follow a plan's status, progress and region-ready events.
#[utoipa::path(get, path = "/v1/plans/{id}/events", tag = "plans", params(("id" = String, Path)),
    responses((status = 200, description = "text/event-stream of PlanEvent", body = PlanEvent),
        (status = 404, body = ErrorBody)))]
pub async fn plan_events(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<SseEvent, Infallible>>>, ApiError> {
    // Subscribe before reading the snapshot so nothing falls between the two.
    let rx = state.events.subscribe();
    let first = state
        .views
        .plan(&id)
        .ok_or_else(|| ApiError::not_found(format!("unknown plan {id:?}")))?
        .record
        .to_response();
    let first = PlanEvent::Status(first);
    let done_already = ends_stream(&first);
    let views = state.views.clone();
    let plan_id = id.clone();
    let live = BroadcastStream::new(rx).filter_map(move |item| {
        let out = match item {
            Ok(e) if e.plan_id() == plan_id => Some(e),
            Ok(_) => None,
            // A slow reader missed events: resynchronise with the current status.
            Err(BroadcastStreamRecvError::Lagged(_)) => {
                views.plan(&plan_id).map(|v| PlanEvent::Status(v.record.to_response()))
            }
        };
        std::future::ready(out)
    });
    let live = if done_already {
        live.take(0).boxed()
    } else {
        live.boxed()
    };
    // Stop after the terminal event (inclusive).
    let mut finished = false;
    let events = stream::once(std::future::ready(first))
        .chain(live)
        .take_while(move |e| {
            let go = !finished;
            finished = finished || ends_stream(e);
            std::future::ready(go)
        })
        .map(|e| Ok(to_sse(&e)))
        .take_until(state.shutdown.clone().cancelled_owned());
    Ok(Sse::new(events).keep_alive(KeepAlive::default()))
}
