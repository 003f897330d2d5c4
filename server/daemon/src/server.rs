//! `shiftd serve`: open the store, restore the engine, serve the API, shut down gracefully.
//!
//! [`run`] takes a bound listener and a shutdown future (mini-redis style) so tests bind 127.0.0.1:0 and stop
//! the server when they like. Shutdown order: stop accepting and end event streams; refuse new plans; give
//! running jobs `shutdown_grace_s` to finish; interrupt the rest (they stay queued in the store and the next
//! start computes them); stop the engine thread.

use std::future::Future;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{Context, Result, anyhow};
use metrics_exporter_prometheus::{Matcher, PrometheusBuilder, PrometheusHandle};
use shift_engine::{Engine, EngineConfig, Event, MapSource, SiteRecord};
use tokio::net::TcpListener;
use tokio::sync::broadcast;
use tokio_util::sync::CancellationToken;

use crate::brain::{self, BrainHandle, Msg, now_ms};
use crate::config::Config;
use crate::fleet::live::LiveMaps;
use crate::fleet::{self, Fleet};
use crate::http::{AppState, router};
use crate::record::Recording;
use crate::store::Store;
use crate::views::Views;

const DEMO_YAML: &str = include_str!("../../../tests/fixtures/four-rooms-obstacles/map.yaml");
const DEMO_IMAGE: &[u8] = include_bytes!("../../../tests/fixtures/four-rooms-obstacles/map.pgm");

/// The process-wide Prometheus recorder (the `metrics` facade has one global recorder; servers started
/// in one process, as tests do, share it).
pub fn prometheus() -> Result<PrometheusHandle> {
    // A mutex, not a OnceLock check-then-set: two servers starting at once must not both install.
    static HANDLE: Mutex<Option<PrometheusHandle>> = Mutex::new(None);
    let mut slot = HANDLE.lock().map_err(|_| anyhow!("prometheus handle lock poisoned"))?;
    if let Some(h) = slot.as_ref() {
        return Ok(h.clone());
    }
    let latency = [
        0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0, 60.0,
    ];
    // Ingest latencies are milliseconds: finer buckets, so p50/p99 can be read off them.
    let ingest = [
        0.0001, 0.00025, 0.0005, 0.00075, 0.001, 0.0015, 0.002, 0.003, 0.004, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03,
        0.05, 0.075, 0.1, 0.15, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
    ];
    let handle = PrometheusBuilder::new()
        .set_buckets(&latency)
        .map_err(|e| anyhow!("prometheus buckets: {e}"))?
        .set_buckets_for_metric(Matcher::Prefix("shift_ingest_".into()), &ingest)
        .map_err(|e| anyhow!("prometheus ingest buckets: {e}"))?
        .install_recorder()
        .map_err(|e| anyhow!("prometheus recorder: {e}"))?;
    *slot = Some(handle.clone());
    Ok(handle)
}

