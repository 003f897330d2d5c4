//! The fleet over Zenoh (DESIGN §5.4): one session per daemon; robot data on the keys of the fleet's mapping
//! (`subscribe`: native, zenoh-bridge-ros2dds or rmw_zenoh) → the ingest thread (`ingest`: the engine's sensor
//! pipeline, then live site maps and the engine loop); liveliness tokens (native) or heard topics (ROS 2,
//! `presence`) → the engine loop; plans, corrections and plan status out (`publish`); queryables serving each
//! robot's current plan and each plan's current status to whoever (re)connects.

pub mod config;
pub mod ingest;
pub mod presence;
pub mod publish;
pub mod stopping;
pub mod subscribe;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use shift_engine::sensors::SensorHub;
use shift_engine::{Event, LiveMapParams, LiveMaps};
use shift_proto::keys::{KeySpace, Stream};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use zenoh::bytes::Encoding;
use zenoh::sample::SampleKind;

use self::config::ZenohConfig;
use self::ingest::Ingest;
use self::publish::Publisher;
use self::stopping::next_or_stop;
use crate::clock::SharedClock;
use crate::engine_loop::handle::{EngineHandle, Msg};
use crate::error::{DaemonError, Result};
use crate::views::Views;

/// The running fleet bridge.
pub struct Fleet {
    session: zenoh::Session,
    ingest: Arc<Ingest>,
    ingest_thread: Option<std::thread::JoinHandle<()>>,
    tasks: Vec<JoinHandle<()>>,
    stop: CancellationToken,
}

/// An open session, its keys and the publisher over it (opened before the engine loop starts, so it can
/// publish).
pub struct Session {
    /// The session.
    pub session: zenoh::Session,
    /// The fleet's key space.
    pub keys: Arc<KeySpace>,
    /// Plans, corrections and status out.
    pub publisher: Publisher,
    publisher_task: JoinHandle<()>,
}

/// Opens the session and starts the publisher.
pub async fn open(config: &ZenohConfig) -> Result<Session> {
    let keys = Arc::new(
        KeySpace::new(&config.prefix, &config.fleet).map_err(|e| DaemonError::config(format!("zenoh keys: {e}")))?,
    );
    let session = zenoh::open(config.to_zenoh()?)
        .await
        .map_err(|e| DaemonError::Zenoh(format!("opening the session: {e}")))?;
    let (publisher, publisher_task) = Publisher::start(session.clone(), keys.clone());
    Ok(Session {
        session,
        keys,
        publisher,
        publisher_task,
    })
}

/// What the fleet bridge feeds and reads.
pub struct FleetParts {
    /// The engine loop.
    pub engine: EngineHandle,
    /// The read model (site maps for the ingest, plans and status for the queryables).
    pub views: Arc<Views>,
    /// Every site's live map.
    pub live: Arc<LiveMaps>,
    /// The sensor pipeline (shared with the engine loop, which routes robots).
    pub sensors: Arc<Mutex<SensorHub>>,
    /// The time.
    pub clock: SharedClock,
}

