//! How far a robot is along its plan, from its odometry alone.
//!
//! Normal driving: among the path's segments from the last waypoint reached on (the next `window`), those within
//! `tolerance_m` of the pose on the first pass of the path by it (a path that passes the same place twice is
//! followed in order), and of them the nearest; the waypoint reached is that segment's end when it is the
//! nearer end and lies within the tolerance, else its start. Where several of that pass are equally near (a lane's end and the next lane, closer
//! than the tolerance), the one whose path direction agrees with the robot's heading wins.
//!
//! Re-acquisition: a robot that joins late, was carried, relocalised or drove on while the daemon restarted is
//! not near the expected waypoint. Then the whole plan is searched through a grid index over the waypoints (built
//! on first need, not per odometry message): among waypoints within the tolerance that agree with the heading,
//! the nearest; among near-equals the first ahead of the last one reached. Progress never moves backwards over
//! driven ground unless only earlier waypoints fit for [`ProgressParams::back_confirm`] poses in a row: the robot
//! really went back, and the caller records the jump.

use std::collections::HashMap;
use std::sync::Arc;

use shift_planner::geom::{Point2, point_segment_distance};
use shift_proto::PlanDocument;

/// Tolerances of progress tracking.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProgressParams {
    /// A pose within this distance of a waypoint reaches it, metres.
    pub tolerance_m: f64,
    /// Waypoints searched ahead of the last one reached before the whole plan is searched.
    pub window: usize,
    /// Consecutive poses that fit only behind the last waypoint reached before progress moves back.
    pub back_confirm: u32,
}

impl Default for ProgressParams {
    fn default() -> Self {
        Self {
            tolerance_m: 0.5,
            window: 200,
            back_confirm: 3,
        }
    }
}

/// Candidates closer than the nearest plus this count as equally near, metres.
const NEAR_TIE_M: f64 = 0.05;
/// A waypoint whose path direction is within this angle of the robot's heading agrees with it (cos 60°).
const HEADING_COS: f64 = 0.5;

/// What one pose did to the progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Advance {
    /// Nothing.
    Stayed,
    /// Moved ahead within the window.
    Forward,
    /// Found elsewhere on the plan by the whole-plan search.
    Reacquired {
        /// Waypoint index before.
        from: usize,
        /// Waypoint index now.
        to: usize,
    },
}

/// Waypoint indices bucketed by a square cell of the tolerance's size.
#[derive(Debug, Clone, PartialEq)]
struct WaypointGrid {
    cell_m: f64,
    cells: HashMap<(i64, i64), Vec<u32>>,
}

impl WaypointGrid {
    fn new(doc: &PlanDocument, cell_m: f64) -> Self {
        let mut cells: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
        for (i, w) in doc.waypoints.iter().enumerate() {
            if let Some(key) = Self::key(w.x, w.y, cell_m) {
                cells.entry(key).or_default().push(i as u32);
            }
        }
        Self { cell_m, cells }
    }

    fn key(x: f64, y: f64, cell_m: f64) -> Option<(i64, i64)> {
        let (cx, cy) = ((x / cell_m).floor(), (y / cell_m).floor());
        (cx.is_finite() && cy.is_finite() && cx.abs() < 1e15 && cy.abs() < 1e15).then_some((cx as i64, cy as i64))
    }

    /// Indices of waypoints in the 3 × 3 cells around `(x, y)` (a superset of those within one cell size).
    fn around(&self, x: f64, y: f64) -> impl Iterator<Item = usize> + '_ {
        let key = Self::key(x, y, self.cell_m);
        key.into_iter()
            .flat_map(|(cx, cy)| (-1..=1).flat_map(move |dx| (-1..=1).map(move |dy| (cx + dx, cy + dy))))
            .filter_map(|k| self.cells.get(&k))
            .flatten()
            .map(|&i| i as usize)
    }
}

