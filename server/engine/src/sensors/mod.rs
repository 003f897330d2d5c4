//! The fleet's sensor pipeline, sans-IO: which site each robot's clouds and scans feed, where they are in the
//! map frame, and what to do with a message whose pose has not arrived yet.
//!
//! [`SensorHub`] is the one place that holds robots' odometry history (a [`PoseHistory`] per robot). The daemon's
//! ingest thread owns it: it hands it every odometry message ([`SensorHub::odometry`]) and every decoded-or-not
//! cloud and scan ([`SensorHub::sensor`]), and gets back [`Outcome`]s — points placed in a site's map frame, or a
//! drop with a counted reason. The engine decides the routing (a robot feeds the site of the plan it is
//! assigned, [`crate::Command::FeedSite`]); unassigned robots feed [`SensorParams::default_site`] when set, else
//! their points are dropped as `unrouted`.
//!
//! Waiting for the pose (tf2's message filter, bounded): odometry and sensor data travel on separate
//! subscriptions, so a scan stamped `t` may arrive before the odometry at `t`. Such a message waits at most
//! [`SensorParams::wait_ms`] (wall clock, milliseconds) and at most [`SensorParams::wait_max`] per robot (the
//! oldest goes first, `wait_full`), and is placed as soon as odometry covering its stamp arrives; at its deadline
//! it is dropped with the reason the lookup gives then (`future`, `no_pose`).

pub mod geometry;
pub mod sweep;

use std::collections::{BTreeMap, BTreeSet, HashMap, VecDeque};

use shift_proto::keys::Stream;
use shift_proto::ros::LaserScan;
use shift_proto::ros::laser_scan::decode_laser_scan;
use shift_proto::ros::point_cloud2::{CloudXyz, decode_cloud_xyz};

use self::geometry::{Heights, SensorOffset, robot_to_map, scan_to_map};
use self::sweep::Sweep;
use crate::pose_history::{PoseHistory, PoseHistoryParams, PoseLookupError};
use crate::robots::Pose2;

/// How sensor data is placed and routed.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorParams {
    /// Clouds in this frame (or with an empty frame) are in the map frame already.
    pub map_frame: String,
    /// Odometry frames taken as map-frame poses (besides `map_frame` and the empty frame); odometry in any other
    /// frame cannot be placed and is reported (`frame`).
    pub pose_frames: Vec<String>,
    /// Each robot's odometry history.
    pub history: PoseHistoryParams,
    /// The laser in the robot frame.
    pub scan_offset: SensorOffset,
    /// Longest a message waits for the odometry that places it, milliseconds (wall clock).
    pub wait_ms: u64,
    /// Most messages waiting per robot.
    pub wait_max: usize,
    /// The site unassigned robots feed; `None`: their points are dropped (`unrouted`).
    pub default_site: Option<String>,
}

impl Default for SensorParams {
    fn default() -> Self {
        Self {
            map_frame: "map".into(),
            pose_frames: vec!["odom".into()],
            history: PoseHistoryParams::default(),
            scan_offset: SensorOffset::default(),
            wait_ms: 500,
            wait_max: 32,
            default_site: None,
        }
    }
}

/// Why a message did not reach a map. [`DropReason::as_str`] is the metric label.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DropReason {
    /// The payload did not decode.
    Malformed,
    /// The robot feeds no site (unassigned and no default site).
    Unrouted,
    /// No odometry from the robot (within the wait).
    NoPose,
    /// The stamp is older than the odometry history.
    TooOld,
    /// The stamp stayed newer than the newest odometry for the whole wait.
    Future,
    /// Too many messages were waiting for their pose; the oldest went.
    WaitFull,
    /// Odometry in a frame the daemon cannot place.
    Frame,
    /// The ingest queue of the robot and stream was full; the oldest went.
    QueueFull,
    /// The site the robot feeds has no map.
    NoMap,
    /// A lock or invariant of the daemon failed (logged).
    Internal,
}

impl DropReason {
    /// Metric label.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Malformed => "malformed",
            Self::Unrouted => "unrouted",
            Self::NoPose => "no_pose",
            Self::TooOld => "too_old",
            Self::Future => "future",
            Self::WaitFull => "wait_full",
            Self::Frame => "frame",
            Self::QueueFull => "queue_full",
            Self::NoMap => "no_map",
            Self::Internal => "internal",
        }
    }

    fn of_lookup(e: PoseLookupError) -> Self {
        match e {
            PoseLookupError::Empty => Self::NoPose,
            PoseLookupError::TooOld { .. } => Self::TooOld,
            PoseLookupError::Future { .. } => Self::Future,
        }
    }
}

