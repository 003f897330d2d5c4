//! `shiftd serve`: open the store, restore the engine, serve the API, shut down gracefully.
//!
//! [`run`] takes a bound listener and a shutdown future (mini-redis style) so tests bind 127.0.0.1:0 and stop
//! the server when they like. Shutdown order: stop accepting and end event streams; refuse new plans; give
//! running jobs `shutdown_grace_s` to finish; interrupt the rest (they stay queued in the store and the next
//! start computes them); stop the engine thread.

use std::future::Future;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::err;
use crate::error::{Context, Result};
use metrics_exporter_prometheus::{Matcher, PrometheusBuilder, PrometheusHandle};
use shift_engine::sensors::SensorHub;
use shift_engine::{Engine, Event, LiveMaps, LoadedSite, MapSource, SiteRecord};
use tokio::net::TcpListener;
use tokio::sync::broadcast;
use tokio_util::sync::CancellationToken;

use crate::clock::SharedClock;
use crate::config::Config;
use crate::engine_loop::handle::{EngineHandle, Msg};
use crate::engine_loop::{self, LoopParts};
use crate::fleet::{self, Fleet, FleetParts};
use crate::http::serve::{ConnLimits, serve};
use crate::http::{AppState, BodyLimits, router};
use crate::pools::Pools;
use crate::record::Recording;
use crate::store::Store;
use crate::views::Views;

pub(crate) const DEMO_YAML: &str = include_str!("../../../tests/fixtures/four-rooms-obstacles/map.yaml");
pub(crate) const DEMO_IMAGE: &[u8] = include_bytes!("../../../tests/fixtures/four-rooms-obstacles/map.pgm");

/// The process-wide Prometheus recorder (the `metrics` facade has one global recorder; servers started
/// in one process, as tests do, share it).
pub fn prometheus() -> Result<PrometheusHandle> {
    // A mutex, not a OnceLock check-then-set: two servers starting at once must not both install.
    static HANDLE: Mutex<Option<PrometheusHandle>> = Mutex::new(None);
    let mut slot = HANDLE.lock().map_err(|_| err!("prometheus handle lock poisoned"))?;
    if let Some(h) = slot.as_ref() {
        return Ok(h.clone());
    }
    let latency = [
        0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0, 60.0,
    ];
    // Ingest and engine-loop latencies are milliseconds: finer buckets, so p50/p99 can be read off them.
    let ingest = [
        0.0001, 0.00025, 0.0005, 0.00075, 0.001, 0.0015, 0.002, 0.003, 0.004, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.03,
        0.05, 0.075, 0.1, 0.15, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
    ];
    let handle = PrometheusBuilder::new()
        .set_buckets(&latency)
        .map_err(|e| err!("prometheus buckets: {e}"))?
        .set_buckets_for_metric(Matcher::Prefix("shift_ingest_".into()), &ingest)
        .map_err(|e| err!("prometheus ingest buckets: {e}"))?
        .set_buckets_for_metric(Matcher::Prefix("shift_engine_".into()), &ingest)
        .map_err(|e| err!("prometheus engine buckets: {e}"))?
        .install_recorder()
        .map_err(|e| err!("prometheus recorder: {e}"))?;
    *slot = Some(handle.clone());
    let upkept = handle.clone();
    if let Err(e) = spawn_upkeep(METRICS_UPKEEP, move || upkept.run_upkeep()) {
        tracing::warn!("no metrics upkeep thread ({e}): histogram samples wait for a scrape of /metrics");
    }
    Ok(handle)
}

/// Histogram samples wait in the recorder until something folds them into their buckets: a scrape of
/// `GET /metrics`, or an upkeep pass. `install_recorder` starts no upkeep of its own, so a daemon nobody
/// scraped kept every sample (about 16 bytes each: three per ingested scan or cloud, one per path check,
/// plan and HTTP request; issue 22). A pass every few seconds keeps that buffer small.
const METRICS_UPKEEP: Duration = Duration::from_secs(5);

/// Calls `upkeep` every `every` on a named thread, for the rest of the process.
fn spawn_upkeep(every: Duration, upkeep: impl Fn() + Send + 'static) -> std::io::Result<()> {
    std::thread::Builder::new()
        .name("metrics-upkeep".into())
        .spawn(move || {
            loop {
                std::thread::sleep(every);
                upkeep();
            }
        })
        .map(drop)
}

