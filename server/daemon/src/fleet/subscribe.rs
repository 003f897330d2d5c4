//! The robot data subscriptions of one fleet, laid out by its key mapping (`zenoh.mapping`: native DESIGN §5.4
//! keys, zenoh-bridge-ros2dds or rmw_zenoh): one subscriber per key expression, every sample routed by the
//! stream its key names — odometry, clouds and scans to the ingest queues (odometry goes on to the engine loop
//! from there, once the sensor pipeline took it into the robot's pose history). rmw_zenoh's attachment (sequence number, source time, gid) is neither required nor used.
//!
//! Robots without a SHIFT liveliness token (the ROS 2 mappings) are tracked by [`Presence`]: alive from their
//! first message, lost after `zenoh.robot_timeout_s` without one.

use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::err;
use crate::error::Result;
use shift_engine::sensors::FramedPose;
use shift_engine::{Event, Pose2};
use shift_proto::keys::{KeySpace, Ros2Mapping, Stream};
use shift_proto::ros::odometry::decode_odom_payload;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use zenoh::sample::Sample;

use super::ingest::{Ingest, RawCloud};
use super::presence::Presence;
use super::stopping::next_or_stop;
use crate::engine_loop::handle::{EngineHandle, Msg};

/// Where a fleet's samples go.
#[derive(Clone)]
struct Route {
    keys: Arc<KeySpace>,
    mapping: Ros2Mapping,
    engine: EngineHandle,
    ingest: Arc<Ingest>,
    presence: Option<Arc<Presence>>,
}

impl Route {
    /// One received sample on a data subscription.
    fn sample(&self, sample: &Sample) {
        let Some((robot, stream)) = self.mapping.classify(&self.keys, sample.key_expr().as_str()) else {
            return;
        };
        if let Some(p) = &self.presence
            && p.seen(&robot, Instant::now())
        {
            let alive = Event::RobotLiveliness {
                robot: robot.clone(),
                alive: true,
            };
            if self.engine.try_tell(Msg::event(alive)).is_ok() {
                tracing::info!(robot, "robot heard on its topics: alive");
                p.reported_alive(&robot);
            }
        }
        match stream {
            Stream::Odom => self.odom(robot, sample),
            Stream::Cloud | Stream::Scan => self.ingest.push(RawCloud {
                robot,
                stream,
                bytes: sample.payload().to_bytes().into_owned(),
                received: Instant::now(),
            }),
            Stream::Alive => {}
        }
    }

    /// Odometry → the ingest (the sensor pipeline's pose history, then the engine loop).
    fn odom(&self, robot: String, sample: &Sample) {
        let encoding = sample.encoding().to_string();
        match decode_odom_payload(&sample.payload().to_bytes(), Some(&encoding)) {
            Ok(p) => {
                let pose = Pose2 {
                    x: p.x,
                    y: p.y,
                    yaw: p.yaw,
                    stamp_ns: p.stamp_ns,
                };
                self.ingest.push_odom(
                    robot,
                    FramedPose {
                        pose,
                        frame: p.frame_id,
                    },
                );
            }
            Err(e) => {
                metrics::counter!("shift_odom_dropped_total", "reason" => "malformed").increment(1);
                tracing::debug!(robot, "odometry dropped: {e}");
            }
        }
    }
}

/// Declares the data subscriptions of `mapping` and, for mappings without liveliness tokens, the presence
/// sweeper; returns their tasks (they end when `stop` is cancelled).
pub async fn data_subscriptions(
    session: &zenoh::Session,
    keys: Arc<KeySpace>,
    mapping: &Ros2Mapping,
    robot_timeout: Duration,
    engine: EngineHandle,
    ingest: Arc<Ingest>,
    stop: &CancellationToken,
) -> Result<Vec<JoinHandle<()>>> {
    mapping.validate().map_err(|e| err!("zenoh.mapping: {e}"))?;
    let presence = (!mapping.has_liveliness()).then(|| Arc::new(Presence::new(robot_timeout)));
    let route = Route {
        keys: keys.clone(),
        mapping: mapping.clone(),
        engine: engine.clone(),
        ingest,
        presence: presence.clone(),
    };
    let mut tasks = Vec::new();
    for (ke, stream) in mapping.subscriptions(&keys) {
        let sub = session
            .declare_subscriber(ke.as_str())
            .await
            .map_err(|e| err!("zenoh subscriber on {ke}: {e}"))?;
        tracing::info!(key = %ke, ?stream, "subscribed");
        let (route, s) = (route.clone(), stop.clone());
        tasks.push(tokio::spawn(async move {
            while let Some(sample) = next_or_stop(&s, sub.recv_async()).await {
                route.sample(&sample);
            }
        }));
    }
    if let Some(presence) = presence {
        let s = stop.clone();
        tasks.push(tokio::spawn(async move {
            let mut tick = tokio::time::interval(presence.sweep_every());
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            loop {
                tokio::select! {
                    () = s.cancelled() => break,
                    _ = tick.tick() => {}
                }
                for robot in presence.expire(Instant::now()) {
                    tracing::info!(robot, "robot silent for robot_timeout_s: lost");
                    let _ = engine
                        .tell(Msg::event(Event::RobotLiveliness { robot, alive: false }))
                        .await;
                }
            }
        }));
    }
    Ok(tasks)
}
