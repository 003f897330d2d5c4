//! Short real walks between two cells of one region (step 3 of [`geodesic_matrix`](super::geodesic_matrix)):
//! the straight octile walk, the walk along the region's shortest-path tree, and walks to ancestors.

use super::super::astar::{DIRS, Graph, ROOT};
use super::SweepCell;

/// Length of the walk from cell `x` to cell `y` of one region along its shortest-path tree (through their
/// lowest common ancestor).
fn tree_walk(graph: &Graph<'_>, cells: &[SweepCell], x: usize, y: usize) -> f64 {
    let (mut a, mut b) = (x, y);
    while a != b {
        // Parents are strictly closer to the root, so moving the farther one up meets at the ancestor.
        if cells[a].dist >= cells[b].dist {
            if cells[a].parent == ROOT {
                return f64::INFINITY;
            }
            a = graph.back(a, cells[a].parent);
        } else {
            if cells[b].parent == ROOT {
                return f64::INFINITY;
            }
            b = graph.back(b, cells[b].parent);
        }
    }
    cells[x].dist + cells[y].dist - 2.0 * cells[a].dist
}

/// A short real walk between cells `x` and `y` of one region: the straight octile walk when it is free (no
/// walk is shorter); otherwise the best of the tree walk and of straight walks from one cell to ancestors
/// of the other, continued down the tree.
pub(super) fn region_walk(graph: &Graph<'_>, cells: &[SweepCell], x: usize, y: usize) -> f64 {
    if let Some(line) = line_walk(graph, x, y) {
        return line;
    }
    tree_walk(graph, cells, x, y)
        .min(ancestor_walk(graph, cells, x, y))
        .min(ancestor_walk(graph, cells, y, x))
}

/// Straight walks from `x` to the ancestors of `y` 1, 2, 4, … steps up `y`'s tree path, then down the tree
/// to `y`: the best of them.
fn ancestor_walk(graph: &Graph<'_>, cells: &[SweepCell], x: usize, y: usize) -> f64 {
    let mut best = f64::INFINITY;
    let (mut a, mut steps, mut next) = (y, 0usize, 1usize);
    while cells[a].parent != ROOT {
        a = graph.back(a, cells[a].parent);
        steps += 1;
        if steps == next {
            next *= 2;
            if let Some(line) = line_walk(graph, x, a) {
                best = best.min(line + cells[y].dist - cells[a].dist);
            }
        }
    }
    best
}

/// The move index of a non-zero offset (`dx`, `dy`) with components in {-1, 0, 1}.
fn dir_of(dx: isize, dy: isize) -> usize {
    // Every such offset is in DIRS; the fallback is never taken.
    DIRS.iter().position(|&o| o == (dx, dy)).unwrap_or(0)
}

/// Octile length of the Bresenham walk from cell `x` to cell `y` when every move of it is allowed.
fn line_walk(graph: &Graph<'_>, x: usize, y: usize) -> Option<f64> {
    let (x0, y0) = graph.xy(x);
    let (x1, y1) = graph.xy(y);
    let (adx, ady) = (x0.abs_diff(x1), y0.abs_diff(y1));
    let sx: isize = if x1 >= x0 { 1 } else { -1 };
    let sy: isize = if y1 >= y0 { 1 } else { -1 };
    let (major, minor, x_major) = if adx >= ady {
        (adx, ady, true)
    } else {
        (ady, adx, false)
    };
    let straight = if x_major { dir_of(sx, 0) } else { dir_of(0, sy) };
    let diagonal = dir_of(sx, sy);
    let (mut cx, mut cy, mut i) = (x0, y0, x);
    let (major_i, minor_i) = (major as i64, minor as i64);
    let mut err = 0i64;
    for _ in 0..major {
        err += minor_i;
        let d = if 2 * err >= major_i {
            err -= major_i;
            diagonal
        } else {
            straight
        };
        i = graph.step(i, cx, cy, d)?;
        (cx, cy) = graph.xy(i);
    }
    (i == y).then(|| graph.octile(x, y))
}
