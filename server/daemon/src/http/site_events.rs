//! `GET /v1/sites/{site}/events`: Server-Sent Events of one site, what the operator's page follows. First
//! `site` (its summary), then as things happen:
//! - `robots` — the site's robots whose view changed (pose, liveliness, plan, progress, last correction), at
//!   most one event per [`ROBOTS_EVERY`]; the first holds all of them. Robots are sampled from the read model,
//!   so a fleet publishing odometry at 50 Hz costs a page 10 events a second, not thousands.
//! - `status`, `progress`, `region-ready`, `correction` — [`PlanEvent`]s of the site's plans, as
//!   `GET /v1/plans/{id}/events` sends them;
//! - `mission` — [`shift_proto::MissionView`]s of the site's missions;
//! - `coverage`, `live` — [`SiteChanged`]: the measured raster or the live map changed (checked every
//!   [`CHANGES_EVERY`]); the page fetches them again.
//!
//! A keep-alive comment goes out every `[http] sse_keep_alive_s`; the stream ends on shutdown or when the
//! reader goes away.

use std::collections::HashMap;
use std::convert::Infallible;
use std::time::Duration;

use axum::extract::{Path, State};
use axum::response::sse::{Event as SseEvent, KeepAlive, Sse};
use futures_util::stream::{Stream, StreamExt};
use serde::Serialize;
use shift_proto::{ErrorBody, PlanEvent, RobotView, RobotsUpdate, SiteChanged};
use tokio::sync::{broadcast, mpsc};
use tokio_stream::wrappers::ReceiverStream;

use super::AppState;
use super::error::ApiError;
use super::live::live_count;

/// Shortest time between two `robots` events of one stream.
pub const ROBOTS_EVERY: Duration = Duration::from_millis(100);

/// How often the coverage raster and the live map are looked at.
pub const CHANGES_EVERY: Duration = Duration::from_secs(1);

/// Events a slow reader may have in hand before the newest are dropped (robots and changes are sent again
/// whole at the next tick, plan events are re-read by status).
const QUEUE: usize = 256;

fn event(name: &str, body: &impl Serialize) -> SseEvent {
    SseEvent::default()
        .event(name)
        .data(serde_json::to_string(body).unwrap_or_else(|_| "{}".into()))
}

/// The robots of `site` whose view differs from `sent` (all when `sent` is empty), remembering them.
fn changed_robots(site: &str, robots: Vec<RobotView>, sent: &mut HashMap<String, RobotView>) -> Vec<RobotView> {
    let mut out = Vec::new();
    for view in robots.into_iter().filter(|r| r.site.as_deref() == Some(site)) {
        if sent.get(&view.robot) != Some(&view) {
            sent.insert(view.robot.clone(), view.clone());
            out.push(view);
        }
    }
    out
}

/// What one stream remembers of what it sent.
#[derive(Default)]
struct Sent {
    robots: HashMap<String, RobotView>,
    coverage_ms: Option<u64>,
    live: Option<usize>,
}

/// Follow a site: its robots, plans, missions, measured coverage and live map.
#[utoipa::path(get, path = "/v1/sites/{site}/events", tag = "sites",
    params(("site" = String, Path, description = "site name")),
    responses((status = 200, description = "text/event-stream: site, robots, status, progress, region-ready, \
        correction, mission, coverage, live", body = RobotsUpdate), (status = 404, body = ErrorBody)))]
