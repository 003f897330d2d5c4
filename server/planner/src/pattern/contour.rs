//! Contour tracing of a cell mask (Moore-neighbour tracing with Jacob's stopping criterion).
//!
//! Returns every boundary loop of the mask — outer boundaries and the boundaries of holes — as ordered lists
//! of cell indices, each consecutive pair 8-adjacent. A boundary cell is a mask cell with a 4-neighbour
//! outside the mask (or on the map edge).

use crate::map::{Cell, GridGeometry};

/// Clockwise Moore neighbourhood, starting west.
const RING: [(isize, isize); 8] = [(-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1)];

/// Traces the boundary loops of the cells `cells` (global indices) on their bounding box only, so tracing
/// one region costs O(region), not O(map). Returns global indices.
pub fn trace_cells(g: &GridGeometry, cells: &[usize]) -> Vec<Vec<usize>> {
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for &i in cells {
        let c = g.cell(i);
        (x0, y0, x1, y1) = (x0.min(c.x), y0.min(c.y), x1.max(c.x), y1.max(c.y));
    }
    if x0 == usize::MAX {
        return Vec::new();
    }
    let (bw, bh) = (x1 - x0 + 1, y1 - y0 + 1);
    let Ok(local) = GridGeometry::new(bw, bh, g.resolution, g.origin) else {
        return Vec::new();
    };
    let mut mask = vec![false; bw * bh];
    for &i in cells {
        let c = g.cell(i);
        mask[(c.y - y0) * bw + (c.x - x0)] = true;
    }
    trace_loops(&local, &mask)
        .into_iter()
        .map(|lp| lp.into_iter().map(|j| (y0 + j / bw) * g.width + x0 + j % bw).collect())
        .collect()
}

/// Traces all boundary loops of `mask`.
pub fn trace_loops(g: &GridGeometry, mask: &[bool]) -> Vec<Vec<usize>> {
    let mut visited = vec![0u32; g.len()];
    trace_from(g, &|i| mask[i], 0..g.len(), &mut visited, 1)
}

/// Traces the boundary loops of the mask `inside` that pass through the candidate start cells `starts` (every
/// boundary cell of a loop to be found must be among them or reached from them). `visited` is scratch of the
/// grid's size, marked with `stamp`; reusing it with a fresh stamp per call makes repeated tracing (one call per
/// spiral ring) cost O(boundary), not O(map).
pub fn trace_from(
    g: &GridGeometry,
    mask: &dyn Fn(usize) -> bool,
    starts: impl IntoIterator<Item = usize>,
    visited: &mut [u32],
    stamp: u32,
) -> Vec<Vec<usize>> {
    let inside = |c: Option<Cell>| c.is_some_and(|c| mask(g.index(c)));
    let is_boundary = |i: usize| {
        let c = g.cell(i);
        mask(i)
            && [(0, 1), (0, -1), (1, 0), (-1, 0)]
                .iter()
                .any(|&(dx, dy)| !inside(g.offset(c, dx, dy)))
    };
    let mut loops = Vec::new();
    for s in starts {
        if visited[s] == stamp || !is_boundary(s) {
            continue;
        }
        let start = g.cell(s);
        // Backtrack direction: an outside 4-neighbour.
        let Some(b0) = [0usize, 2, 4, 6]
            .into_iter()
            .find(|&k| !inside(g.offset(start, RING[k].0, RING[k].1)))
        else {
            continue;
        };
        let mut out = vec![s];
        visited[s] = stamp;
        let (mut cur, mut back) = (start, b0);
        let mut first_move: Option<(Cell, usize)> = None;
        let cap = 4 * g.len() + 8;
        for _ in 0..cap {
            // Scan clockwise from the backtrack direction for the next mask cell.
            let mut found = None;
            for k in 1..=8 {
                let dir = (back + k) % 8;
                if inside(g.offset(cur, RING[dir].0, RING[dir].1)) {
                    found = Some(dir);
                    break;
                }
            }
            let Some(dir) = found else { break }; // isolated cell
            let Some(next) = g.offset(cur, RING[dir].0, RING[dir].1) else {
                break;
            };
            if let Some(fm) = first_move {
                if cur == start && fm == (next, dir) {
                    break;
                }
            } else {
                first_move = Some((next, dir));
            }
            // New backtrack: the cell examined just before `next`, seen from `next`.
            let prev_dir = (dir + 7) % 8;
            let (px, py) = (cur.x as isize + RING[prev_dir].0, cur.y as isize + RING[prev_dir].1);
            let (dx, dy) = (px - next.x as isize, py - next.y as isize);
            back = RING.iter().position(|&d| d == (dx, dy)).unwrap_or((dir + 4) % 8);
            cur = next;
            let i = g.index(cur);
            visited[i] = stamp;
            out.push(i);
        }
        // Drop the closing repeat of the start.
        if out.len() > 1 && out.last() == Some(&s) {
            out.pop();
        }
        loops.push(out);
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;

    #[test]
    fn square_with_hole_has_two_loops_covering_the_boundary() {
        let g = GridGeometry::new(12, 12, 1.0, Point2::origin()).expect("valid");
        let mut mask = vec![false; g.len()];
        for y in 1..11 {
            for x in 1..11 {
                mask[y * 12 + x] = !(5..7).contains(&x) || !(5..7).contains(&y);
            }
        }
        let loops = trace_loops(&g, &mask);
        assert_eq!(loops.len(), 2, "{loops:?}");
        for l in &loops {
            for w in l.windows(2) {
                let (a, b) = (g.cell(w[0]), g.cell(w[1]));
                assert!(a.x.abs_diff(b.x) <= 1 && a.y.abs_diff(b.y) <= 1);
            }
        }
        // Outer ring of a 10×10 block has 36 cells; the hole's ring the 12 cells around the 2×2 hole
        // (4-boundary cells only: 8 edge neighbours + 4 corners reached diagonally are not 4-boundary).
        let mut sizes: Vec<_> = loops
            .iter()
            .map(|l| l.iter().collect::<std::collections::HashSet<_>>().len())
            .collect();
        sizes.sort_unstable();
        assert_eq!(sizes[1], 36);
        assert!(sizes[0] >= 8 && sizes[0] <= 12, "{sizes:?}");
    }

    #[test]
    fn single_cell_and_line() {
        let g = GridGeometry::new(5, 5, 1.0, Point2::origin()).expect("valid");
        let mut mask = vec![false; 25];
        mask[12] = true;
        assert_eq!(trace_loops(&g, &mask), vec![vec![12]]);
        let mut line = vec![false; 25];
        for x in 0..5 {
            line[10 + x] = true;
        }
        let loops = trace_loops(&g, &line);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].iter().collect::<std::collections::HashSet<_>>().len(), 5);
    }
}
