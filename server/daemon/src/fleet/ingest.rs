//! Sensor ingest off the async workers: the adapter between the Zenoh subscriptions and the engine's
//! [`SensorHub`] (which decides where every message goes: see `shift_engine::sensors`).
//!
//! Odometry waits in one queue, clouds and scans in small queues per robot and stream that drop the oldest when
//! full (a flood never grows memory, and the newest view of the world wins). One named thread (`ingest`) takes
//! odometry first, then clouds and scans robots in turn; hands each to the hub; forwards accepted poses to the
//! engine loop; inserts placed points into their site's live map and tells the engine loop where new obstacle
//! points landed ([`Event::MapChanged`]) and that the site is fed ([`Event::SiteFed`], at most once a second per
//! site); counts and logs drops (at most one line a second, plus the first `unrouted` and `frame` drop of each
//! robot). Messages waiting in the hub for their pose are dropped at their deadline even when nothing else comes.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use shift_engine::sensors::{Decoded, DropReason, Dropped, FramedPose, Outcome, Placed, SensorHub};
use shift_engine::{Event, LiveMapParams, LiveMaps};
use shift_proto::keys::Stream;

use crate::clock::SharedClock;
use crate::engine_loop::handle::{EngineHandle, Msg};
use crate::views::Views;

/// How often the live map's horizon is enforced, milliseconds.
const EXPIRE_EVERY_MS: u64 = 5_000;
/// The engine hears that a site is fed at most this often, milliseconds.
const FED_EVERY_MS: u64 = 1_000;
/// Odometry messages waiting at most (all robots); beyond, the oldest is dropped.
const ODOM_QUEUE: usize = 4_096;
/// The memory gauges (`shift_memory_bytes{component}`) are set at most this often, milliseconds.
const MEMORY_EVERY_MS: u64 = 5_000;

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
    odom: VecDeque<(String, FramedPose)>,
    per_robot: HashMap<QueueKey, VecDeque<RawCloud>>,
    ready: VecDeque<QueueKey>,
    stop: bool,
}

/// What the thread takes next.
enum Work {
    Odom(String, FramedPose),
    Sensor(RawCloud),
    /// Nothing came before the hub's next deadline.
    Tick,
}

fn stream_label(stream: Stream) -> &'static str {
    match stream {
        Stream::Scan => "scan",
        Stream::Odom => "odom",
        _ => "cloud",
    }
}

/// The queues, the hub and where placed points go.
#[derive(Debug)]
pub struct Ingest {
    queues: Mutex<Queues>,
    wake: Condvar,
    capacity: usize,
    params: LiveMapParams,
    hub: Arc<Mutex<SensorHub>>,
    views: Arc<Views>,
    live: Arc<LiveMaps>,
    engine: Option<EngineHandle>,
    clock: SharedClock,
    fed_ms: Mutex<HashMap<String, u64>>,
}

impl Ingest {
    /// An ingest of `capacity` messages per robot and stream into `live`, placing through `hub`.
    pub fn new(
        capacity: usize,
        params: LiveMapParams,
        hub: Arc<Mutex<SensorHub>>,
        views: Arc<Views>,
        live: Arc<LiveMaps>,
        engine: Option<EngineHandle>,
        clock: SharedClock,
    ) -> Self {
        Self {
            queues: Mutex::new(Queues::default()),
            wake: Condvar::new(),
            capacity: capacity.max(1),
            params,
            hub,
            views,
            live,
            engine,
            clock,
            fed_ms: Mutex::new(HashMap::new()),
        }
    }

    /// Queues an odometry pose (the frame it names is checked by the hub).
    pub fn push_odom(&self, robot: String, pose: FramedPose) {
        let Ok(mut q) = self.queues.lock() else { return };
        let full = q.odom.len() >= ODOM_QUEUE;
        if full {
            q.odom.pop_front();
        }
        q.odom.push_back((robot, pose));
        drop(q);
        if full {
            metrics::counter!("shift_odom_dropped_total", "reason" => "queue_full").increment(1);
        }
        self.wake.notify_one();
    }

