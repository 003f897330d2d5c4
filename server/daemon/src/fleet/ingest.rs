//! Sensor ingest off the async workers: each robot's clouds and scans wait in small queues (one per robot and
//! stream) that drop the oldest when full (a flood never grows memory, and the newest view of the world wins);
//! one named thread decodes them, moves them into the map frame, and inserts them into the site's live map.
//!
//! Poses: the odometry path feeds a short per-robot [`PoseHistory`]. A LaserScan is placed with the pose
//! interpolated at its stamp (a stamp outside the history, beyond the tolerance, drops the scan: `too_old`,
//! `future`, `no_pose`; an unstamped scan, stamp 0, takes the latest pose); a robot-frame cloud uses the pose at its stamp when the history covers it and the
//! latest pose otherwise; map-frame clouds need no pose. Malformed payloads are counted and logged at most once
//! a second; they never stop the thread.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use shift_engine::{LiveMapParams, Pose2, PoseHistory, PoseHistoryParams};
use shift_proto::keys::Stream;
use shift_proto::ros::Header;
use shift_proto::ros::laser_scan::decode_laser_scan;
use shift_proto::ros::point_cloud2::decode_cloud_xyz;

use shift_engine::Event;

use super::live::LiveMaps;
use super::scan::{SensorOffset, scan_to_map};
use crate::brain::{BrainHandle, Msg, now_ms};
use crate::views::Views;

/// How often the live map's horizon is enforced, milliseconds.
const EXPIRE_EVERY_MS: u64 = 5_000;

/// One cloud or scan as received.
#[derive(Debug)]
pub struct RawCloud {
    /// Robot that sent it.
    pub robot: String,
    /// [`Stream::Cloud`] (sensor_msgs/PointCloud2) or [`Stream::Scan`] (sensor_msgs/LaserScan).
    pub stream: Stream,
    /// CDR bytes.
    pub bytes: Vec<u8>,
    /// When it arrived.
    pub received: Instant,
}

/// A queue: one robot's clouds or scans.
type QueueKey = (String, Stream);

#[derive(Debug, Default)]
struct Queues {
    per_robot: HashMap<QueueKey, VecDeque<RawCloud>>,
    ready: VecDeque<QueueKey>,
    stop: bool,
}

/// Where and how the ingest thread writes.
#[derive(Debug, Clone)]
pub struct IngestSettings {
    /// Messages waiting per robot and stream.
    pub capacity: usize,
    /// Site whose live map is fed.
    pub site: String,
    /// Clouds in this frame (or none) need no transform.
    pub map_frame: String,
    /// The live map's knobs.
    pub params: LiveMapParams,
    /// Per-robot odometry history.
    pub history: PoseHistoryParams,
    /// The laser in the robot frame.
    pub scan_offset: SensorOffset,
}

/// Why a message did not reach the map (the metric label and a message for the log).
#[derive(Debug)]
struct Dropped {
    reason: &'static str,
    detail: String,
}

impl Dropped {
    fn new(reason: &'static str, detail: impl Into<String>) -> Self {
        Self {
            reason,
            detail: detail.into(),
        }
    }
}

fn stream_label(stream: Stream) -> &'static str {
    match stream {
        Stream::Scan => "scan",
        _ => "cloud",
    }
}

/// The queues and the thread's settings.
#[derive(Debug)]
pub struct Ingest {
    queues: Mutex<Queues>,
    wake: Condvar,
    settings: IngestSettings,
    poses: Mutex<HashMap<String, PoseHistory>>,
    views: Arc<Views>,
    live: Arc<LiveMaps>,
    /// Told where new obstacle points landed (path watching).
    brain: Option<BrainHandle>,
}

/// Wall-clock nanoseconds since the Unix epoch.
fn wall_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

impl Ingest {
    /// Settings for the thread.
    pub fn new(settings: IngestSettings, views: Arc<Views>, live: Arc<LiveMaps>, brain: Option<BrainHandle>) -> Self {
        Self {
            queues: Mutex::new(Queues::default()),
            wake: Condvar::new(),
            settings: IngestSettings {
                capacity: settings.capacity.max(1),
                ..settings
            },
            poses: Mutex::new(HashMap::new()),
            views,
            live,
            brain,
        }
    }

