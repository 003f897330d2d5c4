//! A short history of one robot's planar poses (from its odometry), so a sensor reading can be placed with the
//! pose at its own stamp rather than the latest one: linear in x and y, along the shorter arc in yaw. Pure: the
//! caller feeds poses and asks at stamps, both on the robot's clock.

use std::collections::VecDeque;

use crate::robots::Pose2;

/// How long and how much history to keep, and how far outside it a stamp may fall.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoseHistoryParams {
    /// Poses older than the newest by more than this are forgotten, nanoseconds.
    pub span_ns: i64,
    /// Most poses kept (older ones go first).
    pub max_poses: usize,
    /// A stamp at most this far after the newest pose (or before the oldest) takes that end pose, nanoseconds.
    pub tolerance_ns: i64,
}

impl Default for PoseHistoryParams {
    fn default() -> Self {
        Self {
            span_ns: 5_000_000_000,
            max_poses: 512,
            tolerance_ns: 100_000_000,
        }
    }
}

/// Why no pose could be given for a stamp.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PoseLookupError {
    /// No odometry yet.
    #[error("no odometry from this robot yet")]
    Empty,
    /// The stamp is older than the history (beyond the tolerance).
    #[error("stamp {behind_ns} ns older than the oldest pose kept")]
    TooOld {
        /// How far before the oldest pose, nanoseconds.
        behind_ns: i64,
    },
    /// The stamp is newer than the newest pose (beyond the tolerance): no extrapolation.
    #[error("stamp {ahead_ns} ns newer than the newest pose")]
    Future {
        /// How far after the newest pose, nanoseconds.
        ahead_ns: i64,
    },
}

impl PoseLookupError {
    /// Metric label: `no_pose`, `too_old` or `future`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Empty => "no_pose",
            Self::TooOld { .. } => "too_old",
            Self::Future { .. } => "future",
        }
    }
}

/// Poses of one robot ordered by stamp (map frame; stamps on the robot's clock, nanoseconds).
#[derive(Debug, Clone, Default)]
pub struct PoseHistory {
    params: PoseHistoryParams,
    poses: VecDeque<Pose2>,
}

/// `a` wrapped into (−π, π].
fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

impl PoseHistory {
    /// Heap bytes held (the poses kept, by capacity).
    pub fn memory_bytes(&self) -> usize {
        self.poses.capacity() * size_of::<Pose2>()
    }

    /// An empty history.
    pub fn new(params: PoseHistoryParams) -> Self {
        Self {
            params,
            poses: VecDeque::new(),
        }
    }

    /// Poses held.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// True before the first pose.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// The newest pose.
    pub fn latest(&self) -> Option<Pose2> {
        self.poses.back().copied()
    }

    /// Adds a pose (out-of-order stamps are placed in order; an equal stamp replaces the pose held). Poses with
    /// a non-finite coordinate are ignored. A stamp older than the newest by more than the span is no late
    /// sample but the robot's clock jumping back (a restart, a clock reset, a replayed log): the history is
    /// cleared and starts again from this pose, as ROS's tf buffer does; returns true then.
    pub fn push(&mut self, pose: Pose2) -> bool {
        if !(pose.x.is_finite() && pose.y.is_finite() && pose.yaw.is_finite()) {
            return false;
        }
        let jumped_back = self
            .poses
            .back()
            .is_some_and(|last| last.stamp_ns.saturating_sub(pose.stamp_ns) > self.params.span_ns);
        if jumped_back {
            self.poses.clear();
        }
        match self.poses.back() {
            Some(last) if pose.stamp_ns < last.stamp_ns => {
                match self.poses.binary_search_by_key(&pose.stamp_ns, |p| p.stamp_ns) {
                    Ok(i) => self.poses[i] = pose,
                    Err(i) => self.poses.insert(i, pose),
                }
            }
            Some(last) if pose.stamp_ns == last.stamp_ns => {
                if let Some(l) = self.poses.back_mut() {
                    *l = pose;
                }
            }
            _ => self.poses.push_back(pose),
        }
        let newest = self.poses.back().map_or(pose.stamp_ns, |p| p.stamp_ns);
        while self.poses.len() > self.params.max_poses.max(2)
            || self
                .poses
                .front()
                .is_some_and(|p| newest.saturating_sub(p.stamp_ns) > self.params.span_ns && self.poses.len() > 2)
        {
            self.poses.pop_front();
        }
        jumped_back
    }