    /// Queues a cloud or scan; drops the oldest of its robot and stream when that queue is full.
    pub fn push(&self, cloud: RawCloud) {
        let Ok(mut q) = self.queues.lock() else { return };
        let key = (cloud.robot.clone(), cloud.stream);
        let (robot, stream) = (cloud.robot.clone(), cloud.stream);
        let queue = q.per_robot.entry(key.clone()).or_default();
        let full = queue.len() >= self.capacity;
        if full {
            queue.pop_front();
        }
        queue.push_back(cloud);
        if !q.ready.contains(&key) {
            q.ready.push_back(key);
        }
        drop(q);
        if full {
            let detail = format!("more than {} messages queued", self.capacity);
            let dropped = self
                .hub
                .lock()
                .ok()
                .map(|mut h| h.record_drop(&robot, stream, DropReason::QueueFull, detail));
            if let Some(d) = dropped {
                self.count_drop(&d);
            }
        }
        self.wake.notify_one();
    }

    /// Heap bytes waiting in the queues: the raw clouds and scans (their payloads, by capacity) and the odometry.
    /// Bounded: `capacity` messages per robot and stream, [`ODOM_QUEUE`] poses.
    pub fn queued_bytes(&self) -> usize {
        self.queues.lock().map_or(0, |q| {
            let sensors: usize = q
                .per_robot
                .values()
                .map(|v| v.capacity() * size_of::<RawCloud>() + v.iter().map(|c| c.bytes.capacity()).sum::<usize>())
                .sum();
            q.odom.capacity() * size_of::<(String, FramedPose)>() + sensors
        })
    }

    /// Sets `shift_memory_bytes{component}`: the live maps, the static clearance fields they filter with, the
    /// sensor hub (odometry histories, messages waiting for their pose) and the ingest queues (issue 22: a figure
    /// per component, beside the allocator's own in `shift_allocator_bytes`).
    fn publish_memory(&self) {
        let (live, statics) = self.live.memory_bytes();
        let hub = self.hub.lock().map_or(0, |h| h.memory_bytes());
        let parts = [
            ("live_maps", live),
            ("site_clearance", statics),
            ("sensor_hub", hub),
            ("ingest_queues", self.queued_bytes()),
        ];
        for (component, bytes) in parts {
            metrics::gauge!("shift_memory_bytes", "component" => component).set(bytes as f64);
        }
    }

    /// Makes the thread leave once the queues are empty.
    pub fn stop(&self) {
        if let Ok(mut q) = self.queues.lock() {
            q.stop = true;
        }
        self.wake.notify_all();
    }

    /// Takes the next message (odometry first, then robots in turn), or [`Work::Tick`] at the hub's next
    /// deadline; `None` when stopped and empty.
    fn next(&self) -> Option<Work> {
        let mut q = self.queues.lock().ok()?;
        loop {
            if let Some((robot, pose)) = q.odom.pop_front() {
                return Some(Work::Odom(robot, pose));
            }
            while let Some(key) = q.ready.pop_front() {
                let Some(queue) = q.per_robot.get_mut(&key) else {
                    continue;
                };
                if let Some(c) = queue.pop_front() {
                    if !queue.is_empty() {
                        q.ready.push_back(key);
                    }
                    return Some(Work::Sensor(c));
                }
            }
            if q.stop {
                return None;
            }
            let deadline = self.hub.lock().ok().and_then(|h| h.next_deadline_ms());
            match deadline {
                Some(at) => {
                    let wait = at.saturating_sub(self.clock.now_ms()).max(1);
                    let (guard, timeout) = self.wake.wait_timeout(q, Duration::from_millis(wait)).ok()?;
                    q = guard;
                    if timeout.timed_out() {
                        return Some(Work::Tick);
                    }
                }
                None => q = self.wake.wait(q).ok()?,
            }
        }
    }

    /// The thread's loop.
    pub fn run(&self) {
        let mut last_log: Option<Instant> = None;
        let mut memory_ms: Option<u64> = None;
        while let Some(work) = self.next() {
            let now = self.clock.now_ms();
            let outcomes = match work {
                Work::Odom(robot, pose) => self.odometry(&robot, pose, now),
                Work::Sensor(msg) => {
                    // The hub sees it at the time it arrived: its wait for a pose and the latency figures count
                    // from there.
                    let received_ms = now.saturating_sub(msg.received.elapsed().as_millis() as u64);
                    self.sensor(&msg, received_ms)
                }
                Work::Tick => Vec::new(),
            };
            let expired = self.hub.lock().map(|mut h| h.expire(now)).unwrap_or_default();
            let mut placed = false;
            for outcome in outcomes.into_iter().chain(expired) {
                match outcome {
                    Outcome::Placed(p) => match self.insert(p, now) {
                        Ok(()) => placed = true,
                        Err(d) => {
                            self.count_drop(&d);
                            self.log_drop(&d, &mut last_log);
                        }
                    },
                    Outcome::Dropped(d) => {
                        self.count_drop(&d);
                        self.log_drop(&d, &mut last_log);
                    }
                }
            }
            // First at the first points placed, then at most every MEMORY_EVERY_MS.
            let due = match memory_ms {
                None => placed,
                Some(t) => now.saturating_sub(t) >= MEMORY_EVERY_MS,
            };
            if due {
                memory_ms = Some(now);
                self.publish_memory();
            }
        }
    }