    /// Adds an odometry pose (map frame, robot clock) to the robot's history.
    pub fn push_pose(&self, robot: &str, pose: Pose2) {
        let Ok(mut poses) = self.poses.lock() else { return };
        match poses.get_mut(robot) {
            Some(h) => h.push(pose),
            None => {
                let mut h = PoseHistory::new(self.settings.history);
                h.push(pose);
                poses.insert(robot.to_owned(), h);
            }
        }
    }

    fn count_drop(&self, stream: Stream, reason: &'static str) {
        metrics::counter!("shift_ingest_dropped_total", "reason" => reason, "stream" => stream_label(stream))
            .increment(1);
        if let Some(live) = self.live.get(&self.settings.site) {
            live.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// Queues a cloud or scan; drops the oldest of its robot and stream when that queue is full.
    pub fn push(&self, cloud: RawCloud) {
        let Ok(mut q) = self.queues.lock() else { return };
        let key = (cloud.robot.clone(), cloud.stream);
        let stream = cloud.stream;
        let queue = q.per_robot.entry(key.clone()).or_default();
        let full = queue.len() >= self.settings.capacity;
        if full {
            queue.pop_front();
        }
        queue.push_back(cloud);
        if !q.ready.contains(&key) {
            q.ready.push_back(key);
        }
        drop(q);
        if full {
            self.count_drop(stream, "queue_full");
        }
        self.wake.notify_one();
    }

    /// Makes the thread leave once the queues are empty.
    pub fn stop(&self) {
        if let Ok(mut q) = self.queues.lock() {
            q.stop = true;
        }
        self.wake.notify_all();
    }

    /// Takes the next cloud, robots in turn; `None` when stopped and empty.
    fn next(&self) -> Option<RawCloud> {
        let mut q = self.queues.lock().ok()?;
        loop {
            while let Some(key) = q.ready.pop_front() {
                let Some(queue) = q.per_robot.get_mut(&key) else {
                    continue;
                };
                if let Some(c) = queue.pop_front() {
                    if !queue.is_empty() {
                        q.ready.push_back(key);
                    }
                    return Some(c);
                }
            }
            if q.stop {
                return None;
            }
            q = self.wake.wait(q).ok()?;
        }
    }

    /// The thread's loop.
    pub fn run(&self) {
        let mut last_log: Option<Instant> = None;
        while let Some(msg) = self.next() {
            if let Err(d) = self.ingest(&msg) {
                self.count_drop(msg.stream, d.reason);
                if last_log.is_none_or(|t| t.elapsed().as_secs() >= 1) {
                    tracing::warn!(
                        robot = msg.robot,
                        stream = stream_label(msg.stream),
                        reason = d.reason,
                        "sensor message dropped: {}",
                        d.detail
                    );
                    last_log = Some(Instant::now());
                }
            }
        }
    }

    /// The robot's pose at `stamp_ns` from its odometry history.
    fn pose_at(&self, robot: &str, stamp_ns: i64) -> Result<Pose2, Dropped> {
        let poses = self
            .poses
            .lock()
            .map_err(|_| Dropped::new("internal", "pose lock poisoned"))?;
        let h = poses.get(robot);
        if stamp_ns == 0 {
            // Unstamped: the latest pose is the best there is.
            return h
                .and_then(PoseHistory::latest)
                .ok_or_else(|| Dropped::new("no_pose", format!("no odometry from {robot} yet")));
        }
        h.map_or(Err(shift_engine::PoseLookupError::Empty), |h| h.at(stamp_ns))
            .map_err(|e| Dropped::new(e.kind(), format!("{robot}: {e}")))
    }

    /// A cloud's points in the map frame (3-D: the height band applies).
    fn cloud_points(&self, msg: &RawCloud) -> Result<(Header, Vec<[f64; 3]>), Dropped> {
        let xyz = decode_cloud_xyz(&msg.bytes).map_err(|e| Dropped::new("malformed", e.to_string()))?;
        let frame = xyz.header.frame_id.trim_start_matches('/');
        if frame.is_empty() || frame == self.settings.map_frame {
            return Ok((xyz.header, xyz.points));
        }
        // Robot-frame points: the pose at the stamp when the history has it, else the latest one.
        let stamp = xyz.header.stamp.to_ns();
        let pose = self
            .pose_at(&msg.robot, stamp)
            .ok()
            .or_else(|| {
                let poses = self.poses.lock().ok()?;
                poses.get(&msg.robot).and_then(PoseHistory::latest)
            })
            .or_else(|| {
                self.views.robot(&msg.robot).and_then(|r| r.pose).map(|p| Pose2 {
                    x: p.x,
                    y: p.y,
                    yaw: p.yaw,
                    stamp_ns: p.stamp_ns,
                })
            })
            .ok_or_else(|| {
                Dropped::new(
                    "no_pose",
                    format!("points in frame {frame:?} but no odometry from {} yet", msg.robot),
                )
            })?;
        let (s, c) = pose.yaw.sin_cos();
        let points = xyz
            .points
            .iter()
            .map(|p| [pose.x + c * p[0] - s * p[1], pose.y + s * p[0] + c * p[1], p[2]])
            .collect();
        Ok((xyz.header, points))
    }

    /// A scan's returns in the map frame (planar).
    fn scan_points(&self, msg: &RawCloud) -> Result<(Header, Vec<[f64; 3]>), Dropped> {
        let scan = decode_laser_scan(&msg.bytes).map_err(|e| Dropped::new("malformed", e.to_string()))?;
        let pose = self.pose_at(&msg.robot, scan.header.stamp.to_ns())?;
        let points = scan_to_map(&scan, pose, self.settings.scan_offset);
        Ok((scan.header, points))
    }

    fn ingest(&self, msg: &RawCloud) -> Result<(), Dropped> {
        let work = Instant::now();
        let planar = msg.stream == Stream::Scan;
        let (header, points) = if planar {
            self.scan_points(msg)?
        } else {
            self.cloud_points(msg)?
        };
        let site = &self.settings.site;
        let summary = self
            .views
            .site(site)
            .ok_or_else(|| Dropped::new("no_map", format!("site {site:?} has no map")))?;
        let live = self
            .live
            .get_or_create(&summary, self.settings.params)
            .ok_or_else(|| Dropped::new("internal", "live map could not be created"))?;
        let now = now_ms();
        let (report, points_in_map) = match live.map.write() {
            Ok(mut map) => {
                let r = map.ingest(&points, planar, now);
                // Forget what was not seen again within the horizon, at most every few seconds.
                if now.saturating_sub(live.last_expire_ms.load(Ordering::Relaxed)) >= EXPIRE_EVERY_MS {
                    live.last_expire_ms.store(now, Ordering::Relaxed);
                    map.expire(now);
                }
                (r, map.stats().points)
            }
            Err(_) => return Err(Dropped::new("internal", "live map lock poisoned")),
        };
        live.mark_update(now);
        if let (Some(brain), Some((min, max)), true) = (&self.brain, report.extent, report.inserted > 0) {
            // Lossy: a dropped notice is caught by the next pose-triggered check.
            let changed = Event::MapChanged {
                site: self.settings.site.clone(),
                min,
                max,
            };
            if brain.try_tell(Msg::event(changed)).is_err() {
                metrics::counter!("shift_map_change_dropped_total").increment(1);
            }
        }
        tracing::debug!(
            robot = msg.robot,
            stream = stream_label(msg.stream),
            offered = report.offered,
            inserted = report.inserted,
            "sensor message ingested"
        );
        let stream = stream_label(msg.stream);
        metrics::counter!("shift_ingest_clouds_total", "stream" => stream).increment(1);
        metrics::counter!("shift_ingest_points_total", "stream" => stream).increment(report.offered as u64);
        metrics::histogram!("shift_ingest_work_seconds").record(work.elapsed().as_secs_f64());
        metrics::histogram!("shift_ingest_latency_seconds").record(msg.received.elapsed().as_secs_f64());
        // Stamp to visible in the map (transport included; meaningful when the robot's clock is synchronised).
        let stamp = header.stamp.to_ns();
        if stamp > 0 {
            let age = (wall_ns() - stamp) as f64 * 1e-9;
            if age >= 0.0 {
                metrics::histogram!("shift_ingest_stamp_age_seconds").record(age);
            }
        }
        metrics::gauge!("shift_live_map_points", "site" => site.clone()).set(points_in_map as f64);
        Ok(())
    }
}
