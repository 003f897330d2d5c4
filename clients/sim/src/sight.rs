//! Correction latency as a robot lives it, sans-IO: from the first scan that shows something the site's map
//! does not hold across the robot's path inside the daemon's watch window, to the next correction the robot
//! applies. Measured by the simulator on its own clock (wall time), independently of what the daemon reports.
//!
//! "Across the path" is what the daemon must correct whatever its cost threshold (seed 000 Alg. 1 counts any
//! collision as a breach): a return closer than the robot's radius to a path point that lies within
//! `window_radius` of the robot — the body would touch it. A return only inside the clearance margin may be
//! judged harmless (its path cost under J_th), so it starts no clock. Returns on cells the static map already
//! marks occupied (or next to them, for the laser's spread) are not news. A sight that no
//! correction follows within [`SightClock::patience_s`] is counted as unanswered and forgotten (a mover that
//! walked on, an obstacle the daemon judged harmless, or a correction that never came).

use shift_planner::geom::Point2;
use shift_planner::map::OccupancyGrid;

/// The daemon's watch window the sight test mirrors (its default: `[watch] window_radius_m` of shiftd's config).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WatchWindow {
    /// Radius of the detection window round the robot, metres.
    pub window_radius_m: f64,
}

impl Default for WatchWindow {
    fn default() -> Self {
        Self { window_radius_m: 3.0 }
    }
}

/// The first of `seen` (map frame) that is new to `map` and lies across `path` (the waypoints from the robot's
/// target on) inside the window round `robot`, if any.
pub fn news_on_path(
    seen: &[Point2],
    path: &[Point2],
    robot: Point2,
    radius_m: f64,
    window: WatchWindow,
    map: &OccupancyGrid,
) -> Option<Point2> {
    let ahead: Vec<Point2> = path
        .iter()
        .copied()
        .take_while(|p| (*p - robot).norm() <= window.window_radius_m)
        .collect();
    if ahead.is_empty() {
        return None;
    }
    seen.iter().copied().find(|p| {
        (*p - robot).norm() <= window.window_radius_m + radius_m
            && ahead.iter().any(|q| (*p - *q).norm() < radius_m)
            && !near_known(map, *p)
    })
}

/// True when `p` falls on or next to a cell the map does not call free (or off the map).
pub fn near_known(map: &OccupancyGrid, p: Point2) -> bool {
    let g = map.geometry;
    (-1..=1).any(|dy| {
        (-1..=1).any(|dx| {
            let q = Point2::new(p.x + f64::from(dx) * g.resolution, p.y + f64::from(dy) * g.resolution);
            g.locate(q).is_none_or(|c| !map.is_free(g.index(c)))
        })
    })
}

/// One robot's pending sight and the latencies measured so far.
#[derive(Debug, Clone, PartialEq)]
pub struct SightClock {
    /// How long a sight waits for its correction, wall seconds.
    pub patience_s: f64,
    pending: Option<f64>,
    /// Sight → correction, milliseconds, in the order measured.
    pub latencies_ms: Vec<f64>,
    /// Sights no correction followed within `patience_s`.
    pub unanswered: u64,
    /// Sights the daemon answered by holding the plan's end (status `blocked`: the path is blocked to its end
    /// and the end is held in case the blockage moves on), after this long, milliseconds.
    pub held_ms: Vec<f64>,
}

impl SightClock {
    /// A clock whose sights wait `patience_s` wall seconds.
    pub fn new(patience_s: f64) -> Self {
        Self {
            patience_s,
            pending: None,
            latencies_ms: Vec::new(),
            unanswered: 0,
            held_ms: Vec::new(),
        }
    }

    /// The daemon said at wall time `now_s` that it holds the plan's end at a blockage: a deliberate answer
    /// (the robot waits), not a correction; counted apart from the latencies.
    pub fn on_held(&mut self, now_s: f64) {
        self.expire(now_s);
        if let Some(t0) = self.pending.take() {
            self.held_ms.push((now_s - t0) * 1e3);
        }
    }