/// A robot's progress along the plan it drives.
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
    /// Consecutive poses that fit only behind `index`.
    behind: u32,
    grid: Option<WaypointGrid>,
    /// A plan replaced under a driving robot (a replan): until the robot is seen near the path's start, its
    /// poses are those of the old plan it still drives, and must not be searched for on the new one (the
    /// new one covers the old one's rest, so they would match far ahead, even at its end).
    pub await_start: bool,
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
            behind: 0,
            grid: None,
            await_start: false,
        }
    }

    /// Metres driven along the plan.
    pub fn driven_m(&self) -> f64 {
        self.arc_m.get(self.index).copied().unwrap_or(0.0)
    }

    /// Metres along the plan at waypoint `i`.
    pub fn arc_at(&self, i: usize) -> f64 {
        self.arc_m.get(i).copied().unwrap_or(0.0)
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

    /// Unit direction of the path at waypoint `i` (towards the next one; the last one looks back).
    fn direction(&self, i: usize) -> Option<(f64, f64)> {
        let w = &self.doc.waypoints;
        let (a, b) = if i + 1 < w.len() {
            (i, i + 1)
        } else {
            (i.checked_sub(1)?, i)
        };
        let (dx, dy) = (w[b].x - w[a].x, w[b].y - w[a].y);
        let n = dx.hypot(dy);
        (n > 1e-9).then(|| (dx / n, dy / n))
    }

    /// Of `candidates` (index, distance), those whose path direction agrees with `heading` (radians) when any
    /// does, else all of them.
    fn agreeing(&self, candidates: Vec<(usize, f64)>, heading: Option<f64>) -> Vec<(usize, f64)> {
        let Some(h) = heading.filter(|h| h.is_finite()) else {
            return candidates;
        };
        let (hs, hc) = h.sin_cos();
        let agree: Vec<(usize, f64)> = candidates
            .iter()
            .copied()
            .filter(|&(i, _)| {
                self.direction(i)
                    .is_none_or(|(dx, dy)| dx * hc + dy * hs >= HEADING_COS)
            })
            .collect();
        if agree.is_empty() { candidates } else { agree }
    }

    /// How near `(x, y)` is to the path's segment from waypoint `i` (waypoint `i` alone when it is the last
    /// before `end`, the searched window's end), and the
    /// waypoint it has reached there: the segment's end when that is the nearer end and within `tol` (a
    /// waypoint within the tolerance is reached), else its start. Segments, not waypoints: a detour's few waypoints lie metres
    /// apart, and a robot between two of them is on its path, not near another pass of it.
    fn by_segment(&self, i: usize, end: usize, x: f64, y: f64, tol: f64) -> (usize, f64) {
        let w = &self.doc.waypoints;
        let (here, a) = (Point2::new(x, y), Point2::new(w[i].x, w[i].y));
        let Some(b) = w[..end].get(i + 1).map(|b| Point2::new(b.x, b.y)) else {
            return (i, (a - here).norm());
        };
        let d = point_segment_distance(here, a, b);
        let (da, db) = ((a - here).norm(), (b - here).norm());
        let reached = if db < da && db <= tol { i + 1 } else { i };
        (reached, d)
    }

    /// Of `candidates` (index ascending, each within `tol` of one pose), those of the first pass of the path
    /// by the pose: a later pass starts where the path between two candidates is longer than `2 tol`, i.e. it
    /// left the pose's neighbourhood and came back. A plan that passes a place twice is driven in order, so a
    /// robot near both passes is on the first one it has not driven, whatever its heading says (a robot
    /// turning on the spot at its dock faces a lane that passes the dock later).
    fn first_pass(&self, candidates: Vec<(usize, f64)>, tol: f64) -> Vec<(usize, f64)> {
        let mut pass = Vec::with_capacity(candidates.len());
        for c in candidates {
            if let Some(&(prev, _)) = pass.last()
                && self.arc_at(c.0) - self.arc_at(prev) > 2.0 * tol
            {
                break;
            }
            pass.push(c);
        }
        pass
    }

    /// Updates the progress from a pose at `(x, y)` moving along `heading` (radians, map frame; `None` when
    /// unknown). See the module docs.
    pub fn advance(&mut self, x: f64, y: f64, heading: Option<f64>, params: &ProgressParams) -> Advance {
        if !(x.is_finite() && y.is_finite()) {
            return Advance::Stayed;
        }
        let tol = params.tolerance_m;
        let w = &self.doc.waypoints;
        let end = self.index.saturating_add(params.window).saturating_add(1).min(w.len());
        let local: Vec<(usize, f64)> = (self.index..end)
            .map(|i| self.by_segment(i, end, x, y, tol))
            .filter(|&(_, d)| d <= tol)
            .collect();
        if self.await_start {
            if local.is_empty() {
                return Advance::Stayed;
            }
            self.await_start = false;
        }
        if !local.is_empty() {
            self.behind = 0;
            // The first pass ahead, then its nearest waypoint, ties to the earlier one.
            let pass = self.first_pass(local, tol);
            let best = self
                .agreeing(pass, heading)
                .into_iter()
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            return match best {
                Some((i, _)) if i > self.index => {
                    self.index = i;
                    Advance::Forward
                }
                _ => Advance::Stayed,
            };
        }
        self.reacquire(x, y, heading, params)
    }

    /// The whole-plan search.
    fn reacquire(&mut self, x: f64, y: f64, heading: Option<f64>, params: &ProgressParams) -> Advance {
        let tol = params.tolerance_m;
        let cell_m = tol.max(0.05);
        if self.grid.as_ref().is_none_or(|g| g.cell_m != cell_m) {
            self.grid = Some(WaypointGrid::new(&self.doc, cell_m));
        }
        let Some(grid) = &self.grid else { return Advance::Stayed };
        let w = &self.doc.waypoints;
        let near: Vec<(usize, f64)> = grid
            .around(x, y)
            .map(|i| (i, (w[i].x - x).hypot(w[i].y - y)))
            .filter(|&(_, d)| d <= tol)
            .collect();
        let near = self.agreeing(near, heading);
        let Some(nearest) = near.iter().map(|c| c.1).min_by(f64::total_cmp) else {
            self.behind = 0;
            return Advance::Stayed;
        };
        let ties: Vec<usize> = near
            .iter()
            .filter(|c| c.1 <= nearest + NEAR_TIE_M)
            .map(|c| c.0)
            .collect();
        let from = self.index;
        if let Some(&ahead) = ties.iter().filter(|&&i| i > from).min() {
            self.behind = 0;
            self.index = ahead;
            return Advance::Reacquired { from, to: ahead };
        }
        let Some(&back) = ties.iter().filter(|&&i| i < from).max() else {
            return Advance::Stayed; // at the waypoint reached already
        };
        self.behind += 1;
        if self.behind < params.back_confirm {
            return Advance::Stayed;
        }
        self.behind = 0;
        self.index = back;
        Advance::Reacquired { from, to: back }
    }
}

#[cfg(test)]
mod tests;