/// Serves until `shutdown` completes, then drains as described in the module docs.
pub async fn run(
    config: Config,
    listener: TcpListener,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> Result<()> {
    let prometheus = prometheus()?;
    let store = Arc::new(Store::open(&config.store.data_dir)?);
    let views = Arc::new(Views::default());
    let (events, _) = broadcast::channel(1024);
    let engine = Engine::new(EngineConfig {
        workers: config.jobs.effective_workers(),
        queue_capacity: config.jobs.queue_capacity,
        watch: config.watch,
    });
    let zenoh = if config.zenoh.enabled {
        Some(fleet::open(&config.zenoh).await?)
    } else {
        None
    };
    let publisher = zenoh.as_ref().map(|(s, k)| fleet::publisher(s, k));
    let live = Arc::new(LiveMaps::default());
    let recording = Recording::start(&config, zenoh.as_ref().map(|(s, k)| (s, k)), live.clone()).await?;
    let (brain, engine_thread) = brain::spawn(
        engine,
        brain::BrainParts {
            store: store.clone(),
            views: views.clone(),
            events: events.clone(),
            publisher,
            live: live.clone(),
            overlay: config.jobs.live_overlay.then(|| live.clone()),
            runtime: tokio::runtime::Handle::current(),
            recorder: recording.as_ref().map(Recording::recorder),
        },
    )
    .context("starting the engine thread")?;
    restore(&config, &store, &views, &brain).await?;
    let fleet = match zenoh {
        Some((session, keys)) => Some(
            Fleet::start(&config.zenoh, session, keys, brain.clone(), views.clone(), live.clone())
                .await
                .context("starting the Zenoh fleet bridge")?,
        ),
        None => None,
    };

    let token = CancellationToken::new();
    let state = AppState {
        brain: brain.clone(),
        views,
        live,
        events,
        shutdown: token.clone(),
        prometheus,
        auth_token: Arc::from(config.http.auth_token.as_str()),
        max_body_bytes: config.http.max_body_bytes,
        request_timeout: Duration::from_secs(config.http.request_timeout_s.max(1)),
    };
    let addr = listener.local_addr()?;
    tracing::info!(%addr, data_dir = %config.store.data_dir.display(), "shiftd serving");
    let stop = token.clone();
    axum::serve(listener, router(state))
        .with_graceful_shutdown(async move {
            shutdown.await;
            stop.cancel();
        })
        .await
        .context("serving HTTP")?;

    if let Some(f) = fleet {
        f.shutdown().await;
    }
    tracing::info!("draining plan jobs");
    brain.call(Event::Shutdown).await.ok();
    let mut running = brain.running();
    let grace = Duration::from_secs(config.jobs.shutdown_grace_s);
    let idle = |n: &usize| *n == 0;
    if tokio::time::timeout(grace, running.wait_for(idle)).await.is_err() {
        tracing::warn!("grace period over: interrupting running plans (they stay queued)");
        brain.tell(Msg::InterruptJobs).await.ok();
        // The planner checks its flag between stages and regions; this bounds a pathological stage.
        let _ = tokio::time::timeout(Duration::from_secs(60), running.wait_for(idle)).await;
    }
    brain.tell(Msg::Stop).await.ok();
    tokio::task::spawn_blocking(move || engine_thread.join()).await.ok();
    if let Some(r) = recording {
        r.finish().await.context("finishing the MCAP recording")?;
    }
    tracing::info!("shiftd stopped");
    Ok(())
}

/// Feeds the engine what the store holds, plus the demo site when configured and missing.
async fn restore(config: &Config, store: &Arc<Store>, views: &Arc<Views>, brain: &BrainHandle) -> Result<()> {
    let s = store.clone();
    let (sites, plans) = tokio::task::spawn_blocking(move || -> Result<_> {
        let mut sites = Vec::new();
        for rec in s.sites()? {
            match rec.source.parse() {
                Ok(map) => sites.push((rec, map)),
                Err(e) => tracing::error!(site = rec.site, "stored map no longer parses, skipped: {e}"),
            }
        }
        Ok((sites, s.plans()?))
    })
    .await??;
    let has_demo = sites.iter().any(|(r, _)| r.site == config.demo.site);
    let finished: Vec<String> = plans
        .iter()
        .filter(|p| p.version > 0)
        .map(|p| p.plan_id.clone())
        .collect();
    tracing::info!(sites = sites.len(), plans = plans.len(), "restoring from the store");
    brain.call(Event::Restore { sites, plans }).await?;
    // Computed plans are served again from their stored documents, corrections applied.
    for id in finished {
        if let Some(doc) = store.current(&id)? {
            views.set_doc(&id, Arc::new(doc));
        }
    }
    if config.demo.enabled && !has_demo {
        let source = MapSource::Ros {
            yaml: DEMO_YAML.to_owned(),
            image: DEMO_IMAGE.to_vec(),
        };
        let map = source.parse().context("the bundled demo map")?;
        let record = SiteRecord {
            site: config.demo.site.clone(),
            source,
            updated_ms: now_ms(),
        };
        brain.call(Event::MapUploaded { record, map }).await?;
        tracing::info!(
            site = config.demo.site,
            "demo site loaded (four rooms with obstacles, start 0.5,0.5)"
        );
    }
    Ok(())
}
