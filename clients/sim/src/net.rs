//! Each robot as its own Zenoh participant: a session connected to the daemon's endpoint, a liveliness token,
//! odometry and scans published on the keys of the fleet's mapping, and its plan and corrections received through
//! [`RobotLink`] (a plan fetch when asked, e.g. on a version gap, and once at start as a restarting robot does).

use std::time::Duration;

use shift_client::robot::{RobotLink, RobotMessage, peer_config};
use shift_proto::keys::{KeySpace, Ros2Mapping, Stream};
use shift_proto::ros::{Header, LaserScan, Odometry, Time, encode_laser_scan, encode_odometry};
use tokio::sync::mpsc;
use zenoh::bytes::Encoding;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;

use crate::drive::DiffDrive;
use crate::error::SimError;
use crate::lidar::Lidar;

fn zerr(e: impl std::fmt::Display) -> SimError {
    SimError::Fleet(e.to_string())
}

/// How long a plan fetch waits for the daemon's answer.
const FETCH_TIMEOUT: Duration = Duration::from_secs(2);

/// A message for robot `index`.
pub type Inbox = mpsc::UnboundedSender<(usize, RobotMessage)>;

/// One robot's Zenoh side.
pub struct RobotNet {
    odom: Option<Publisher<'static>>,
    scan: Option<Publisher<'static>>,
    fetch: mpsc::UnboundedSender<()>,
    _token: Option<LivelinessToken>,
    session: zenoh::Session,
}

impl RobotNet {
    /// Opens robot `id`'s session to `endpoint`, announces it, and forwards what the fleet sends it to `inbox`
    /// as `(index, message)`.
    pub async fn connect(
        endpoint: &str,
        keys: &KeySpace,
        mapping: &Ros2Mapping,
        id: &str,
        index: usize,
        inbox: Inbox,
    ) -> Result<Self, SimError> {
        let session = zenoh::open(peer_config(endpoint).map_err(zerr)?).await.map_err(zerr)?;
        let token = if mapping.has_liveliness() {
            Some(
                session
                    .liveliness()
                    .declare_token(keys.alive(id).map_err(zerr)?)
                    .await
                    .map_err(zerr)?,
            )
        } else {
            None
        };
        let publisher = async |stream| -> Result<Option<Publisher<'static>>, SimError> {
            match mapping.robot_key(keys, id, stream).map_err(zerr)? {
                Some(key) => Ok(Some(
                    session
                        .declare_publisher(key)
                        .encoding(Encoding::APPLICATION_CDR)
                        .await
                        .map_err(zerr)?,
                )),
                None => Ok(None),
            }
        };
        let odom = publisher(Stream::Odom).await?;
        let scan = publisher(Stream::Scan).await?;
        let link = RobotLink::on_session(session.clone(), keys.clone(), id)
            .await
            .map_err(zerr)?;
        let (fetch, mut fetch_rx) = mpsc::unbounded_channel::<()>();
        // A robot that (re)starts asks for its current plan first.
        let _ = fetch.send(());
        tokio::spawn(async move {
            loop {
                tokio::select! {
                    message = link.recv() => match message {
                        Ok(m) => {
                            if inbox.send((index, m)).is_err() {
                                break;
                            }
                        }
                        Err(e) => {
                            tracing::debug!("robot link closed: {e}");
                            break;
                        }
                    },
                    asked = fetch_rx.recv() => {
                        if asked.is_none() {
                            break;
                        }
                        match link.fetch_plan(FETCH_TIMEOUT).await {
                            Ok(Some(doc)) => {
                                let plan_id = doc.plan_id.clone();
                                if inbox.send((index, RobotMessage::Plan(doc))).is_err() {
                                    break;
                                }
                                // Statuses are published on change: one that changed before this robot
                                // listened (a hold on a blocked path) is asked for.
                                match link.fetch_status(&plan_id, FETCH_TIMEOUT).await {
                                    Ok(Some(status)) => {
                                        if inbox.send((index, RobotMessage::Status(Box::new(status)))).is_err() {
                                            break;
                                        }
                                    }
                                    Ok(None) => {}
                                    Err(e) => tracing::warn!("plan status fetch failed: {e}"),
                                }
                            }
                            Ok(None) => {}
                            Err(e) => tracing::warn!("plan fetch failed: {e}"),
                        }
                    }
                }
            }
        });
        Ok(Self {
            odom,
            scan,
            fetch,
            _token: token,
            session,
        })
    }

    /// Asks the daemon for the robot's current plan (the answer arrives in the inbox).
    pub fn request_plan(&self) {
        let _ = self.fetch.send(());
    }

    /// Publishes nav_msgs/Odometry (map frame) for `body` stamped `stamp_ns`.
    pub async fn odometry(&self, body: &DiffDrive, stamp_ns: i64) -> Result<(), SimError> {
        let Some(p) = &self.odom else { return Ok(()) };
        let mut o = Odometry {
            header: Header {
                stamp: Time::from_ns(stamp_ns),
                frame_id: "map".into(),
            },
            child_frame_id: "base_link".into(),
            ..Odometry::default()
        };
        o.pose.pose.position.x = body.x;
        o.pose.pose.position.y = body.y;
        o.pose.pose.orientation.z = (body.yaw / 2.0).sin();
        o.pose.pose.orientation.w = (body.yaw / 2.0).cos();
        o.twist.twist.linear.x = body.v;
        o.twist.twist.angular.z = body.w;
        p.put(encode_odometry(&o)).await.map_err(zerr)
    }

    /// Publishes a sensor_msgs/LaserScan in the laser frame (at the robot's centre) stamped `stamp_ns`.
    pub async fn scan(&self, lidar: &Lidar, ranges: &[f32], stamp_ns: i64) -> Result<(), SimError> {
        let Some(p) = &self.scan else { return Ok(()) };
        let inc = lidar.increment() as f32;
        let msg = LaserScan {
            header: Header {
                stamp: Time::from_ns(stamp_ns),
                frame_id: "laser".into(),
            },
            angle_min: 0.0,
            angle_max: inc * (ranges.len().saturating_sub(1)) as f32,
            angle_increment: inc,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: lidar.range_min as f32,
            range_max: lidar.range_max as f32,
            ranges: ranges.to_vec(),
            intensities: Vec::new(),
        };
        p.put(encode_laser_scan(&msg)).await.map_err(zerr)
    }

    /// Closes the session (the liveliness token goes with it).
    pub async fn close(self) {
        let _ = self.session.close().await;
    }
}