/// Points placed in a site's map frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    /// Robot that sent them.
    pub robot: String,
    /// Site whose live map they feed.
    pub site: String,
    /// [`Stream::Cloud`] or [`Stream::Scan`].
    pub stream: Stream,
    /// Map-frame points `[x, y, z]`, metres.
    pub points: Vec<[f64; 3]>,
    /// What the points' z measures (a scan's are planar: no height band).
    pub heights: Heights,
    /// A scan: the free space its rays crossed (the live map forgets what they saw through).
    pub sweep: Option<Sweep>,
    /// The message's stamp, nanoseconds (robot clock; 0 = unstamped).
    pub stamp_ns: i64,
    /// When it arrived, milliseconds (the caller's clock).
    pub received_ms: u64,
    /// It waited for its pose.
    pub waited: bool,
}

/// A message that reaches no map.
#[derive(Debug, Clone, PartialEq)]
pub struct Dropped {
    /// Robot that sent it.
    pub robot: String,
    /// Its stream.
    pub stream: Stream,
    /// Why.
    pub reason: DropReason,
    /// A sentence for the log.
    pub detail: String,
    /// The first drop of this robot for this reason (since it last fed a site): worth one log line.
    pub first: bool,
}

impl Dropped {
    /// A drop for a failure of the daemon itself, not of the message.
    pub fn internal(robot: &str, stream: Stream, detail: String) -> Self {
        Self {
            robot: robot.to_owned(),
            stream,
            reason: DropReason::Internal,
            detail,
            first: false,
        }
    }
}

/// What became of a message.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Placed.
    Placed(Placed),
    /// Dropped.
    Dropped(Dropped),
}

/// What an odometry message did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OdomOutcome {
    /// The pose, map frame, when accepted (the engine gets it as [`crate::Event::RobotPose`]).
    pub pose: Option<Pose2>,
    /// Why it was not accepted.
    pub rejected: Option<Dropped>,
    /// Messages that waited for it, now placed.
    pub released: Vec<Outcome>,
    /// Its stamp lay a whole history span before the newest pose: the robot's clock jumped back (a restart, a
    /// clock reset, a replayed log), so the history started again from this pose.
    pub clock_jumped_back: bool,
}

/// A planar pose as received, in the frame it names.
#[derive(Debug, Clone, PartialEq)]
pub struct FramedPose {
    /// The pose (stamp on the robot's clock).
    pub pose: Pose2,
    /// Its frame (`header.frame_id`; empty = the map frame).
    pub frame: String,
}

/// Per-robot figures for the API (`GET /v1/robots/{id}`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SensorCounts {
    /// Site its data feeds now.
    pub site: Option<String>,
    /// Messages placed.
    pub placed: u64,
    /// Points placed.
    pub points: u64,
    /// Messages waiting for their pose now.
    pub waiting: usize,
    /// Messages dropped, by reason label.
    pub dropped: BTreeMap<String, u64>,
    /// The last drop's sentence.
    pub last_drop: Option<String>,
}

/// A decoded cloud or scan, not yet placed.
#[derive(Debug)]
pub enum Decoded {
    /// sensor_msgs/PointCloud2, x/y/z extracted.
    Cloud(CloudXyz),
    /// sensor_msgs/LaserScan.
    Scan(LaserScan),
}

impl Decoded {
    /// Decodes a [`Stream::Cloud`] (PointCloud2) or [`Stream::Scan`] (LaserScan) CDR payload. Pure and possibly
    /// long for large clouds: callers sharing a hub decode before they lock it.
    pub fn decode(stream: Stream, bytes: &[u8]) -> Result<Self, shift_proto::CodecError> {
        match stream {
            Stream::Scan => decode_laser_scan(bytes).map(Self::Scan),
            _ => decode_cloud_xyz(bytes).map(Self::Cloud),
        }
    }

    fn stamp_ns(&self) -> i64 {
        match self {
            Self::Cloud(c) => c.header.stamp.to_ns(),
            Self::Scan(s) => s.header.stamp.to_ns(),
        }
    }

    /// Heap bytes of the points or beams, by capacity.
    fn heap_bytes(&self) -> usize {
        match self {
            Self::Cloud(c) => c.points.capacity() * size_of::<[f64; 3]>() + c.header.frame_id.capacity(),
            Self::Scan(s) => {
                (s.ranges.capacity() + s.intensities.capacity()) * size_of::<f32>() + s.header.frame_id.capacity()
            }
        }
    }