    /// A cloud or scan → hub. Decoded outside the hub's lock (a large cloud takes a while; the engine loop and
    /// the API lock the hub too), routing checked first so unrouted robots cost no decode.
    fn sensor(&self, msg: &RawCloud, received_ms: u64) -> Vec<Outcome> {
        let Ok(unrouted) = self.hub.lock().map(|mut h| h.unrouted(&msg.robot, msg.stream)) else {
            return Vec::new();
        };
        if let Some(drop) = unrouted {
            return vec![drop];
        }
        let decoded = Decoded::decode(msg.stream, &msg.bytes);
        let Ok(mut hub) = self.hub.lock() else {
            return Vec::new();
        };
        match decoded {
            Ok(m) => hub.decoded(&msg.robot, m, received_ms),
            Err(e) => vec![Outcome::Dropped(hub.record_drop(
                &msg.robot,
                msg.stream,
                DropReason::Malformed,
                e.to_string(),
            ))],
        }
    }

    /// Odometry → hub (history, waiting messages released) → engine (progress, checks).
    fn odometry(&self, robot: &str, pose: FramedPose, now: u64) -> Vec<Outcome> {
        let Ok(out) = self.hub.lock().map(|mut h| h.odometry(robot, pose, now)) else {
            return Vec::new();
        };
        if let Some(d) = &out.rejected {
            metrics::counter!("shift_odom_dropped_total", "reason" => d.reason.as_str()).increment(1);
            if d.first {
                tracing::warn!(robot, reason = d.reason.as_str(), "odometry not used: {}", d.detail);
            }
        }
        if out.clock_jumped_back {
            metrics::counter!("shift_odom_clock_jumps_total").increment(1);
            tracing::info!(
                robot,
                "odometry clock jumped back (robot restarted?): pose history started again"
            );
        }
        if let (Some(pose), Some(engine)) = (out.pose, &self.engine) {
            let event = Event::RobotPose {
                robot: robot.to_owned(),
                pose,
            };
            // Lossy under overload: the next pose supersedes a dropped one.
            if engine.try_tell(Msg::event(event)).is_err() {
                metrics::counter!("shift_odom_dropped_total", "reason" => "engine_busy").increment(1);
            }
        }
        out.released
    }

