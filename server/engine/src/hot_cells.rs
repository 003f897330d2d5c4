//! Where a site's live map has changed lately, on a coarse grid.
//!
//! The engine hears every change of a site's live map as a box ([`crate::Event::MapChanged`]) and checks at
//! once the robots whose window reaches the box then. A robot that comes to a known obstacle later (seen from
//! afar by its own sensor, or by another robot) hears of nothing new: its checks come at the pose cadence
//! (`check_interval_ms`), which bounds how late a correction can be. [`HotCells`] keeps the boxes on a grid of
//! cells for the live map's horizon (points older than that are gone from the map too), so a robot is checked
//! as soon as its window takes in a changed cell it did not take in at its last check; in open space nothing is
//! hot and the cadence alone applies.

use std::collections::{BTreeSet, HashMap};

/// A cell of the coarse grid: `(floor(x / cell), floor(y / cell))`.
pub type HotCell = (i64, i64);

/// Most cells one change marks: a box larger than this many cells marks its cells on a coarser lattice
/// (every k-th cell each way), which still puts a mark within k cells of any point of it.
const MAX_CELLS_PER_MARK: i64 = 4096;

/// Changed cells of one site, each with when it last changed.
#[derive(Debug, Clone)]
pub struct HotCells {
    cell_m: f64,
    horizon_ms: u64,
    cells: HashMap<HotCell, u64>,
}

impl HotCells {
    /// Cells of `cell_m` metres, each hot for `horizon_ms` after its last change.
    pub fn new(cell_m: f64, horizon_ms: u64) -> Self {
        Self {
            cell_m: if cell_m.is_finite() && cell_m > 0.0 {
                cell_m
            } else {
                1.0
            },
            horizon_ms,
            cells: HashMap::new(),
        }
    }

    fn cell_of(&self, v: f64) -> i64 {
        (v / self.cell_m).floor() as i64
    }

    /// The live map changed within the box `[min, max]` (map frame, metres) at `now_ms`. Non-finite boxes are
    /// ignored.
    pub fn mark(&mut self, min: [f64; 2], max: [f64; 2], now_ms: u64) {
        if !min.iter().chain(&max).all(|v| v.is_finite()) || min[0] > max[0] || min[1] > max[1] {
            return;
        }
        let (x0, x1) = (self.cell_of(min[0]), self.cell_of(max[0]));
        let (y0, y1) = (self.cell_of(min[1]), self.cell_of(max[1]));
        let (nx, ny) = (x1 - x0 + 1, y1 - y0 + 1);
        let step = (((nx as f64) * (ny as f64) / MAX_CELLS_PER_MARK as f64).sqrt().ceil() as i64).max(1);
        let mut y = y0;
        while y <= y1 {
            let mut x = x0;
            while x <= x1 {
                let t = self.cells.entry((x, y)).or_insert(now_ms);
                *t = (*t).max(now_ms);
                x += step;
            }
            y += step;
        }
        self.expire(now_ms);
    }

    /// Forgets cells that have not changed within the horizon.
    pub fn expire(&mut self, now_ms: u64) {
        let horizon = self.horizon_ms;
        self.cells.retain(|_, &mut t| now_ms.saturating_sub(t) <= horizon);
    }

    /// The hot cells that reach within `reach` metres of `p` (any part of the cell), as of `now_ms`.
    pub fn near(&self, p: [f64; 2], reach: f64, now_ms: u64) -> BTreeSet<HotCell> {
        let mut out = BTreeSet::new();
        if self.cells.is_empty() || !(p[0].is_finite() && p[1].is_finite() && reach.is_finite()) {
            return out;
        }
        let (cx0, cx1) = (self.cell_of(p[0] - reach), self.cell_of(p[0] + reach));
        let (cy0, cy1) = (self.cell_of(p[1] - reach), self.cell_of(p[1] + reach));
        // A window wider than the grid of hot cells: walk the cells instead of the window.
        let window = (cx1 - cx0 + 1).saturating_mul(cy1 - cy0 + 1);
        let reaches = |&(x, y): &HotCell| {
            let c = self.cell_m;
            let dx = (x as f64 * c - p[0]).max(p[0] - (x + 1) as f64 * c).max(0.0);
            let dy = (y as f64 * c - p[1]).max(p[1] - (y + 1) as f64 * c).max(0.0);
            dx.hypot(dy) <= reach
        };
        let fresh = |t: u64| now_ms.saturating_sub(t) <= self.horizon_ms;
        if window as usize > self.cells.len() {
            out.extend(
                self.cells
                    .iter()
                    .filter(|&(c, &t)| fresh(t) && reaches(c))
                    .map(|(&c, _)| c),
            );
        } else {
            for y in cy0..=cy1 {
                for x in cx0..=cx1 {
                    if self.cells.get(&(x, y)).is_some_and(|&t| fresh(t)) && reaches(&(x, y)) {
                        out.insert((x, y));
                    }
                }
            }
        }
        out
    }

    /// Cells held.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// True when no cell is hot.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_change_is_near_a_robot_whose_window_reaches_it_until_the_horizon() {
        let mut h = HotCells::new(0.5, 1000);
        h.mark([4.1, 2.0], [4.3, 2.2], 100);
        assert!(h.near([0.0, 2.0], 3.0, 200).is_empty(), "4.0 m away, reach 3 m");
        let near = h.near([1.2, 2.0], 3.0, 200);
        assert_eq!(near.len(), 1, "{near:?}");
        assert!(h.near([1.2, 2.0], 3.0, 1101).is_empty(), "past the horizon");
        h.expire(1101);
        assert!(h.is_empty());
        // Garbage is ignored.
        h.mark([f64::NAN, 0.0], [1.0, 1.0], 5);
        h.mark([2.0, 0.0], [1.0, 1.0], 5);
        assert!(h.is_empty());
        assert!(h.near([f64::INFINITY, 0.0], 3.0, 5).is_empty());
    }

    #[test]
    fn a_huge_box_marks_a_bounded_lattice_that_still_reaches_every_point() {
        let mut h = HotCells::new(0.5, 1000);
        h.mark([0.0, 0.0], [500.0, 500.0], 0);
        assert!(h.len() <= 2 * MAX_CELLS_PER_MARK as usize, "{} cells", h.len());
        for p in [[0.3, 0.3], [250.1, 499.0], [499.9, 7.7]] {
            assert!(!h.near(p, 8.0, 1).is_empty(), "{p:?}");
        }
    }

    proptest! {
        /// `near` against brute force over every cell held.
        #[test]
        fn near_is_every_fresh_cell_within_reach(
            boxes in proptest::collection::vec((-20.0..20.0f64, -20.0..20.0f64, 0.0..3.0f64, 0.0..3.0f64, 0u64..50), 1..12),
            px in -25.0..25.0f64, py in -25.0..25.0f64, reach in 0.0..10.0f64, now in 0u64..120,
        ) {
            let mut h = HotCells::new(0.7, 60);
            for (x, y, w, d, t) in boxes {
                h.mark([x, y], [x + w, y + d], t);
            }
            let got = h.near([px, py], reach, now);
            let want: BTreeSet<HotCell> = h
                .cells
                .iter()
                .filter(|&(&(x, y), &t)| {
                    let c = 0.7;
                    let dx = (x as f64 * c - px).max(px - (x + 1) as f64 * c).max(0.0);
                    let dy = (y as f64 * c - py).max(py - (y + 1) as f64 * c).max(0.0);
                    now.saturating_sub(t) <= 60 && dx.hypot(dy) <= reach
                })
                .map(|(&c, _)| c)
                .collect();
            prop_assert_eq!(got, want);
        }
    }
}