    fn stream(&self) -> Stream {
        match self {
            Self::Cloud(_) => Stream::Cloud,
            Self::Scan(_) => Stream::Scan,
        }
    }
}

#[derive(Debug)]
struct Waiting {
    msg: Decoded,
    received_ms: u64,
    deadline_ms: u64,
}

#[derive(Debug, Default)]
struct RobotSensors {
    history: PoseHistory,
    routed: Option<String>,
    waiting: VecDeque<Waiting>,
    counts: SensorCounts,
    warned: BTreeSet<DropReason>,
}

/// Where a message stands after a placement attempt.
enum Step {
    Placed(Vec<[f64; 3]>, Heights, Option<Sweep>),
    Wait(PoseLookupError, Decoded),
    Drop(DropReason, String),
}

/// The sensor pipeline of one fleet. See the module docs.
#[derive(Debug, Default)]
pub struct SensorHub {
    params: SensorParams,
    robots: HashMap<String, RobotSensors>,
}

impl SensorHub {
    /// An empty hub.
    pub fn new(params: SensorParams) -> Self {
        Self {
            params: SensorParams {
                wait_max: params.wait_max.max(1),
                ..params
            },
            robots: HashMap::new(),
        }
    }

    fn robot(&mut self, robot: &str) -> &mut RobotSensors {
        let history = self.params.history;
        self.robots.entry(robot.to_owned()).or_insert_with(|| RobotSensors {
            history: PoseHistory::new(history),
            ..RobotSensors::default()
        })
    }

    /// The site `robot`'s data feeds: its assigned plan's site, else the default site.
    pub fn site_of(&self, robot: &str) -> Option<&str> {
        self.robots
            .get(robot)
            .and_then(|r| r.routed.as_deref())
            .or(self.params.default_site.as_deref())
    }

    /// Routes `robot`'s data to `site` (its plan's site), or back to the default with `None`. Returns the
    /// effective site before and after when it changed.
    pub fn route(&mut self, robot: &str, site: Option<String>) -> Option<(Option<String>, Option<String>)> {
        let before = self.site_of(robot).map(str::to_owned);
        let r = self.robot(robot);
        r.routed = site;
        r.warned.remove(&DropReason::Unrouted);
        let after = self.site_of(robot).map(str::to_owned);
        (before != after).then_some((before, after))
    }

    /// Per-robot figures.
    pub fn counts(&self, robot: &str) -> Option<SensorCounts> {
        let r = self.robots.get(robot)?;
        Some(SensorCounts {
            site: self.site_of(robot).map(str::to_owned),
            waiting: r.waiting.len(),
            ..r.counts.clone()
        })
    }

    /// Robots with a history or a route, sorted.
    pub fn robots(&self) -> Vec<String> {
        let mut v: Vec<String> = self.robots.keys().cloned().collect();
        v.sort();
        v
    }

    /// Heap bytes held: every robot's odometry history and the messages waiting for their pose (both bounded:
    /// `history` by its span, the waiting by `wait_max` per robot). Robots' names and counters are not counted.
    pub fn memory_bytes(&self) -> usize {
        self.robots
            .values()
            .map(|r| {
                let waiting: usize = r.waiting.iter().map(|w| w.msg.heap_bytes()).sum();
                r.history.memory_bytes() + r.waiting.capacity() * size_of::<Waiting>() + waiting
            })
            .sum()
    }

    /// The robot's newest pose.
    pub fn latest_pose(&self, robot: &str) -> Option<Pose2> {
        self.robots.get(robot).and_then(|r| r.history.latest())
    }

    /// An odometry message: accepted into the history when its frame can be placed, then every waiting message
    /// it now places is released.
    pub fn odometry(&mut self, robot: &str, pose: FramedPose, now_ms: u64) -> OdomOutcome {
        let frame = pose.frame.trim_start_matches('/');
        let placeable =
            frame.is_empty() || frame == self.params.map_frame || self.params.pose_frames.iter().any(|f| f == frame);
        if !placeable {
            let detail = format!(
                "odometry in frame {frame:?}: the daemon takes poses in {:?} (zenoh.map_frame) or {:?} \
                 (zenoh.pose_frames) only",
                self.params.map_frame, self.params.pose_frames
            );
            let dropped = self.drop(robot, Stream::Odom, DropReason::Frame, detail);
            return OdomOutcome {
                rejected: Some(dropped),
                ..OdomOutcome::default()
            };
        }
        let p = pose.pose;
        if !(p.x.is_finite() && p.y.is_finite() && p.yaw.is_finite()) {
            let dropped = self.drop(robot, Stream::Odom, DropReason::Malformed, "non-finite pose".into());
            return OdomOutcome {
                rejected: Some(dropped),
                ..OdomOutcome::default()
            };
        }
        let r = self.robot(robot);
        let clock_jumped_back = r.history.push(p);
        r.warned.remove(&DropReason::Frame);
        let released = self.release(robot, now_ms, false);
        OdomOutcome {
            pose: Some(p),
            rejected: None,
            released,
            clock_jumped_back,
        }
    }

