//! Boustrophedon cellular decomposition (Choset) on the grid.
//!
//! A sweep line moves across the reachable set, column by column (or row by row). In each column the
//! reachable cells form runs (intervals). A run continues the cell of the run before it when the two touch
//! one-to-one; wherever the connectivity changes — a run splits around an obstacle (IN event), two runs join
//! behind it (OUT event), a run appears or vanishes — the sweep meets a critical point and new cells start.
//! Each resulting cell is monotone along the sweep: every column slice is a single interval, so lanes
//! parallel to the sweep line cross it exactly once. Adjacent cells that share no column are then merged
//! (their union is still monotone), which roughly halves the cells around each obstacle.
//!
//! The sweep runs on the outline of the reachable set without details smaller than the tool (see
//! [`super::outline`]); the cells it leaves out join their nearest cell. Both sweep axes are tried; the one
//! that yields fewer cells wins (a map of rooms aligned with the axes gives far fewer cells along one of
//! them).

use super::outline::{assign_rest, outline};
use super::{DecomposeParams, Decomposer, NO_REGION};
use crate::map::GridGeometry;
use crate::space::CoverageSpace;

/// Radius of the opening that simplifies the outline before the sweep, in tool widths.
pub const OUTLINE_RHO_WIDTHS: f64 = 0.5;

/// The boustrophedon strategy.
#[derive(Debug, Clone, Copy, Default)]
pub struct Boustrophedon;

impl Decomposer for Boustrophedon {
    fn label(&self, space: &CoverageSpace, _params: &DecomposeParams) -> Vec<u32> {
        let w = space.robot.tool_width_m;
        let res = space.geometry().resolution;
        // Holes up to about a tool-width-sized post with its clearance ring are ignored by the sweep.
        let hole = std::f64::consts::PI * (space.robot.radius_m + w).powi(2) / (res * res);
        let mask = outline(space, OUTLINE_RHO_WIDTHS * w, hole as usize);
        let (by_x, nx) = sweep(space.geometry(), &mask, false);
        let (by_y, ny) = sweep(space.geometry(), &mask, true);
        let mut labels = if ny < nx { by_y } else { by_x };
        assign_rest(space, &mut labels);
        labels
    }
}

/// Runs the sweep on `mask`; `transpose` sweeps rows instead of columns. Returns labels and the number of
/// cells after [`merge_monotone`].
fn sweep(g: &GridGeometry, mask: &[bool], transpose: bool) -> (Vec<u32>, usize) {
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
    // Per cell: first and last sweep line. Adjacencies between cells that meet across a line: (a, b, the
    // length of their common border in cells).
    let mut span: Vec<(usize, usize)> = Vec::new();
    let mut edges: Vec<(u32, u32, usize)> = Vec::new();
    // Runs of the previous line: (start, end inclusive, cell id).
    let mut prev: Vec<(usize, usize, u32)> = Vec::new();
    let mut cur: Vec<(usize, usize, u32)> = Vec::new();
    for line in 0..lines {
        cur.clear();
        let mut k = 0;
        while k < len {
            if !mask[idx(line, k)] {
                k += 1;
                continue;
            }
            let start = k;
            while k < len && mask[idx(line, k)] {
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
                span.push((line, line));
                for p in prev.iter().filter(|p| touches((p.0, p.1), c)) {
                    let common = (p.1.min(c.1) + 1).saturating_sub(p.0.max(c.0)).max(1);
                    edges.push((p.2, next_id - 1, common));
                }
                next_id - 1
            });
            span[id as usize].1 = line;
            cur[ci].2 = id;
            for k in c.0..=c.1 {
                labels[idx(line, k)] = id;
            }
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let (group, count) = merge_monotone(&span, edges);
    for l in labels.iter_mut().filter(|l| **l != NO_REGION) {
        *l = group[*l as usize];
    }
    (labels, count)
}

/// Merges adjacent cells whose union is still monotone along the sweep — cells that share no sweep line, so
/// every line still crosses the union in one run and lanes along the line cross it once. A room with a
/// pillar gives four cells (before, above, below, after it); before + above + after sweep as one. Widest
/// common borders first (the natural continuations), deterministic. Returns the group of every cell
/// (dense, in order of first cell) and the number of groups.
fn merge_monotone(span: &[(usize, usize)], mut edges: Vec<(u32, u32, usize)>) -> (Vec<u32>, usize) {
    let n = span.len();
    let mut parent: Vec<usize> = (0..n).collect();
    let mut lines: Vec<Vec<(usize, usize)>> = span.iter().map(|&s| vec![s]).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    edges.sort_by(|a, b| b.2.cmp(&a.2).then(a.0.cmp(&b.0)).then(a.1.cmp(&b.1)));
    for (a, b, _) in edges {
        let (ra, rb) = (find(&mut parent, a as usize), find(&mut parent, b as usize));
        if ra == rb {
            continue;
        }
        let disjoint = lines[ra]
            .iter()
            .all(|x| lines[rb].iter().all(|y| x.1 < y.0 || y.1 < x.0));
        if disjoint {
            let (keep, gone) = (ra.min(rb), ra.max(rb));
            parent[gone] = keep;
            let moved = std::mem::take(&mut lines[gone]);
            lines[keep].extend(moved);
        }
    }
    let mut dense = vec![u32::MAX; n];
    let mut out = vec![0u32; n];
    let mut count = 0u32;
    for (i, o) in out.iter_mut().enumerate() {
        let r = find(&mut parent, i);
        if dense[r] == u32::MAX {
            dense[r] = count;
            count += 1;
        }
        *o = dense[r];
    }
    (out, count as usize)
}

#[cfg(test)]
mod tests {
    use crate::decompose::{DecomposeParams, DecompositionMethod, decompose};
    use crate::geom::Point2;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};

    #[test]
    fn pillar_in_a_room_gives_two_monotone_cells() {
        // 6 m × 4 m room, a 1 m pillar in the middle: cells left, below, above, right of the pillar; left +
        // one side + right merge (still monotone), the other side stays alone.
        let g = GridGeometry::new(60, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(2.5, 1.5, 3.5, 2.5, CellState::Occupied);
        let space = crate::decompose::tests::small_robot_space(grid);
        let r = decompose(&space, DecompositionMethod::Bcd, &DecomposeParams::default());
        assert_eq!(r.count, 2);
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
