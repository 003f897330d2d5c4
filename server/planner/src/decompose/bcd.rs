//! Boustrophedon cellular decomposition (Choset) on the grid.
//!
//! A sweep line moves across the reachable set, column by column (or row by row). In each column the
//! reachable cells form runs (intervals). A run continues the cell of the run before it when the two touch
//! one-to-one; wherever the connectivity changes — a run splits around an obstacle (IN event), two runs join
//! behind it (OUT event), a run appears or vanishes — the sweep meets a critical point and new cells start.
//! Each resulting cell is monotone along the sweep: every column slice is a single interval, so lanes
//! parallel to the sweep line cross it exactly once.
//!
//! Both sweep axes are tried; the one that yields fewer cells wins (a map of rooms aligned with the axes
//! gives far fewer cells along one of them).

use super::{DecomposeParams, Decomposer, NO_REGION};
use crate::space::CoverageSpace;

/// The boustrophedon strategy.
#[derive(Debug, Clone, Copy, Default)]
pub struct Boustrophedon;

impl Decomposer for Boustrophedon {
    fn label(&self, space: &CoverageSpace, _params: &DecomposeParams) -> Vec<u32> {
        let (by_x, nx) = sweep(space, false);
        let (by_y, ny) = sweep(space, true);
        if ny < nx { by_y } else { by_x }
    }
}

/// Runs the sweep; `transpose` sweeps rows instead of columns. Returns labels and the number of cells.
fn sweep(space: &CoverageSpace, transpose: bool) -> (Vec<u32>, usize) {
    let g = space.geometry();
    let (lines, len) = if transpose {
        (g.height, g.width)
    } else {
        (g.width, g.height)
    };
    let idx = |line: usize, k: usize| {
        if transpose {
            line * g.width + k
        } else {
            k * g.width + line
        }
    };
    let mut labels = vec![NO_REGION; g.len()];
    let mut next_id = 0u32;
    // Runs of the previous line: (start, end inclusive, cell id).
    let mut prev: Vec<(usize, usize, u32)> = Vec::new();
    let mut cur: Vec<(usize, usize, u32)> = Vec::new();
    for line in 0..lines {
        cur.clear();
        let mut k = 0;
        while k < len {
            if !space.reachable[idx(line, k)] {
                k += 1;
                continue;
            }
            let start = k;
            while k < len && space.reachable[idx(line, k)] {
                k += 1;
            }
            cur.push((start, k - 1, NO_REGION));
        }
        // 8-connected overlap between runs of consecutive lines.
        let touches = |a: (usize, usize), b: (usize, usize)| a.0 <= b.1 + 1 && b.0 <= a.1 + 1;
        for ci in 0..cur.len() {
            let c = (cur[ci].0, cur[ci].1);
            let mut left = prev.iter().filter(|p| touches((p.0, p.1), c));
            let id = match (left.next(), left.next()) {
                (Some(&p), None) => {
                    // The one predecessor must touch only this run too.
                    let fan_out = cur.iter().filter(|q| touches((p.0, p.1), (q.0, q.1))).count();
                    if fan_out == 1 { Some(p.2) } else { None }
                }
                _ => None,
            };
            let id = id.unwrap_or_else(|| {
                next_id += 1;
                next_id - 1
            });
            cur[ci].2 = id;
            for k in c.0..=c.1 {
                labels[idx(line, k)] = id;
            }
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    (labels, next_id as usize)
}

#[cfg(test)]
mod tests {
    use crate::decompose::{DecomposeParams, DecompositionMethod, decompose};
    use crate::geom::Point2;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};

    #[test]
    fn pillar_in_a_room_gives_four_cells() {
        // 6 m × 4 m room, a 1 m pillar in the middle: cells left, below, above, right of the pillar.
        let g = GridGeometry::new(60, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(2.5, 1.5, 3.5, 2.5, CellState::Occupied);
        let space = crate::decompose::tests::small_robot_space(grid);
        let r = decompose(&space, DecompositionMethod::Bcd, &DecomposeParams::default());
        assert_eq!(r.count, 4);
        // Each cell is monotone along the sweep: every column (or row) slice is one run.
        for cells in r.cells() {
            let mut cols: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
            let mut rows: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
            for &i in &cells {
                let c = g.cell(i);
                cols.entry(c.x).or_default().push(c.y);
                rows.entry(c.y).or_default().push(c.x);
            }
            let monotone = |m: &std::collections::BTreeMap<usize, Vec<usize>>| {
                m.values().all(|v| v.windows(2).all(|w| w[1] == w[0] + 1))
            };
            assert!(monotone(&cols) || monotone(&rows));
        }
    }

    #[test]
    fn empty_room_is_one_cell() {
        let g = GridGeometry::new(30, 20, 0.1, Point2::origin()).expect("valid");
        let grid = OccupancyGrid::filled(g, CellState::Free);
        let space = crate::decompose::tests::small_robot_space(grid);
        let r = decompose(&space, DecompositionMethod::Bcd, &DecomposeParams::default());
        assert_eq!(r.count, 1);
    }
}