    /// A cloud ([`Stream::Cloud`], sensor_msgs/PointCloud2 CDR) or scan ([`Stream::Scan`], sensor_msgs/LaserScan
    /// CDR) received at `now_ms`: placed now, dropped, or kept waiting for its pose (then nothing is returned).
    pub fn sensor(&mut self, robot: &str, stream: Stream, bytes: &[u8], now_ms: u64) -> Vec<Outcome> {
        if let Some(unrouted) = self.unrouted(robot, stream) {
            return vec![unrouted];
        }
        match Decoded::decode(stream, bytes) {
            Ok(msg) => self.decoded(robot, msg, now_ms),
            Err(e) => vec![Outcome::Dropped(self.drop(
                robot,
                stream,
                DropReason::Malformed,
                e.to_string(),
            ))],
        }
    }

    /// The drop of a message from `robot` when the robot feeds no site (checked before decoding).
    pub fn unrouted(&mut self, robot: &str, stream: Stream) -> Option<Outcome> {
        if self.site_of(robot).is_some() {
            return None;
        }
        let detail = format!("{robot} is assigned no plan and the fleet has no default site (zenoh.site)");
        Some(Outcome::Dropped(self.drop(robot, stream, DropReason::Unrouted, detail)))
    }

    /// A message decoded by the caller ([`Decoded::decode`]) received at `now_ms`: as [`SensorHub::sensor`].
    pub fn decoded(&mut self, robot: &str, msg: Decoded, now_ms: u64) -> Vec<Outcome> {
        if let Some(unrouted) = self.unrouted(robot, msg.stream()) {
            return vec![unrouted];
        }
        let mut out = Vec::new();
        let deadline_ms = now_ms.saturating_add(self.params.wait_ms);
        let wait_max = self.params.wait_max;
        let r = self.robot(robot);
        r.waiting.push_back(Waiting {
            msg,
            received_ms: now_ms,
            deadline_ms,
        });
        if r.waiting.len() > wait_max
            && let Some(old) = r.waiting.pop_front()
        {
            let detail = format!("more than {wait_max} messages waiting for odometry");
            out.push(Outcome::Dropped(self.drop(
                robot,
                old.msg.stream(),
                DropReason::WaitFull,
                detail,
            )));
        }
        out.extend(self.release(robot, now_ms, false));
        out
    }

    /// Drops every waiting message whose deadline passed at `now_ms` (and places those that can be placed).
    pub fn expire(&mut self, now_ms: u64) -> Vec<Outcome> {
        let robots: Vec<String> = self
            .robots
            .iter()
            .filter(|(_, r)| r.waiting.front().is_some())
            .map(|(k, _)| k.clone())
            .collect();
        robots
            .into_iter()
            .flat_map(|robot| self.release(&robot, now_ms, true))
            .collect()
    }

    /// The earliest deadline of a waiting message, milliseconds.
    pub fn next_deadline_ms(&self) -> Option<u64> {
        self.robots
            .values()
            .flat_map(|r| r.waiting.iter().map(|w| w.deadline_ms))
            .min()
    }

