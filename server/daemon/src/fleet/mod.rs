//! The fleet over Zenoh (DESIGN §5.4): one session per daemon; robot data on the keys of the fleet's mapping
//! (`subscribe`: native, zenoh-bridge-ros2dds or rmw_zenoh): odometry → engine, clouds and scans → ingest
//! thread → live site map; liveliness tokens (native) or heard topics (ROS 2, `presence`) → robot registry, plans out (JSON on the plan key, nav_msgs/Path CDR on
//! the plan_path key) and a queryable serving each robot's current plan to robots that (re)connect.

pub mod config;
pub mod ingest;
pub mod live;
pub mod presence;
pub mod scan;
pub mod subscribe;

use std::sync::Arc;
use std::time::Duration;

use anyhow::{Result, anyhow};
use shift_engine::{Event, LiveMapParams};
use shift_proto::keys::{KeySpace, Stream};
use shift_proto::ros::path::encode_path;
use shift_proto::ros::{Header, Time};
use shift_proto::{CorrectionDoc, PlanDocument};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use zenoh::bytes::Encoding;
use zenoh::qos::CongestionControl;
use zenoh::sample::SampleKind;

use self::config::ZenohConfig;
use self::ingest::{Ingest, IngestSettings};
use self::live::LiveMaps;
use self::scan::SensorOffset;
use crate::brain::{BrainHandle, Msg};
use crate::views::Views;

/// Publishes plans to robots; cheap to clone, usable from the engine thread.
#[derive(Clone)]
pub struct PlanPublisher {
    session: zenoh::Session,
    keys: Arc<KeySpace>,
    runtime: tokio::runtime::Handle,
}

impl std::fmt::Debug for PlanPublisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PlanPublisher")
            .field("keys", &self.keys)
            .finish_non_exhaustive()
    }
}

/// Plan document → nav_msgs/Path poses `(x, y, yaw)`, yaw along the path.
fn path_poses(doc: &PlanDocument) -> Vec<(f64, f64, f64)> {
    let w = &doc.waypoints;
    (0..w.len())
        .map(|i| {
            let (a, b) = if i + 1 < w.len() {
                (i, i + 1)
            } else {
                (i.saturating_sub(1), i)
            };
            let yaw = (w[b].y - w[a].y).atan2(w[b].x - w[a].x);
            (w[i].x, w[i].y, if yaw.is_finite() { yaw } else { 0.0 })
        })
        .collect()
}

impl PlanPublisher {
    /// Sends `doc` to `robot` (fire and forget: a robot that misses it fetches it from the queryable).
    pub fn publish(&self, robot: &str, doc: Arc<PlanDocument>) {
        let (Ok(plan_key), Ok(path_key)) = (self.keys.plan(robot), self.keys.plan_path(robot)) else {
            tracing::warn!(robot, "no valid plan key for this robot name");
            return;
        };
        let session = self.session.clone();
        let robot = robot.to_owned();
        self.runtime.spawn(async move {
            let json = match serde_json::to_vec(&*doc) {
                Ok(j) => j,
                Err(e) => return tracing::error!("plan JSON: {e}"),
            };
            // Block, not drop, when the link is congested: a plan is worth the wait (this task is the one
            // waiting, never the engine).
            let put = session.put(&plan_key, json).encoding(Encoding::APPLICATION_JSON);
            if let Err(e) = put.congestion_control(CongestionControl::Block).await {
                tracing::warn!(robot, "publishing the plan: {e}");
            }
            let header = Header {
                stamp: Time { sec: 0, nanosec: 0 },
                frame_id: doc.frame.clone(),
            };
            let cdr = encode_path(&header, &path_poses(&doc));
            let put = session.put(&path_key, cdr).encoding(Encoding::APPLICATION_CDR);
            if let Err(e) = put.congestion_control(CongestionControl::Block).await {
                tracing::warn!(robot, "publishing the ROS path: {e}");
            }
        });
    }
}

impl PlanPublisher {
    /// Sends a correction to its robot's corrections key (JSON). A robot that misses it sees a version gap
    /// at the next one and fetches the current plan from the queryable.
    pub fn publish_correction(&self, correction: Arc<CorrectionDoc>) {
        let Ok(key) = self.keys.corrections(&correction.robot) else {
            tracing::warn!(robot = correction.robot, "no valid corrections key for this robot name");
            return;
        };
        let session = self.session.clone();
        self.runtime.spawn(async move {
            let json = match serde_json::to_vec(&*correction) {
                Ok(j) => j,
                Err(e) => return tracing::error!("correction JSON: {e}"),
            };
            if let Err(e) = session.put(&key, json).encoding(Encoding::APPLICATION_JSON).await {
                tracing::warn!(robot = correction.robot, "publishing a correction: {e}");
            }
        });
    }
}

