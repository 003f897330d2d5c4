//! The robot registry: who is alive (liveliness tokens, or messages for ROS 2 robots), where each robot last was
//! (odometry), which plan it drives and how far along it is ([`crate::progress`]), which site its sensor data
//! feeds, and the bookkeeping of its path checks.

use std::collections::BTreeMap;

pub use crate::progress::Assignment;

/// A planar pose in the map frame. In recordings non-finite numbers are kept as strings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pose2 {
    /// x, metres.
    #[serde(with = "crate::lossless_f64")]
    pub x: f64,
    /// y, metres.
    #[serde(with = "crate::lossless_f64")]
    pub y: f64,
    /// Heading, radians, counter-clockwise from +x.
    #[serde(with = "crate::lossless_f64")]
    pub yaw: f64,
    /// Stamp, nanoseconds (robot clock).
    pub stamp_ns: i64,
}

/// One robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    /// Robot id (as in its Zenoh keys).
    pub id: String,
    /// Its liveliness token is present.
    pub alive: bool,
    /// Its token was present and went away (not merely never seen).
    pub gone: bool,
    /// Last pose.
    pub pose: Option<Pose2>,
    /// Last message or liveliness change, milliseconds since the Unix epoch.
    pub last_seen_ms: u64,
    /// The plan it drives.
    pub assignment: Option<Assignment>,
    /// When it got that plan (or the daemon restored it), milliseconds since the Unix epoch.
    pub assigned_ms: u64,
    /// Path watching (Circular Judgment) bookkeeping.
    pub watch: WatchState,
    /// The last correction sent to it.
    pub last_correction: Option<shift_proto::LastCorrection>,
}

/// When a robot's path was last checked and whether a check is running.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WatchState {
    /// A check job is running.
    pub in_flight: bool,
    /// Something changed while it ran: check again when it ends.
    pub pending: bool,
    /// Last check started, milliseconds since the Unix epoch (0 = never).
    pub last_check_ms: u64,
    /// Since when checks have proposed to end the plan at a blockage, milliseconds (see
    /// [`crate::watch::WatchParams::end_hold_s`]).
    pub end_proposed_since_ms: Option<u64>,
}

/// Every robot seen, by id.
#[derive(Debug, Default, Clone)]
pub struct Robots {
    robots: BTreeMap<String, Robot>,
}

impl Robots {
    /// The robot, created on first sight.
    pub fn entry(&mut self, id: &str, now_ms: u64) -> &mut Robot {
        self.robots.entry(id.to_owned()).or_insert_with(|| Robot {
            id: id.to_owned(),
            alive: false,
            gone: false,
            pose: None,
            last_seen_ms: now_ms,
            assignment: None,
            assigned_ms: now_ms,
            watch: WatchState::default(),
            last_correction: None,
        })
    }

    /// A robot.
    pub fn get(&self, id: &str) -> Option<&Robot> {
        self.robots.get(id)
    }

    /// Every robot.
    pub fn iter(&self) -> impl Iterator<Item = &Robot> {
        self.robots.values()
    }

    /// Every robot, mutably.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut Robot> {
        self.robots.values_mut()
    }

    /// A robot, mutably.
    pub fn get_mut(&mut self, id: &str) -> Option<&mut Robot> {
        self.robots.get_mut(id)
    }
}