/// Serves until `shutdown` completes, then drains as described in the module docs.
pub async fn run(
    config: Config,
    listener: TcpListener,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> Result<()> {
    run_with_clock(config, listener, shutdown, crate::clock::system()).await
}

/// [`run`] on a given clock.
pub async fn run_with_clock(
    config: Config,
    listener: TcpListener,
    shutdown: impl Future<Output = ()> + Send + 'static,
    clock: SharedClock,
) -> Result<()> {
    config.http.validate()?;
    config.store.validate()?;
    let (auth_token, token_source) =
        crate::http::token::resolve(&config.http.auth_token, &config.http.auth_token_file, &|k| {
            std::env::var(k).ok()
        })?;
    let prometheus = prometheus()?;
    let store = Arc::new(Store::open_with_cache(
        &config.store.data_dir,
        config.store.cache_mb.saturating_mul(1 << 20),
    )?);
    let views = Arc::new(Views::default());
    let (events, _) = broadcast::channel(1024);
    let (mission_events, _) = broadcast::channel(256);
    let engine_config = config.engine_config();
    let engine = Engine::new(engine_config.clone());
    let zenoh = if config.zenoh.enabled {
        Some(fleet::open(&config.zenoh).await?)
    } else {
        None
    };
    let live = Arc::new(LiveMaps::default());
    let sensors = Arc::new(std::sync::Mutex::new(SensorHub::new(config.zenoh.sensor_params())));
    let recording = Recording::start(
        &config,
        &engine_config,
        zenoh.as_ref().map(|z| (&z.session, &z.keys)),
        live.clone(),
        &clock,
    )
    .await?;
    let (engine, engine_thread) = engine_loop::spawn(
        engine,
        LoopParts {
            store: store.clone(),
            views: views.clone(),
            events: events.clone(),
            mission_events: mission_events.clone(),
            publisher: zenoh.as_ref().map(|z| z.publisher.clone()),
            live: live.clone(),
            overlay: config.jobs.live_overlay,
            sensors: sensors.clone(),
            pools: Pools::new(config.jobs.effective_workers()).context("starting the plan and check threads")?,
            recorder: recording.as_ref().map(Recording::recorder),
            clock: clock.clone(),
        },
    )
    .context("starting the engine loop")?;
    restore(&config, &store, &views, &engine, &clock).await?;
    let fleet = match zenoh {
        Some(session) => Some(
            Fleet::start(
                &config.zenoh,
                session,
                FleetParts {
                    engine: engine.clone(),
                    views: views.clone(),
                    live: live.clone(),
                    sensors: sensors.clone(),
                    clock: clock.clone(),
                },
            )
            .await
            .context("starting the Zenoh fleet bridge")?,
        ),
        None => None,
    };

    let token = CancellationToken::new();
    let state = AppState {
        engine: engine.clone(),
        views,
        live,
        sensors,
        clock,
        events,
        mission_events,
        shutdown: token.clone(),
        prometheus,
        auth_token: Arc::new(auth_token),
        body_limits: BodyLimits {
            map_bytes: config.http.max_body_bytes,
            request_bytes: config.http.max_request_bytes,
        },
        request_timeout: Duration::from_secs(config.http.request_timeout_s.max(1)),
        sse_keep_alive: Duration::from_secs(config.http.sse_keep_alive_s.max(1)),
        retry_after_s: config.http.retry_after_s,
    };
    let addr = listener.local_addr()?;
    tracing::info!(%addr, data_dir = %config.store.data_dir.display(), auth = ?token_source, "shiftd serving");
    let stop = token.clone();
    tokio::spawn(async move {
        shutdown.await;
        stop.cancel();
    });
    let limits = ConnLimits {
        header_read_timeout: Duration::from_secs(config.http.header_read_timeout_s.max(1)),
        max_connections: config.http.max_connections.max(1),
        write_stall: Duration::from_secs(config.http.write_stall_s.max(1)),
        drain: Duration::from_secs(config.http.request_timeout_s.max(1)),
    };
    serve(listener, router(state), limits, token).await;

    if let Some(f) = fleet {
        f.shutdown().await;
    }
    tracing::info!("draining plan jobs");
    engine.call(Event::Shutdown).await.ok();
    let mut running = engine.running();
    let grace = Duration::from_secs(config.jobs.shutdown_grace_s);
    let idle = |n: &usize| *n == 0;
    if tokio::time::timeout(grace, running.wait_for(idle)).await.is_err() {
        tracing::warn!("grace period over: interrupting running plans (they stay queued)");
        engine.tell(Msg::InterruptJobs).await.ok();
        // The planner checks its flag between stages and regions; this bounds a pathological stage.
        let _ = tokio::time::timeout(Duration::from_secs(60), running.wait_for(idle)).await;
    }
    engine.tell(Msg::Stop).await.ok();
    tokio::task::spawn_blocking(move || engine_thread.join()).await.ok();
    if let Some(r) = recording {
        r.finish().await.context("finishing the MCAP recording")?;
    }
    tracing::info!("shiftd stopped");
    Ok(())
}

/// Feeds the engine what the store holds, plus the demo site when configured and missing.
async fn restore(
    config: &Config,
    store: &Arc<Store>,
    views: &Arc<Views>,
    engine: &EngineHandle,
    clock: &SharedClock,
) -> Result<()> {
    let s = store.clone();
    let (sites, plans, active, missions, coverage) = tokio::task::spawn_blocking(move || -> Result<_> {
        let mut sites = Vec::new();
        for rec in s.sites()? {
            let site = rec.site.clone();
            match LoadedSite::parse(rec) {
                Ok(loaded) => sites.push(loaded),
                Err(e) => tracing::error!(site, "stored map no longer parses, skipped: {e}"),
            }
        }
        let plans = s.plans()?;
        // The plans robots were driving, at their last committed version.
        let mut active = Vec::new();
        for p in plans.iter().filter(|p| p.status == shift_proto::PlanStatus::Active) {
            if let Some(doc) = s.current(&p.plan_id)? {
                active.push(Arc::new(doc));
            }
        }
        Ok((sites, plans, active, s.missions()?, s.coverage()?))
    })
    .await
    .map_err(|e| crate::err!("restoring from the store: {e}"))??;
    let has_demo = sites.iter().any(|s| s.record.site == config.demo.site);
    let finished: Vec<String> = plans
        .iter()
        .filter(|p| p.version > 0)
        .map(|p| p.plan_id.clone())
        .collect();
    tracing::info!(
        sites = sites.len(),
        plans = plans.len(),
        driven = active.len(),
        missions = missions.len(),
        rasters = coverage.len(),
        "restoring from the store"
    );
    engine
        .call(Event::Restore {
            sites,
            plans,
            active,
            missions,
            coverage,
        })
        .await?;
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
        let record = SiteRecord {
            site: config.demo.site.clone(),
            source,
            updated_ms: clock.now_ms(),
        };
        let site = LoadedSite::parse(record).context("the bundled demo map")?;
        engine.call(Event::MapUploaded { site }).await?;
        tracing::info!(
            site = config.demo.site,
            "demo site loaded (four rooms with obstacles, start 0.5,0.5)"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::time::{Duration, Instant};

    use metrics_exporter_prometheus::PrometheusBuilder;

    use super::spawn_upkeep;

    #[test]
    fn upkeep_runs_again_and_again() {
        let passes = Arc::new(AtomicUsize::new(0));
        let counted = passes.clone();
        spawn_upkeep(Duration::from_millis(20), move || {
            counted.fetch_add(1, Ordering::Relaxed);
        })
        .expect("thread");
        let deadline = Instant::now() + Duration::from_secs(10);
        while passes.load(Ordering::Relaxed) < 3 {
            assert!(Instant::now() < deadline, "fewer than 3 upkeep passes in 10 s");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// What the upkeep does to samples nobody scraped: folds them into the buckets, none lost.
    #[test]
    fn upkeep_keeps_every_histogram_sample() {
        let recorder = PrometheusBuilder::new()
            .set_buckets(&[1.0])
            .expect("buckets")
            .build_recorder();
        let handle = recorder.handle();
        metrics::with_local_recorder(&recorder, || {
            for _ in 0..1000 {
                metrics::histogram!("upkept_seconds").record(0.5);
            }
        });
        handle.run_upkeep();
        metrics::with_local_recorder(&recorder, || metrics::histogram!("upkept_seconds").record(2.0));
        handle.run_upkeep();
        let text = handle.render();
        assert!(text.contains("upkept_seconds_count 1001"), "{text}");
        assert!(text.contains("upkept_seconds_bucket{le=\"1\"} 1000"), "{text}");
    }
}