/// The next item of a zenoh receiver, or `None` once `stop` is cancelled or the receiver closed.
async fn next_or_stop<T, E>(
    stop: &CancellationToken,
    recv: impl std::future::Future<Output = Result<T, E>>,
) -> Option<T> {
    tokio::select! {
        () = stop.cancelled() => None,
        r = recv => r.ok(),
    }
}

/// The running fleet bridge.
pub struct Fleet {
    session: zenoh::Session,
    ingest: Arc<Ingest>,
    ingest_thread: Option<std::thread::JoinHandle<()>>,
    tasks: Vec<JoinHandle<()>>,
    stop: CancellationToken,
}

/// Opens the session (before the engine thread starts, so it can publish).
pub async fn open(config: &ZenohConfig) -> Result<(zenoh::Session, Arc<KeySpace>)> {
    let keys = Arc::new(KeySpace::new(&config.prefix, &config.fleet).map_err(|e| anyhow!("zenoh keys: {e}"))?);
    let session = zenoh::open(config.to_zenoh()?)
        .await
        .map_err(|e| anyhow!("opening the zenoh session: {e}"))?;
    Ok((session, keys))
}

/// A publisher over an open session.
pub fn publisher(session: &zenoh::Session, keys: &Arc<KeySpace>) -> PlanPublisher {
    PlanPublisher {
        session: session.clone(),
        keys: keys.clone(),
        runtime: tokio::runtime::Handle::current(),
    }
}

impl Fleet {
    /// Declares the subscribers, the liveliness watcher and the plan queryable, and starts the ingest thread.
    pub async fn start(
        config: &ZenohConfig,
        session: zenoh::Session,
        keys: Arc<KeySpace>,
        brain: BrainHandle,
        views: Arc<Views>,
        live: Arc<LiveMaps>,
    ) -> Result<Self> {
        let params = LiveMapParams {
            voxel_m: config.voxel_m as f32,
            z_min_m: config.obstacle_z_min_m as f32,
            z_max_m: config.obstacle_z_max_m as f32,
            max_points: config.max_points,
            horizon_ms: config.horizon_s.saturating_mul(1000),
            known_tolerance_m: config.known_tolerance_m as f32,
        };
        let settings = IngestSettings {
            capacity: config.cloud_queue,
            site: config.site.clone(),
            map_frame: config.map_frame.clone(),
            params,
            history: config.pose_history(),
            scan_offset: SensorOffset {
                x_m: config.scan_offset_x_m,
                y_m: config.scan_offset_y_m,
                yaw_rad: config.scan_offset_yaw_rad,
            },
        };
        let ingest = Arc::new(Ingest::new(settings, views.clone(), live, Some(brain.clone())));
        let worker = ingest.clone();
        let ingest_thread = std::thread::Builder::new()
            .name("ingest".into())
            .spawn(move || worker.run())?;
        let stop = CancellationToken::new();
        let mut tasks = Vec::new();
        let z = |e: zenoh::Error| anyhow!("zenoh: {e}");

        // Odometry, clouds and scans on the keys of the fleet's mapping (native, bridge or rmw_zenoh).
        tasks.extend(
            subscribe::data_subscriptions(
                &session,
                keys.clone(),
                &config.mapping,
                Duration::from_secs(config.robot_timeout_s.max(1)),
                brain.clone(),
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
        let (k, b, s) = (keys.clone(), brain.clone(), stop.clone());
        tasks.push(tokio::spawn(async move {
            loop {
                let Some(sample) = next_or_stop(&s, sub.recv_async()).await else {
                    break;
                };
                let Some((robot, Stream::Alive)) = k.robot_of(sample.key_expr().as_str()) else {
                    continue;
                };
                let alive = sample.kind() == SampleKind::Put;
                tracing::info!(robot, alive, "robot liveliness");
                let _ = b.tell(Msg::event(Event::RobotLiveliness { robot, alive })).await;
            }
        }));

        // Each robot's current plan, for robots that (re)connect.
        let queryable = session.declare_queryable(keys.all_plan()).await.map_err(z)?;
        let (k, v, s) = (keys.clone(), views, stop.clone());
        tasks.push(tokio::spawn(async move {
            loop {
                let Some(query) = next_or_stop(&s, queryable.recv_async()).await else {
                    break;
                };
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
