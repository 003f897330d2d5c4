//! `GET /v1/plans/{id}/events`: Server-Sent Events of one plan. The first event is the current status; for a
//! plan still planning, the regions it already streamed follow (so a client that connects late can start a
//! robot on them too); then progress, region-ready and status events in the order the engine published them.
//! The stream ends after a failed / cancelled / done status, and on shutdown (otherwise graceful shutdown
//! would wait forever). A keep-alive comment goes out every `[http] sse_keep_alive_s`, so a reader that is gone
//! is noticed; a reader that stops reading is cut after `[http] write_stall_s` (`serve.rs`).

use std::collections::HashSet;
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
    let replay: Vec<PlanEvent> = if matches!(&first, PlanEvent::Status(s) if s.status == PlanStatus::Planning) {
        state
            .views
            .regions_ready(&id)
            .into_iter()
            .map(|region| PlanEvent::RegionReady {
                plan_id: id.clone(),
                region,
            })
            .collect()
    } else {
        Vec::new()
    };
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
    let events = subscription(first, replay, live)
        .map(|e| Ok(to_sse(&e)))
        .take_until(state.shutdown.clone().cancelled_owned());
    Ok(Sse::new(events).keep_alive(KeepAlive::new().interval(state.sse_keep_alive)))
}

/// One subscription's events: `first` (the current status); for a plan still planning, `replay` — the
/// regions it streamed before the client connected, so a late client can start a robot on them too; then
/// `live`, without the regions already replayed (the subscription starts before the snapshot, so the two
/// may overlap). Ends after a terminal status (inclusive); a plan already ended yields only `first`.
fn subscription(
    first: PlanEvent,
    replay: Vec<PlanEvent>,
    live: impl Stream<Item = PlanEvent> + Send + 'static,
) -> impl Stream<Item = PlanEvent> + Send {
    let done_already = ends_stream(&first);
    let mut replayed: HashSet<u32> = replay
        .iter()
        .filter_map(|e| match e {
            PlanEvent::RegionReady { region, .. } => Some(region.region),
            _ => None,
        })
        .collect();
    let live = live.filter(move |e| {
        let dup = matches!(e, PlanEvent::RegionReady { region, .. } if replayed.remove(&region.region));
        std::future::ready(!dup)
    });
    let live = if done_already {
        live.take(0).boxed()
    } else {
        live.boxed()
    };
    let mut finished = false;
    stream::once(std::future::ready(first))
        .chain(stream::iter(replay))
        .chain(live)
        .take_while(move |e| {
            let go = !finished;
            finished = finished || ends_stream(e);
            std::future::ready(go)
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use shift_proto::{PlanStatusResponse, RegionReady};

    fn region(id: u32) -> PlanEvent {
        PlanEvent::RegionReady {
            plan_id: "p".into(),
            region: RegionReady {
                region: id,
                polygon: vec![[0.0, 0.0]],
                path: vec![[f64::from(id), 0.0]],
            },
        }
    }

    fn status(status: PlanStatus) -> PlanEvent {
        PlanEvent::Status(PlanStatusResponse {
            plan_id: "p".into(),
            site: "s".into(),
            status,
            progress: 0.5,
            version: 0,
            regions_ready: 0,
            metrics: None,
            error: None,
            warnings: Vec::new(),
            robot: None,
            driven_fraction: None,
            missed: Vec::new(),
            corrections: 0,
            watch: None,
            progress_jumps: Vec::new(),
            mission: None,
            created_ms: 0,
            updated_ms: 0,
        })
    }

    fn names(events: &[PlanEvent]) -> Vec<String> {
        events
            .iter()
            .map(|e| match e {
                PlanEvent::RegionReady { region, .. } => format!("region {}", region.region),
                PlanEvent::Status(s) => format!("status {}", s.status.as_str()),
                other => other.name().to_owned(),
            })
            .collect()
    }

    #[tokio::test]
    async fn late_clients_get_the_regions_so_far_once_then_the_rest() {
        // Regions 0 and 1 were streamed before the client came; region 1 also arrives on the subscription
        // (it was published between subscribing and reading the snapshot).
        let live = stream::iter(vec![region(1), region(2), status(PlanStatus::Cancelled), region(9)]);
        let got: Vec<PlanEvent> = subscription(status(PlanStatus::Planning), vec![region(0), region(1)], live)
            .collect()
            .await;
        assert_eq!(
            names(&got),
            vec![
                "status planning",
                "region 0",
                "region 1",
                "region 2",
                "status cancelled"
            ]
        );
    }

    #[tokio::test]
    async fn an_ended_plan_yields_its_status_only() {
        let live = stream::iter(vec![region(3)]);
        let got: Vec<PlanEvent> = subscription(status(PlanStatus::Failed), Vec::new(), live)
            .collect()
            .await;
        assert_eq!(names(&got), vec!["status failed"]);
    }
}
