//! The robot registry: who is alive (liveliness tokens), where each robot last was (odometry), which plan it
//! drives and how far along it is. Progress is the nearest waypoint ahead of the last matched one, searched in a
//! short window so a path that passes the same place twice is followed in order.

use std::collections::BTreeMap;
use std::sync::Arc;

use shift_proto::PlanDocument;

/// A planar pose in the map frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose2 {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians, counter-clockwise from +x.
    pub yaw: f64,
    /// Stamp, nanoseconds (robot clock).
    pub stamp_ns: i64,
}

/// How far a robot is along its plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    /// Plan id.
    pub plan_id: String,
    /// The plan being driven.
    pub doc: Arc<PlanDocument>,
    /// Cumulative arc length at each waypoint, metres.
    pub arc_m: Vec<f64>,
    /// Index of the last waypoint reached.
    pub index: usize,
}

impl Assignment {
    /// Starts at the first waypoint.
    pub fn new(plan_id: String, doc: Arc<PlanDocument>) -> Self {
        let mut arc_m = Vec::with_capacity(doc.waypoints.len());
        let mut s = 0.0;
        for (i, w) in doc.waypoints.iter().enumerate() {
            if i > 0 {
                let p = &doc.waypoints[i - 1];
                s += (w.x - p.x).hypot(w.y - p.y);
            }
            arc_m.push(s);
        }
        Self {
            plan_id,
            doc,
            arc_m,
            index: 0,
        }
    }

    /// Metres driven along the plan.
    pub fn driven_m(&self) -> f64 {
        self.arc_m.get(self.index).copied().unwrap_or(0.0)
    }

    /// Fraction of the plan's length driven, 0–1.
    pub fn fraction(&self) -> f64 {
        let total = self.arc_m.last().copied().unwrap_or(0.0);
        if total > 0.0 { self.driven_m() / total } else { 1.0 }
    }

    /// Drives the corrected document from now on: the arc lengths are recomputed and the reached index is
    /// moved past the patch (`waypoints[from..to)` replaced by `inserted` waypoints). A robot inside the
    /// replaced stretch continues from the waypoint before it.
    pub fn corrected(&mut self, doc: Arc<PlanDocument>, from: usize, to: usize, inserted: usize) {
        let index = if self.index >= to {
            self.index - (to - from) + inserted
        } else if self.index >= from {
            from.saturating_sub(1)
        } else {
            self.index
        };
        let plan_id = std::mem::take(&mut self.plan_id);
        *self = Self::new(plan_id, doc);
        self.index = index.min(self.doc.waypoints.len().saturating_sub(1));
    }

    /// True once the last waypoint is reached.
    pub fn finished(&self) -> bool {
        self.index + 1 >= self.doc.waypoints.len()
    }

    /// Advances to the nearest waypoint within `tolerance_m` of `(x, y)` among the next `window` waypoints.
    /// Returns true when the index moved.
    pub fn advance(&mut self, x: f64, y: f64, tolerance_m: f64, window: usize) -> bool {
        let w = &self.doc.waypoints;
        let end = (self.index + window + 1).min(w.len());
        let mut best: Option<(usize, f64)> = None;
        for (i, p) in w.iter().enumerate().take(end).skip(self.index) {
            let d = (p.x - x).hypot(p.y - y);
            if d <= tolerance_m && best.is_none_or(|(_, bd)| d < bd + 1e-12) {
                best = Some((i, d));
            }
        }
        match best {
            Some((i, _)) if i > self.index => {
                self.index = i;
                true
            }
            _ => false,
        }
    }
}

/// One robot.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    /// Robot id (as in its Zenoh keys).
    pub id: String,
    /// Its liveliness token is present.
    pub alive: bool,
    /// Last pose.
    pub pose: Option<Pose2>,
    /// Last message or liveliness change, milliseconds since the Unix epoch.
    pub last_seen_ms: u64,
    /// The plan it drives.
    pub assignment: Option<Assignment>,
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
}

/// Every robot seen, by id.
#[derive(Debug, Default)]
pub struct Robots {
    robots: BTreeMap<String, Robot>,
}

impl Robots {
    /// The robot, created on first sight.
    pub fn entry(&mut self, id: &str, now_ms: u64) -> &mut Robot {
        self.robots.entry(id.to_owned()).or_insert_with(|| Robot {
            id: id.to_owned(),
            alive: false,
            pose: None,
            last_seen_ms: now_ms,
            assignment: None,
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

#[cfg(test)]
mod tests {
    use shift_proto::{PlanMetricsDoc, WaypointDoc, WaypointKindDoc};

    use super::*;

    fn doc(points: &[(f64, f64)]) -> Arc<PlanDocument> {
        Arc::new(PlanDocument {
            plan_id: "p-1".into(),
            version: 1,
            frame: "map".into(),
            waypoints: points
                .iter()
                .map(|&(x, y)| WaypointDoc {
                    x,
                    y,
                    z: 0.0,
                    v: 0.5,
                    t: 0.0,
                    kind: WaypointKindDoc::Cover,
                    region: None,
                })
                .collect(),
            regions: vec![],
            metrics: PlanMetricsDoc::default(),
        })
    }

    #[test]
    fn progress_follows_the_path_in_order_even_where_it_crosses_itself() {
        // Out along y = 0 and back along the same line.
        let pts = [
            (0.0, 0.0),
            (1.0, 0.0),
            (2.0, 0.0),
            (3.0, 0.0),
            (2.0, 0.0),
            (1.0, 0.0),
            (0.0, 0.0),
        ];
        let mut a = Assignment::new("p-1".into(), doc(&pts));
        assert!(a.advance(1.0, 0.05, 0.3, 2));
        assert_eq!(a.index, 1, "the outbound (1,0), not the return one");
        assert!(a.advance(2.9, 0.0, 0.3, 2));
        assert_eq!(a.index, 3);
        assert!((a.fraction() - 0.5).abs() < 1e-12);
        assert!(!a.advance(10.0, 10.0, 0.3, 2), "far away: no progress");
        a.advance(1.0, 0.0, 0.3, 2);
        a.advance(0.0, 0.0, 0.3, 2);
        assert!(a.finished());
        assert!((a.driven_m() - 6.0).abs() < 1e-12);
    }

    #[test]
    fn a_correction_moves_the_reached_index_past_the_patch() {
        let pts: Vec<(f64, f64)> = (0..6).map(|i| (i as f64, 0.0)).collect();
        let mut a = Assignment::new("p-1".into(), doc(&pts));
        a.index = 4;
        // waypoints[1..3) (two) replaced by three.
        let new: Vec<(f64, f64)> = vec![
            (0.0, 0.0),
            (0.5, 0.5),
            (1.0, 0.6),
            (1.5, 0.5),
            (3.0, 0.0),
            (4.0, 0.0),
            (5.0, 0.0),
        ];
        a.corrected(doc(&new), 1, 3, 3);
        assert_eq!(a.index, 5, "still at (4, 0)");
        assert_eq!(a.doc.waypoints[a.index].x, 4.0);
        assert_eq!(a.plan_id, "p-1");
        // Inside the patch: back to the waypoint before it.
        a.index = 2;
        a.corrected(doc(&new), 2, 4, 1);
        assert_eq!(a.index, 1);
        // Before it: unchanged.
        a.index = 0;
        a.corrected(doc(&new), 2, 4, 1);
        assert_eq!(a.index, 0);
    }
}