    /// Tries every waiting message of `robot` in arrival order; with `expire`, those past their deadline that
    /// still cannot be placed are dropped.
    fn release(&mut self, robot: &str, now_ms: u64, expire: bool) -> Vec<Outcome> {
        let Some(site) = self.site_of(robot).map(str::to_owned) else {
            // Routed away while waiting: nothing waits for a site that is gone.
            let waiting = std::mem::take(&mut self.robot(robot).waiting);
            return waiting
                .into_iter()
                .map(|w| {
                    let detail = format!("{robot} feeds no site any more");
                    Outcome::Dropped(self.drop(robot, w.msg.stream(), DropReason::Unrouted, detail))
                })
                .collect();
        };
        let mut out = Vec::new();
        let waiting = std::mem::take(&mut self.robot(robot).waiting);
        let mut keep = VecDeque::new();
        for w in waiting {
            let stamp_ns = w.msg.stamp_ns();
            let stream = w.msg.stream();
            let Waiting {
                msg,
                received_ms,
                deadline_ms,
            } = w;
            // Before its deadline a message stamped after the newest pose waits for the odometry that covers it
            // (as tf2's message filter does); only then does the end pose within the tolerance stand in.
            let patient = now_ms < deadline_ms;
            match self.place(robot, msg, patient) {
                Step::Placed(points, heights, sweep) => {
                    let r = self.robot(robot);
                    r.counts.placed += 1;
                    r.counts.points += points.len() as u64;
                    r.warned.clear();
                    out.push(Outcome::Placed(Placed {
                        robot: robot.to_owned(),
                        site: site.clone(),
                        stream,
                        heights,
                        points,
                        sweep,
                        stamp_ns,
                        received_ms,
                        waited: now_ms > received_ms,
                    }));
                }
                Step::Drop(reason, detail) => out.push(Outcome::Dropped(self.drop(robot, stream, reason, detail))),
                Step::Wait(e, _) if expire && now_ms >= deadline_ms => {
                    let detail = format!("{robot}: {e} after waiting {} ms for odometry", self.params.wait_ms);
                    out.push(Outcome::Dropped(self.drop(
                        robot,
                        stream,
                        DropReason::of_lookup(e),
                        detail,
                    )));
                }
                Step::Wait(_, msg) => keep.push_back(Waiting {
                    msg,
                    received_ms,
                    deadline_ms,
                }),
            }
        }
        self.robot(robot).waiting = keep;
        out
    }

    /// Map-frame points of one message, or why it must wait or go.
    /// `patient`: a stamp after the newest pose waits rather than take the newest pose (within the tolerance).
    fn place(&self, robot: &str, msg: Decoded, patient: bool) -> Step {
        let history = self.robots.get(robot).map(|r| &r.history);
        let lookup = |stamp_ns: i64| -> Result<Pose2, PoseLookupError> {
            let h = history.ok_or(PoseLookupError::Empty)?;
            if stamp_ns == 0 {
                // Unstamped: the latest pose is the best there is.
                return h.latest().ok_or(PoseLookupError::Empty);
            }
            match h.latest() {
                Some(newest) if patient && stamp_ns > newest.stamp_ns => Err(PoseLookupError::Future {
                    ahead_ns: stamp_ns - newest.stamp_ns,
                }),
                _ => h.at(stamp_ns),
            }
        };
        match msg {
            Decoded::Cloud(c) => {
                let frame = c.header.frame_id.trim_start_matches('/');
                if frame.is_empty() || frame == self.params.map_frame {
                    return Step::Placed(c.points, Heights::MapFrame, None);
                }
                match lookup(c.header.stamp.to_ns()) {
                    Ok(pose) => Step::Placed(robot_to_map(&c.points, pose), Heights::OverGround, None),
                    // Older than the history: the latest pose is closer than nothing (a cloud's points are
                    // obstacles for a while; a scan's are not worth a wrong place).
                    Err(PoseLookupError::TooOld { .. }) => match history.and_then(PoseHistory::latest) {
                        Some(pose) => Step::Placed(robot_to_map(&c.points, pose), Heights::OverGround, None),
                        None => Step::Wait(PoseLookupError::Empty, Decoded::Cloud(c)),
                    },
                    Err(e) => Step::Wait(e, Decoded::Cloud(c)),
                }
            }
            Decoded::Scan(s) => match lookup(s.header.stamp.to_ns()) {
                Ok(pose) => Step::Placed(
                    scan_to_map(&s, pose, self.params.scan_offset),
                    Heights::Planar,
                    Sweep::of_scan(&s, pose, self.params.scan_offset),
                ),
                Err(e @ PoseLookupError::TooOld { .. }) => Step::Drop(DropReason::TooOld, format!("{robot}: {e}")),
                Err(e) => Step::Wait(e, Decoded::Scan(s)),
            },
        }
    }

    /// Counts a drop decided outside the hub (the daemon's queues, a site without a map) in the robot's figures.
    pub fn record_drop(&mut self, robot: &str, stream: Stream, reason: DropReason, detail: String) -> Dropped {
        self.drop(robot, stream, reason, detail)
    }

    fn drop(&mut self, robot: &str, stream: Stream, reason: DropReason, detail: String) -> Dropped {
        let r = self.robot(robot);
        *r.counts.dropped.entry(reason.as_str().to_owned()).or_default() += 1;
        r.counts.last_drop = Some(detail.clone());
        let first = r.warned.insert(reason);
        Dropped {
            robot: robot.to_owned(),
            stream,
            reason,
            detail,
            first,
        }
    }
}

#[cfg(test)]
mod tests;