    /// A scan published at wall time `now_s` did (`news`) or did not show news on the path; true when it
    /// starts a sight.
    pub fn on_scan(&mut self, now_s: f64, news: bool) -> bool {
        self.expire(now_s);
        let starts = news && self.pending.is_none();
        if starts {
            self.pending = Some(now_s);
        }
        starts
    }

    /// A correction was applied at wall time `now_s`; the latency of the sight it answered, milliseconds.
    pub fn on_correction(&mut self, now_s: f64) -> Option<f64> {
        self.expire(now_s);
        let t0 = self.pending.take()?;
        let ms = (now_s - t0) * 1e3;
        self.latencies_ms.push(ms);
        Some(ms)
    }

    fn expire(&mut self, now_s: f64) {
        if self.pending.is_some_and(|t0| now_s - t0 > self.patience_s) {
            self.pending = None;
            self.unanswered += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shift_planner::map::{Cell, CellState, GridGeometry};

    fn open_map() -> OccupancyGrid {
        let geometry = GridGeometry::new(100, 100, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let mut g = OccupancyGrid::filled(geometry, CellState::Free);
        g.set(Cell::new(50, 90), CellState::Occupied);
        g
    }

    #[test]
    fn news_is_a_return_off_the_map_across_the_path_in_the_window() {
        let map = open_map();
        let robot = Point2::new(1.0, 5.0);
        let path: Vec<Point2> = (0..80).map(|k| Point2::new(1.0 + 0.1 * f64::from(k), 5.0)).collect();
        let w = WatchWindow::default();
        let on_path = [Point2::new(2.5, 5.1)];
        assert_eq!(news_on_path(&on_path, &path, robot, 0.25, w, &map), Some(on_path[0]));
        // Only inside the clearance margin, beside the path, beyond the window, or on a known wall: no news.
        assert!(news_on_path(&[Point2::new(2.5, 5.28)], &path, robot, 0.25, w, &map).is_none());
        assert!(news_on_path(&[Point2::new(2.5, 5.6)], &path, robot, 0.25, w, &map).is_none());
        assert!(news_on_path(&[Point2::new(6.0, 5.0)], &path, robot, 0.25, w, &map).is_none());
        let wall_path: Vec<Point2> = (0..30).map(|k| Point2::new(5.05, 6.5 + 0.1 * f64::from(k))).collect();
        assert!(
            news_on_path(
                &[Point2::new(5.05, 9.05)],
                &wall_path,
                Point2::new(5.05, 6.5),
                0.25,
                w,
                &map
            )
            .is_none()
        );
    }

    #[test]
    fn a_sight_is_timed_to_the_next_correction_or_given_up() {
        let mut c = SightClock::new(2.0);
        c.on_scan(10.0, false);
        c.on_correction(10.5);
        assert!(c.latencies_ms.is_empty(), "a correction without a sight is not timed");
        c.on_scan(11.0, true);
        c.on_scan(11.1, true);
        c.on_correction(11.25);
        assert_eq!(c.latencies_ms.len(), 1);
        assert!((c.latencies_ms[0] - 250.0).abs() < 1e-6, "{:?}", c.latencies_ms);
        c.on_scan(20.0, true);
        c.on_scan(22.5, false);
        assert_eq!(c.unanswered, 1);
        c.on_correction(22.6);
        assert_eq!(c.latencies_ms.len(), 1);
        // Held at a blockage: answered, apart from the corrections.
        c.on_scan(30.0, true);
        c.on_held(30.02);
        c.on_correction(30.5);
        assert_eq!(c.latencies_ms.len(), 1, "a held sight is no correction's latency");
        assert_eq!(c.held_ms.len(), 1);
        assert!((c.held_ms[0] - 20.0).abs() < 1e-6, "{:?}", c.held_ms);
    }
}
