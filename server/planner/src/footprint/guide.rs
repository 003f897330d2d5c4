//! The lattice search's guide: the 8-connected grid distance to the goal over the cells a robot centre could
//! possibly stand in (its inscribed disc clear), within a window. It is the search's heuristic, and a cell it
//! does not reach holds no pose that can get to the goal.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::geom::Point2;
use crate::map::{DistanceField, GridGeometry};

/// Distances to the goal over a window of the grid, metres.
#[derive(Debug, Clone)]
pub struct Guide {
    geometry: GridGeometry,
    /// First column and row of the window.
    x0: usize,
    y0: usize,
    /// Window size in cells.
    w: usize,
    h: usize,
    /// Distance to the goal's cell per window cell (∞ where unreached).
    dist_m: Vec<f64>,
}

impl Guide {
    /// The guide to `goal` within the map-frame box `lo`–`hi` (clipped to the map), over cells whose centre
    /// is at least `min_clearance_m` from every blocked cell centre (`clearance`). `None` when the goal lies
    /// off the map or in a cell that fails the test.
    pub fn toward(
        clearance: &DistanceField,
        goal: Point2,
        lo: Point2,
        hi: Point2,
        min_clearance_m: f64,
    ) -> Option<Self> {
        let g = *clearance.geometry();
        let clip = |p: Point2| {
            let (cx, cy) = g.to_cell_coords(p);
            (
                (cx.floor().max(0.0) as usize).min(g.width - 1),
                (cy.floor().max(0.0) as usize).min(g.height - 1),
            )
        };
        let (x0, y0) = clip(lo);
        let (x1, y1) = clip(hi);
        let (w, h) = (x1 + 1 - x0, y1 + 1 - y0);
        let goal_cell = g.locate(goal)?;
        if goal_cell.x < x0 || goal_cell.x > x1 || goal_cell.y < y0 || goal_cell.y > y1 {
            return None;
        }
        let open = |x: usize, y: usize| clearance.at(y * g.width + x) >= min_clearance_m;
        if !open(goal_cell.x, goal_cell.y) {
            return None;
        }
        let mut dist_m = vec![f64::INFINITY; w * h];
        let start = (goal_cell.y - y0) * w + (goal_cell.x - x0);
        dist_m[start] = 0.0;
        let mut heap = BinaryHeap::from([(Reverse(0u64), start)]);
        let r = g.resolution;
        let steps: [(isize, isize, f64); 8] = [
            (1, 0, r),
            (-1, 0, r),
            (0, 1, r),
            (0, -1, r),
            (1, 1, r * std::f64::consts::SQRT_2),
            (1, -1, r * std::f64::consts::SQRT_2),
            (-1, 1, r * std::f64::consts::SQRT_2),
            (-1, -1, r * std::f64::consts::SQRT_2),
        ];
        while let Some((Reverse(d_bits), i)) = heap.pop() {
            let d = f64::from_bits(d_bits);
            if d > dist_m[i] {
                continue;
            }
            let (lx, ly) = (i % w, i / w);
            for &(dx, dy, cost) in &steps {
                let (Some(nx), Some(ny)) = (lx.checked_add_signed(dx), ly.checked_add_signed(dy)) else {
                    continue;
                };
                if nx >= w || ny >= h || !open(x0 + nx, y0 + ny) {
                    continue;
                }
                let j = ny * w + nx;
                let nd = d + cost;
                if nd < dist_m[j] {
                    dist_m[j] = nd;
                    // Non-negative f64s order as their bits.
                    heap.push((Reverse(nd.to_bits()), j));
                }
            }
        }
        Some(Self {
            geometry: g,
            x0,
            y0,
            w,
            h,
            dist_m,
        })
    }

    /// Grid distance from the cell of `p` to the goal's cell, metres; `∞` outside the window or where the
    /// goal cannot be reached.
    #[inline]
    pub fn at(&self, p: Point2) -> f64 {
        let Some(c) = self.geometry.locate(p) else {
            return f64::INFINITY;
        };
        if c.x < self.x0 || c.y < self.y0 || c.x >= self.x0 + self.w || c.y >= self.y0 + self.h {
            return f64::INFINITY;
        }
        self.dist_m[(c.y - self.y0) * self.w + (c.x - self.x0)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, OccupancyGrid};

    #[test]
    fn the_guide_goes_round_a_wall_and_not_through_it() {
        let g = GridGeometry::new(40, 20, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(1.95, 0.0, 2.05, 1.5, CellState::Occupied);
        let df = DistanceField::compute(g, |i| !grid.is_free(i), true);
        let guide =
            Guide::toward(&df, Point2::new(3.0, 0.5), Point2::origin(), Point2::new(4.0, 2.0), 0.1).expect("goal open");
        let d = guide.at(Point2::new(1.0, 0.5));
        assert!(d.is_finite() && d > 2.5, "round the wall's end: {d}");
        assert!(guide.at(Point2::new(9.0, 0.5)).is_infinite());
        let shut = Guide::toward(
            &df,
            Point2::new(3.0, 0.5),
            Point2::origin(),
            Point2::new(4.0, 2.0),
            0.35,
        )
        .expect("goal open");
        assert!(
            shut.at(Point2::new(1.0, 0.5)).is_infinite(),
            "the gap above the wall is too narrow"
        );
    }
}