impl Fleet {
    /// Declares the subscribers, the liveliness watcher and the queryables, and starts the ingest thread.
    pub async fn start(config: &ZenohConfig, session: Session, parts: FleetParts) -> Result<Self> {
        let Session {
            session,
            keys,
            publisher: _,
            publisher_task,
        } = session;
        let FleetParts {
            engine,
            views,
            live,
            sensors,
            clock,
        } = parts;
        let params = LiveMapParams {
            voxel_m: config.voxel_m as f32,
            z_min_m: config.obstacle_z_min_m as f32,
            z_max_m: config.obstacle_z_max_m as f32,
            max_points: config.max_points,
            horizon_ms: config.horizon_s.saturating_mul(1000),
            known_tolerance_m: config.known_tolerance_m as f32,
            clear_margin_m: config.clear_margin_m as f32,
        };
        let ingest = Arc::new(Ingest::new(
            config.cloud_queue,
            params,
            sensors,
            views.clone(),
            live,
            Some(engine.clone()),
            clock,
        ));
        let worker = ingest.clone();
        let ingest_thread = std::thread::Builder::new()
            .name("ingest".into())
            .spawn(move || worker.run())?;
        let stop = CancellationToken::new();
        let mut tasks = vec![publisher_task];
        let z = |e: zenoh::Error| DaemonError::Zenoh(e.to_string());

        // Odometry, clouds and scans on the keys of the fleet's mapping (native, bridge or rmw_zenoh).
        tasks.extend(
            subscribe::data_subscriptions(
                &session,
                keys.clone(),
                &config.mapping,
                Duration::from_secs(config.robot_timeout_s.max(1)),
                engine.clone(),
                ingest.clone(),
                &stop,
            )
            .await?,
        );

        // Liveliness: tokens present now (history) and every change after.
        let sub = session
            .liveliness()
            .declare_subscriber(keys.all_alive())
            .history(true)
            .await
            .map_err(z)?;
        let (k, e, s) = (keys.clone(), engine.clone(), stop.clone());
        tasks.push(tokio::spawn(async move {
            while let Some(sample) = next_or_stop(&s, sub.recv_async()).await {
                let Some((robot, Stream::Alive)) = k.robot_of(sample.key_expr().as_str()) else {
                    continue;
                };
                let alive = sample.kind() == SampleKind::Put;
                tracing::info!(robot, alive, "robot liveliness");
                let _ = e.tell(Msg::event(Event::RobotLiveliness { robot, alive })).await;
            }
        }));

        // Each robot's current plan, for robots that (re)connect.
        let queryable = session.declare_queryable(keys.all_plan()).await.map_err(z)?;
        let (k, v, s) = (keys.clone(), views.clone(), stop.clone());
        tasks.push(tokio::spawn(async move {
            while let Some(query) = next_or_stop(&s, queryable.recv_async()).await {
                let Some(robot) = k.robot_of_plan(query.key_expr().as_str()) else {
                    continue;
                };
                let Some(doc) = v.robot_plan(&robot) else { continue };
                let Ok(json) = serde_json::to_vec(&*doc) else { continue };
                let Ok(plan_key) = k.plan(&robot) else { continue };
                if let Err(e) = query.reply(plan_key, json).encoding(Encoding::APPLICATION_JSON).await {
                    tracing::debug!(robot, "plan query reply: {e}");
                }
            }
        }));

        // Each plan's current status (`…/plans/*/status`; a wildcard query gets every plan's).
        let queryable = session.declare_queryable(keys.all_plan_status()).await.map_err(z)?;
        let (k, v, s) = (keys.clone(), views, stop.clone());
        tasks.push(tokio::spawn(async move {
            while let Some(query) = next_or_stop(&s, queryable.recv_async()).await {
                let asked = query.key_expr().clone();
                for status in v.statuses() {
                    let Ok(key) = k.plan_status(&status.plan_id) else {
                        continue;
                    };
                    let Ok(ke) = zenoh::key_expr::KeyExpr::try_from(key.as_str()) else {
                        continue;
                    };
                    if !asked.intersects(&ke) {
                        continue;
                    }
                    let Ok(json) = serde_json::to_vec(&status) else {
                        continue;
                    };
                    if let Err(e) = query.reply(key, json).encoding(Encoding::APPLICATION_JSON).await {
                        tracing::debug!("status query reply: {e}");
                    }
                }
            }
        }));

        Ok(Self {
            session,
            ingest,
            ingest_thread: Some(ingest_thread),
            tasks,
            stop,
        })
    }

    /// Stops the tasks and the ingest thread and closes the session.
    pub async fn shutdown(mut self) {
        self.stop.cancel();
        for t in self.tasks.drain(..) {
            if !t.is_finished() {
                t.abort();
            }
            let _ = t.await;
        }
        self.ingest.stop();
        if let Some(t) = self.ingest_thread.take() {
            let _ = tokio::task::spawn_blocking(move || t.join()).await;
        }
        if let Err(e) = self.session.close().await {
            tracing::warn!("closing the zenoh session: {e}");
        }
    }
}
