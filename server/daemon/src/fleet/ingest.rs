//! Cloud ingest off the async workers: each robot's clouds wait in a small queue that drops the oldest when
//! full (a flood never grows memory, and the newest view of the world wins); one named thread decodes them,
//! moves robot-frame points into the map frame with the robot's latest pose, and inserts them into the site's
//! live map. Malformed payloads are counted and logged at most once a second; they never stop the thread.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use shift_engine::LiveMapParams;
use shift_proto::ros::point_cloud2::{cloud_xyz, decode_point_cloud2};

use shift_engine::Event;

use super::live::LiveMaps;
use crate::brain::{BrainHandle, Msg, now_ms};
use crate::views::Views;

/// How often the live map's horizon is enforced, milliseconds.
const EXPIRE_EVERY_MS: u64 = 5_000;

/// One cloud as received.
#[derive(Debug)]
pub struct RawCloud {
    /// Robot that sent it.
    pub robot: String,
    /// CDR bytes.
    pub bytes: Vec<u8>,
    /// When it arrived.
    pub received: Instant,
}

#[derive(Debug, Default)]
struct Queues {
    per_robot: HashMap<String, VecDeque<RawCloud>>,
    ready: VecDeque<String>,
    stop: bool,
}

/// The queues and the thread's settings.
#[derive(Debug)]
pub struct Ingest {
    queues: Mutex<Queues>,
    wake: Condvar,
    capacity: usize,
    site: String,
    map_frame: String,
    params: LiveMapParams,
    views: Arc<Views>,
    live: Arc<LiveMaps>,
    /// Told where new obstacle points landed (path watching).
    brain: Option<BrainHandle>,
}

impl Ingest {
    /// Settings for the thread.
    pub fn new(
        capacity: usize,
        site: String,
        map_frame: String,
        params: LiveMapParams,
        views: Arc<Views>,
        live: Arc<LiveMaps>,
        brain: Option<BrainHandle>,
    ) -> Self {
        Self {
            queues: Mutex::new(Queues::default()),
            wake: Condvar::new(),
            capacity: capacity.max(1),
            site,
            map_frame,
            params,
            views,
            live,
            brain,
        }
    }

    /// Queues a cloud; drops the robot's oldest when its queue is full.
    pub fn push(&self, cloud: RawCloud) {
        let Ok(mut q) = self.queues.lock() else { return };
        let robot = cloud.robot.clone();
        let queue = q.per_robot.entry(robot.clone()).or_default();
        if queue.len() >= self.capacity {
            queue.pop_front();
            metrics::counter!("shift_ingest_dropped_total", "reason" => "queue_full").increment(1);
            if let Some(live) = self.live.get(&self.site) {
                live.dropped.fetch_add(1, Ordering::Relaxed);
            }
        }
        queue.push_back(cloud);
        if !q.ready.contains(&robot) {
            q.ready.push_back(robot);
        }
        drop(q);
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
            while let Some(robot) = q.ready.pop_front() {
                let Some(queue) = q.per_robot.get_mut(&robot) else {
                    continue;
                };
                if let Some(c) = queue.pop_front() {
                    if !queue.is_empty() {
                        q.ready.push_back(robot);
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
        while let Some(cloud) = self.next() {
            if let Err(reason) = self.ingest(&cloud) {
                metrics::counter!("shift_ingest_dropped_total", "reason" => "malformed").increment(1);
                if let Some(live) = self.live.get(&self.site) {
                    live.dropped.fetch_add(1, Ordering::Relaxed);
                }
                if last_log.is_none_or(|t| t.elapsed().as_secs() >= 1) {
                    tracing::warn!(robot = cloud.robot, "cloud dropped: {reason}");
                    last_log = Some(Instant::now());
                }
            }
        }
    }

    fn ingest(&self, cloud: &RawCloud) -> Result<(), String> {
        let msg = decode_point_cloud2(&cloud.bytes).map_err(|e| e.to_string())?;
        let xyz = cloud_xyz(&msg).map_err(|e| e.to_string())?;
        let frame = xyz.header.frame_id.trim_start_matches('/');
        let points: Vec<[f64; 3]> = if frame.is_empty() || frame == self.map_frame {
            xyz.points
        } else {
            // Robot-frame points: move them by the robot's latest pose (planar robots: yaw only).
            let pose = self
                .views
                .robot(&cloud.robot)
                .and_then(|r| r.pose)
                .ok_or_else(|| format!("points in frame {frame:?} but no odometry from {} yet", cloud.robot))?;
            let (s, c) = pose.yaw.sin_cos();
            xyz.points
                .iter()
                .map(|p| [pose.x + c * p[0] - s * p[1], pose.y + s * p[0] + c * p[1], p[2]])
                .collect()
        };
        let summary = self
            .views
            .site(&self.site)
            .ok_or_else(|| format!("site {:?} has no map", self.site))?;
        let live = self
            .live
            .get_or_create(&summary, self.params)
            .ok_or_else(|| "live map could not be created".to_owned())?;
        let now = now_ms();
        let report = match live.map.write() {
            Ok(mut map) => {
                let r = map.ingest(&points, false, now);
                // Forget what was not seen again within the horizon, at most every few seconds.
                if now.saturating_sub(live.last_expire_ms.load(Ordering::Relaxed)) >= EXPIRE_EVERY_MS {
                    live.last_expire_ms.store(now, Ordering::Relaxed);
                    map.expire(now);
                }
                r
            }
            Err(_) => return Err("live map lock poisoned".into()),
        };
        live.mark_update(now);
        if let (Some(brain), Some((min, max)), true) = (&self.brain, report.extent, report.inserted > 0) {
            // Lossy: a dropped notice is caught by the next pose-triggered check.
            let changed = Event::MapChanged {
                site: self.site.clone(),
                min,
                max,
            };
            if brain.try_tell(Msg::event(changed)).is_err() {
                metrics::counter!("shift_map_change_dropped_total").increment(1);
            }
        }
        tracing::debug!(
            robot = cloud.robot,
            offered = report.offered,
            inserted = report.inserted,
            "cloud ingested"
        );
        metrics::counter!("shift_ingest_clouds_total").increment(1);
        metrics::counter!("shift_ingest_points_total").increment(report.offered as u64);
        metrics::histogram!("shift_ingest_latency_seconds").record(cloud.received.elapsed().as_secs_f64());
        if let Ok(map) = live.map.read() {
            metrics::gauge!("shift_live_map_points", "site" => self.site.clone()).set(map.stats().points as f64);
        }
        Ok(())
    }
}
