//! Sub-area division along walls (seed 003, Alg. 1).
//!
//! Seed 003 scans the binary map row by row and, where a wall ends (a free cell beside an obstacle whose
//! column turns free on the next row), draws a boundary along the row back to the previous obstacle, so that
//! rooms separate at their doorways. We apply the same rule on the reachable set, in both axes and both
//! directions, which is what the paper's figures show: where a straight wall face of at least `min_wall`
//! cells ends, its line is extended across the open space; if it meets another obstacle within `max_cut`
//! (a doorway or an alcove mouth, not a hall), those cells become a boundary. The pieces between boundaries
//! are the sub-areas; boundary cells then join the sub-area they touch most, and [`super::normalize`] merges
//! slivers.

use super::{DecomposeParams, Decomposer, NO_REGION};
use crate::space::CoverageSpace;

/// The wall-division strategy.
#[derive(Debug, Clone, Copy, Default)]
pub struct WallDivision;

impl Decomposer for WallDivision {
    fn label(&self, space: &CoverageSpace, _params: &DecomposeParams) -> Vec<u32> {
        let g = *space.geometry();
        let (w, h) = (g.width as isize, g.height as isize);
        let reach = |x: isize, y: isize| x >= 0 && y >= 0 && x < w && y < h && space.reachable[(y * w + x) as usize];
        let wt = space.robot.tool_width_m / g.resolution;
        let min_wall = (2.0 * wt).ceil().max(3.0) as isize;
        let max_cut = (8.0 * wt).max(1.5 / g.resolution).ceil() as isize;
        let mut cut = vec![false; g.len()];
        // A wall face: cells (x, y) reachable with the wall at (x, y + side). Walking along +x or -x (dir), the
        // face ends at x_end when (x_end + dir, y) is reachable and (x_end + dir, y + side) is reachable too.
        // The cut follows row y + side from x_end + dir onwards. Transposed for columns.
        for transpose in [false, true] {
            let at = |a: isize, b: isize| if transpose { reach(b, a) } else { reach(a, b) };
            let (la, lb) = if transpose { (h, w) } else { (w, h) };
            for side in [-1isize, 1] {
                for dir in [-1isize, 1] {
                    for b in 0..lb {
                        let mut run = 0isize;
                        let mut a = if dir > 0 { 0 } else { la - 1 };
                        while a >= 0 && a < la {
                            if at(a, b) && !at(a, b + side) {
                                run += 1;
                            } else {
                                if run >= min_wall && at(a, b) && at(a, b + side) {
                                    // Wall face ended at a - dir: extend the wall line (row b + side) from a.
                                    let row = b + side;
                                    let mut k = a;
                                    let mut len = 0;
                                    while at(k, row) && len <= max_cut {
                                        k += dir;
                                        len += 1;
                                    }
                                    if len <= max_cut && len > 0 && k >= 0 && k < la {
                                        let mut m = a;
                                        while m != k {
                                            let (x, y) = if transpose { (row, m) } else { (m, row) };
                                            cut[(y * w + x) as usize] = true;
                                            m += dir;
                                        }
                                    }
                                }
                                run = 0;
                            }
                            a += dir;
                        }
                    }
                }
            }
        }
        // Pieces of reachable minus cuts (4-connected so a one-cell cut line separates).
        let mut labels = vec![NO_REGION; g.len()];
        let mut next = 0u32;
        for s in 0..g.len() {
            if !space.reachable[s] || cut[s] || labels[s] != NO_REGION {
                continue;
            }
            labels[s] = next;
            let mut stack = vec![s];
            while let Some(i) = stack.pop() {
                for n in g.neighbors4(g.cell(i)) {
                    let j = g.index(n);
                    if space.reachable[j] && !cut[j] && labels[j] == NO_REGION {
                        labels[j] = next;
                        stack.push(j);
                    }
                }
            }
            next += 1;
        }
        // Cut cells join a labelled 4-neighbour (repeat until none left unlabelled).
        loop {
            let mut changed = false;
            for i in 0..g.len() {
                if space.reachable[i]
                    && labels[i] == NO_REGION
                    && let Some(l) = g
                        .neighbors4(g.cell(i))
                        .map(|n| labels[g.index(n)])
                        .find(|&l| l != NO_REGION)
                {
                    labels[i] = l;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        labels
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::{DecompositionMethod, decompose};
    use crate::geom::Point2;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};

    #[test]
    fn two_rooms_split_at_the_door() {
        // 8 m × 4 m, a wall at x = 4 m with a 1 m door in the middle.
        let g = GridGeometry::new(80, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(3.95, 0.0, 4.05, 1.5, CellState::Occupied);
        grid.fill_rect(3.95, 2.5, 4.05, 4.0, CellState::Occupied);
        let space = crate::decompose::tests::small_robot_space(grid);
        let r = decompose(&space, DecompositionMethod::Walls, &DecomposeParams::default());
        assert_eq!(r.count, 2, "rooms left and right of the door");
        let left = r.labels[g.index(g.locate(Point2::new(1.0, 2.0)).expect("on map"))];
        let right = r.labels[g.index(g.locate(Point2::new(7.0, 2.0)).expect("on map"))];
        assert_ne!(left, right);
    }
}