    fn count_drop(&self, d: &Dropped) {
        metrics::counter!("shift_ingest_dropped_total", "reason" => d.reason.as_str(), "stream" => stream_label(d.stream))
            .increment(1);
        let site = self
            .hub
            .lock()
            .ok()
            .and_then(|h| h.site_of(&d.robot).map(str::to_owned));
        if let Some(live) = site.and_then(|s| self.live.get(&s)) {
            live.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }

    fn log_drop(&self, d: &Dropped, last_log: &mut Option<Instant>) {
        if d.first && matches!(d.reason, DropReason::Unrouted | DropReason::NoMap) {
            // Once per robot: a configuration problem, not noise.
            tracing::warn!(
                robot = d.robot,
                reason = d.reason.as_str(),
                "sensor data goes nowhere: {}",
                d.detail
            );
        } else if last_log.is_none_or(|t| t.elapsed().as_secs() >= 1) {
            tracing::warn!(
                robot = d.robot,
                stream = stream_label(d.stream),
                reason = d.reason.as_str(),
                "sensor message dropped: {}",
                d.detail
            );
            *last_log = Some(Instant::now());
        }
    }

    /// Placed points into their site's live map.
    fn insert(&self, p: Placed, now: u64) -> Result<(), Dropped> {
        let work = Instant::now();
        let no_map = |detail: String| {
            self.hub
                .lock()
                .map(|mut h| h.record_drop(&p.robot, p.stream, DropReason::NoMap, detail.clone()))
                .unwrap_or_else(|_| Dropped::internal(&p.robot, p.stream, detail))
        };
        let Some(summary) = self.views.site(&p.site) else {
            return Err(no_map(format!("site {:?} has no map", p.site)));
        };
        let Some(live) = self.live.get_or_create(&summary, self.params) else {
            return Err(no_map(format!("site {:?}: its live map could not be created", p.site)));
        };
        let (report, points_in_map, map_bytes) = match live.map.write() {
            Ok(mut map) => {
                // What the scan saw through first: its own returns are never cleared by it.
                if let Some(sweep) = &p.sweep {
                    map.clear_through(sweep);
                }
                let r = map.ingest(&p.points, p.heights, now);
                // Forget what was not seen again within the horizon, at most every few seconds.
                if now.saturating_sub(live.last_expire_ms.load(Ordering::Relaxed)) >= EXPIRE_EVERY_MS {
                    live.last_expire_ms.store(now, Ordering::Relaxed);
                    map.expire(now);
                }
                (r, map.stats().points, map.memory_bytes())
            }
            Err(_) => return Err(Dropped::internal(&p.robot, p.stream, "live map lock poisoned".into())),
        };
        live.mark_update(now);
        if let Some(engine) = &self.engine {
            if let (Some((min, max)), true) = (report.extent, report.inserted > 0) {
                // Lossy: a dropped notice is caught by the next pose-triggered check.
                let changed = Event::MapChanged {
                    site: p.site.clone(),
                    min,
                    max,
                };
                if engine.try_tell(Msg::event(changed)).is_err() {
                    metrics::counter!("shift_map_change_dropped_total").increment(1);
                }
            }
            self.tell_fed(engine, &p.site, now);
        }
        tracing::debug!(
            robot = p.robot,
            site = p.site,
            stream = stream_label(p.stream),
            offered = report.offered,
            inserted = report.inserted,
            waited = p.waited,
            "sensor message ingested"
        );
        let stream = stream_label(p.stream);
        metrics::counter!("shift_ingest_clouds_total", "stream" => stream).increment(1);
        metrics::counter!("shift_ingest_points_total", "stream" => stream).increment(report.offered as u64);
        metrics::histogram!("shift_ingest_work_seconds").record(work.elapsed().as_secs_f64());
        metrics::histogram!("shift_ingest_latency_seconds").record(now.saturating_sub(p.received_ms) as f64 / 1e3);
        // Stamp to visible in the map (transport included; meaningful when the robot's clock is synchronised).
        if p.stamp_ns > 0 {
            let age = (now as f64 * 1e-3) - (p.stamp_ns as f64 * 1e-9);
            if age >= 0.0 {
                metrics::histogram!("shift_ingest_stamp_age_seconds").record(age);
            }
        }
        metrics::gauge!("shift_live_map_points", "site" => p.site.clone()).set(points_in_map as f64);
        metrics::gauge!("shift_live_map_bytes", "site" => p.site.clone()).set(map_bytes as f64);
        Ok(())
    }

    /// Tells the engine the site's live map is fed, at most every [`FED_EVERY_MS`].
    fn tell_fed(&self, engine: &EngineHandle, site: &str, now: u64) {
        let Ok(mut fed) = self.fed_ms.lock() else { return };
        let last = fed.get(site).copied().unwrap_or(0);
        if now.saturating_sub(last) < FED_EVERY_MS {
            return;
        }
        if engine
            .try_tell(Msg::event(Event::SiteFed { site: site.to_owned() }))
            .is_ok()
        {
            fed.insert(site.to_owned(), now);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ingest(capacity: usize) -> Ingest {
        Ingest::new(
            capacity,
            LiveMapParams::default(),
            Arc::new(Mutex::new(SensorHub::default())),
            Arc::new(Views::default()),
            Arc::new(LiveMaps::default()),
            None,
            crate::clock::system(),
        )
    }

    fn scan(robot: &str, bytes: usize) -> RawCloud {
        RawCloud {
            robot: robot.into(),
            stream: Stream::Scan,
            bytes: vec![0; bytes],
            received: Instant::now(),
        }
    }

    #[test]
    fn queued_bytes_stay_within_the_per_robot_bound_under_a_flood() {
        let ingest = ingest(4);
        assert_eq!(ingest.queued_bytes(), 0);
        // 200 scans of 10 kB from each of two robots, nothing taken: 4 of each stay.
        for _ in 0..200 {
            ingest.push(scan("r1", 10_000));
            ingest.push(scan("r2", 10_000));
        }
        let queued = ingest.queued_bytes();
        assert!(
            (80_000..90_000).contains(&queued),
            "{queued} bytes queued for 2 x 4 scans of 10 kB"
        );
        // Taken: the payloads go, only the queues' slots stay.
        for _ in 0..8 {
            assert!(matches!(ingest.next(), Some(Work::Sensor(_))));
        }
        assert!(ingest.queued_bytes() < 2_000, "{} bytes left", ingest.queued_bytes());
    }
}