    /// The pose at `stamp_ns`: interpolated between the two poses around it (x, y linearly, yaw along the shorter
    /// arc, wrapped into (−π, π]); the end pose within the tolerance outside the history; an error beyond.
    pub fn at(&self, stamp_ns: i64) -> Result<Pose2, PoseLookupError> {
        let (Some(first), Some(last)) = (self.poses.front(), self.poses.back()) else {
            return Err(PoseLookupError::Empty);
        };
        let tol = self.params.tolerance_ns;
        if stamp_ns >= last.stamp_ns {
            let ahead_ns = stamp_ns.saturating_sub(last.stamp_ns);
            return if ahead_ns <= tol {
                Ok(Pose2 { stamp_ns, ..*last })
            } else {
                Err(PoseLookupError::Future { ahead_ns })
            };
        }
        if stamp_ns <= first.stamp_ns {
            let behind_ns = first.stamp_ns.saturating_sub(stamp_ns);
            return if behind_ns <= tol {
                Ok(Pose2 { stamp_ns, ..*first })
            } else {
                Err(PoseLookupError::TooOld { behind_ns })
            };
        }
        // first < stamp < last: the first pose at or after the stamp has a predecessor.
        let i = self.poses.partition_point(|p| p.stamp_ns < stamp_ns);
        let (a, b) = (self.poses[i - 1], self.poses[i]);
        let span = (b.stamp_ns - a.stamp_ns) as f64;
        let t = if span > 0.0 {
            (stamp_ns - a.stamp_ns) as f64 / span
        } else {
            1.0
        };
        Ok(Pose2 {
            x: a.x + t * (b.x - a.x),
            y: a.y + t * (b.y - a.y),
            yaw: wrap(a.yaw + t * wrap(b.yaw - a.yaw)),
            stamp_ns,
        })
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    fn pose(x: f64, y: f64, yaw: f64, stamp_ms: i64) -> Pose2 {
        Pose2 {
            x,
            y,
            yaw,
            stamp_ns: stamp_ms * 1_000_000,
        }
    }

    fn history() -> PoseHistory {
        PoseHistory::new(PoseHistoryParams {
            span_ns: 1_000_000_000,
            max_poses: 8,
            tolerance_ns: 50_000_000,
        })
    }

    #[test]
    fn interpolates_position_and_yaw_across_the_wrap() {
        let mut h = history();
        h.push(pose(0.0, 0.0, 0.0, 0));
        h.push(pose(1.0, 2.0, PI / 2.0, 100));
        // Out of order: placed between.
        h.push(pose(10.0, 10.0, 3.0, 300));
        h.push(pose(3.0, 2.0, -3.0, 400)); // 3.0 → −3.0 is +0.283 rad through π, not −6 rad
        let p = h.at(50_000_000).expect("inside");
        assert!((p.x - 0.5).abs() < 1e-12 && (p.y - 1.0).abs() < 1e-12, "{p:?}");
        assert!((p.yaw - PI / 4.0).abs() < 1e-12, "{p:?}");
        let p = h.at(350_000_000).expect("inside");
        assert!((p.x - 6.5).abs() < 1e-12 && (p.y - 6.0).abs() < 1e-12, "{p:?}");
        let mid = 3.0 + (2.0 * PI - 6.0) / 2.0; // half of the short arc from 3.0
        assert!((p.yaw - wrap(mid)).abs() < 1e-12, "{} vs {}", p.yaw, wrap(mid));
        assert!(p.yaw.abs() > 3.0, "went the long way: {}", p.yaw);
        // Exact stamps give the pose itself.
        assert_eq!(h.at(100_000_000).map(|p| p.x), Ok(1.0));
    }

    #[test]
    fn out_of_order_pose_lands_in_order() {
        let mut h = history();
        h.push(pose(0.0, 0.0, 0.0, 0));
        h.push(pose(2.0, 0.0, 0.0, 200));
        h.push(pose(5.0, 0.0, 0.0, 100));
        assert_eq!(h.len(), 3);
        assert!((h.at(150_000_000).expect("inside").x - 3.5).abs() < 1e-12);
        assert_eq!(h.latest().map(|p| p.x), Some(2.0));
    }

    #[test]
    fn outside_the_history_within_tolerance_takes_the_end_pose_beyond_is_an_error() {
        let mut h = history();
        assert_eq!(h.at(0), Err(PoseLookupError::Empty));
        h.push(pose(1.0, 0.0, 0.0, 1000));
        h.push(pose(2.0, 0.0, 0.0, 1100));
        assert_eq!(h.at(1_140_000_000).map(|p| p.x), Ok(2.0));
        assert_eq!(h.at(960_000_000).map(|p| p.x), Ok(1.0));
        assert_eq!(
            h.at(1_200_000_000),
            Err(PoseLookupError::Future { ahead_ns: 100_000_000 })
        );
        assert_eq!(
            h.at(900_000_000),
            Err(PoseLookupError::TooOld { behind_ns: 100_000_000 })
        );
        assert_eq!(h.at(900_000_000).map_err(|e| e.kind()), Err("too_old"));
    }

    #[test]
    fn a_clock_jumping_back_starts_the_history_again() {
        let mut h = history();
        for i in 0..50 {
            assert!(!h.push(pose(f64::from(i), 0.0, 0.0, 1_000_000 + i64::from(i) * 100)));
        }
        // A late sample inside the span is placed in order; a stamp a whole span older is a restarted clock.
        assert!(!h.push(pose(-1.0, 0.0, 0.0, 1_004_550)));
        assert!(h.push(pose(7.0, 7.0, 0.0, 2_000)));
        assert_eq!(h.len(), 1);
        let p = h.at(2_000 * 1_000_000).expect("the new clock's pose");
        assert_eq!((p.x, p.y), (7.0, 7.0));
        assert!(!h.push(pose(7.5, 7.0, 0.0, 2_100)));
        assert_eq!(h.len(), 2);
    }

    #[test]
    fn span_and_count_bound_the_history() {
        let mut h = history();
        for i in 0..20 {
            h.push(pose(i as f64, 0.0, 0.0, i * 100));
        }
        assert_eq!(h.len(), 8, "count cap");
        let mut h = history();
        h.push(pose(0.0, 0.0, 0.0, 0));
        h.push(pose(1.0, 0.0, 0.0, 500));
        h.push(pose(2.0, 0.0, 0.0, 2000));
        assert_eq!(h.len(), 2, "older than 1 s before the newest goes, but two are kept");
        assert!(matches!(h.at(100_000_000), Err(PoseLookupError::TooOld { .. })));
        h.push(pose(f64::NAN, 0.0, 0.0, 2100));
        assert_eq!(h.len(), 2, "non-finite ignored");
    }
}