pub async fn site_events(
    State(state): State<AppState>,
    Path(site): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<SseEvent, Infallible>>>, ApiError> {
    let summary = state
        .views
        .site(&site)
        .ok_or_else(|| ApiError::not_found(format!("unknown site {site:?}")))?;
    // Subscribe before the first snapshot so nothing falls between the two.
    let plans = state.events.subscribe();
    let missions = state.mission_events.subscribe();
    let (tx, rx) = mpsc::channel(QUEUE);
    let _ = tx.try_send(event("site", &summary));
    tokio::spawn(follow(state.clone(), site, plans, missions, tx));
    let events = ReceiverStream::new(rx).map(Ok);
    Ok(Sse::new(events).keep_alive(KeepAlive::new().interval(state.sse_keep_alive)))
}

/// The stream's task: ends with the reader (the channel closes), or on shutdown.
async fn follow(
    state: AppState,
    site: String,
    mut plans: broadcast::Receiver<PlanEvent>,
    mut missions: broadcast::Receiver<shift_proto::MissionView>,
    tx: mpsc::Sender<SseEvent>,
) {
    let mut sent = Sent::default();
    let mut robots_tick = tokio::time::interval(ROBOTS_EVERY);
    let mut changes_tick = tokio::time::interval(CHANGES_EVERY);
    for tick in [&mut robots_tick, &mut changes_tick] {
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    }
    loop {
        let out = tokio::select! {
            () = state.shutdown.cancelled() => return,
            () = tx.closed() => return,
            _ = robots_tick.tick() => {
                let changed = changed_robots(&site, state.views.robots(), &mut sent.robots);
                (!changed.is_empty()).then(|| event("robots", &RobotsUpdate { robots: changed }))
            }
            _ = changes_tick.tick() => {
                changes(&state, &site, &mut sent, &tx);
                None
            }
            got = plans.recv() => match got {
                Ok(e) => on_site(&state, &site, e.plan_id()).then(|| event(e.name(), &e)),
                Err(broadcast::error::RecvError::Lagged(_)) => None,
                Err(broadcast::error::RecvError::Closed) => return,
            },
            got = missions.recv() => match got {
                Ok(m) => (m.site == site).then(|| event("mission", &m)),
                Err(broadcast::error::RecvError::Lagged(_)) => None,
                Err(broadcast::error::RecvError::Closed) => return,
            },
        };
        // A full queue is a slow reader: it misses this one (robots and changes come again whole).
        if let Some(e) = out {
            let _ = tx.try_send(e);
        }
    }
}

/// `coverage` and `live` when they changed since the last look.
fn changes(state: &AppState, site: &str, sent: &mut Sent, tx: &mpsc::Sender<SseEvent>) {
    if let Some(raster) = state.views.coverage(site)
        && sent.coverage_ms != Some(raster.updated_ms)
    {
        sent.coverage_ms = Some(raster.updated_ms);
        let body = SiteChanged {
            site: site.to_owned(),
            updated_ms: Some(raster.updated_ms),
            count: None,
        };
        let _ = tx.try_send(event("coverage", &body));
    }
    let count = live_count(state, site);
    if sent.live != Some(count) {
        sent.live = Some(count);
        let body = SiteChanged {
            site: site.to_owned(),
            updated_ms: None,
            count: Some(count),
        };
        let _ = tx.try_send(event("live", &body));
    }
}

fn on_site(state: &AppState, site: &str, plan_id: &str) -> bool {
    state.views.plan(plan_id).is_some_and(|v| v.record.request.site == site)
}

#[cfg(test)]
mod tests {
    use super::*;
    use shift_proto::PoseView;

    fn robot(id: &str, site: &str, x: f64) -> RobotView {
        RobotView {
            robot: id.into(),
            alive: true,
            last_seen_ms: 1,
            pose: Some(PoseView {
                x,
                y: 0.0,
                yaw: 0.0,
                stamp_ns: 0,
            }),
            plan_id: None,
            driven_fraction: None,
            driven_m: None,
            last_correction: None,
            site: Some(site.into()),
            sensors: None,
        }
    }

    #[test]
    fn only_the_sites_robots_that_moved_are_sent_again() {
        let mut sent = HashMap::new();
        let first = changed_robots(
            "a",
            vec![robot("r1", "a", 0.0), robot("r2", "a", 0.0), robot("r3", "b", 0.0)],
            &mut sent,
        );
        assert_eq!(first.iter().map(|r| r.robot.as_str()).collect::<Vec<_>>(), ["r1", "r2"]);
        let again = changed_robots("a", vec![robot("r1", "a", 0.0), robot("r2", "a", 1.0)], &mut sent);
        assert_eq!(again.iter().map(|r| r.robot.as_str()).collect::<Vec<_>>(), ["r2"]);
        assert!(changed_robots("a", vec![robot("r2", "a", 1.0)], &mut sent).is_empty());
    }
}
