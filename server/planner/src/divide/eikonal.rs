//! Travel distance from a start over a set of cells by the fast marching method (Sethian 1996): the
//! first-order upwind solution of the eikonal equation |∇T| = 1 on the grid.
//!
//! Division needs distances whose level sets are round. Grid walks (octile steps) measure with an
//! octagonal norm, and with it a whole 45° cone of cells behind a robot's dock is exactly one dock spacing
//! further from the robot beside it: two docks a metre apart in a hall could then never be balanced by an
//! additive weight (the cone stays with the robot behind, whatever the weights). Fast marching has no such
//! flat facets: the cells at a fixed difference of distance shrink to a ray.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::map::GridGeometry;

/// Total order on non-negative finite distances for the heap.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Key(f64);

impl Eq for Key {}

impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Key {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Travel distance (metres) from cell `start` (whose value is `start_m`, the offset of the real start from
/// the cell's centre) to every cell of `passable` connected to it through 8-neighbours; infinite elsewhere.
///
/// The stencil is the 4-neighbour one; a diagonal step (h√2) is taken only between two cells whose two
/// common neighbours are both impassable, the corner-to-corner links of ragged real maps that the robots'
/// reachable sets (8-connected) hold and a 4-neighbour march would leave unreached. Taking every diagonal
/// would bring back the octagonal facets the module docs warn of.
pub(super) fn travel_distance(g: &GridGeometry, passable: &[bool], start: usize, start_m: f64) -> Vec<f64> {
    let h = g.resolution;
    let mut dist = vec![f64::INFINITY; g.len()];
    let mut known = vec![false; g.len()];
    if !passable.get(start).copied().unwrap_or(false) {
        return dist;
    }
    let mut heap = BinaryHeap::new();
    dist[start] = start_m;
    heap.push(Reverse((Key(start_m), start)));
    let (w, ht) = (g.width, g.height);
    while let Some(Reverse((Key(d), u))) = heap.pop() {
        if known[u] || d > dist[u] {
            continue;
        }
        known[u] = true;
        let (x, y) = (u % w, u / w);
        let neighbours = [
            (x > 0).then(|| u - 1),
            (x + 1 < w).then(|| u + 1),
            (y > 0).then(|| u - w),
            (y + 1 < ht).then(|| u + w),
        ];
        for v in neighbours.into_iter().flatten() {
            if known[v] || !passable[v] {
                continue;
            }
            let (vx, vy) = (v % w, v / w);
            let along = |a: Option<usize>, b: Option<usize>| -> f64 {
                [a, b]
                    .into_iter()
                    .flatten()
                    .filter(|&n| known[n])
                    .map(|n| dist[n])
                    .fold(f64::INFINITY, f64::min)
            };
            let a = along((vx > 0).then(|| v - 1), (vx + 1 < w).then(|| v + 1));
            let b = along((vy > 0).then(|| v - w), (vy + 1 < ht).then(|| v + w));
            let t = if a.is_finite() && b.is_finite() && (a - b).abs() < h {
                (a + b + (2.0 * h * h - (a - b) * (a - b)).sqrt()) / 2.0
            } else {
                a.min(b) + h
            };
            if t < dist[v] {
                dist[v] = t;
                heap.push(Reverse((Key(t), v)));
            }
        }
        for (dx, dy) in [(-1i64, -1i64), (1, -1), (-1, 1), (1, 1)] {
            let (vx, vy) = (x as i64 + dx, y as i64 + dy);
            if vx < 0 || vy < 0 || vx >= w as i64 || vy >= ht as i64 {
                continue;
            }
            let v = vy as usize * w + vx as usize;
            let (side_a, side_b) = (y * w + vx as usize, vy as usize * w + x);
            if known[v] || !passable[v] || passable[side_a] || passable[side_b] {
                continue;
            }
            let t = d + h * std::f64::consts::SQRT_2;
            if t < dist[v] {
                dist[v] = t;
                heap.push(Reverse((Key(t), v)));
            }
        }
    }
    dist
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;

    #[test]
    fn in_open_space_the_distance_is_nearly_euclidean_and_round() {
        let g = GridGeometry::new(201, 201, 0.1, Point2::origin()).expect("geometry");
        let all = vec![true; g.len()];
        let c = 100 * 201 + 100;
        let d = travel_distance(&g, &all, c, 0.0);
        for (x, y) in [(200, 100), (100, 0), (200, 200), (170, 150), (0, 37)] {
            let e = (((x as f64) - 100.0).hypot((y as f64) - 100.0)) * 0.1;
            let got = d[y * 201 + x];
            assert!(got >= e - 1e-9 && got <= e * 1.06 + 0.05, "({x}, {y}): {got} vs {e}");
        }
    }

    #[test]
    fn walls_are_gone_round_and_closed_pieces_are_unreached() {
        // A wall at x = 10 from y = 0 to 18 of a 21 × 21 grid: the far side is reached round its end.
        let g = GridGeometry::new(21, 21, 1.0, Point2::origin()).expect("geometry");
        let mut pass = vec![true; g.len()];
        for y in 0..19 {
            pass[y * 21 + 10] = false;
        }
        let d = travel_distance(&g, &pass, 0, 0.0);
        let straight = 12.0;
        assert!(d[12] > straight + 20.0, "{}", d[12]);
        let mut closed = vec![true; g.len()];
        for y in 0..21 {
            closed[y * 21 + 10] = false;
        }
        let d = travel_distance(&g, &closed, 0, 0.0);
        assert!(d[12].is_infinite());
        assert!(travel_distance(&g, &closed, 10, 0.0).iter().all(|v| v.is_infinite()));
    }

    #[test]
    fn cells_linked_only_corner_to_corner_are_reached_by_a_diagonal_step() {
        // Two 3 × 3 blocks touching only at one corner: (2, 2) and (3, 3). An 8-connected reachable set
        // holds both; the march must too, at one diagonal step across the corner.
        let g = GridGeometry::new(6, 6, 1.0, Point2::origin()).expect("geometry");
        let pass: Vec<bool> = (0..36).map(|i| (i % 6 < 3) == (i / 6 < 3)).collect();
        let d = travel_distance(&g, &pass, 0, 0.0);
        let corner = 2 * 6 + 2;
        let across = 3 * 6 + 3;
        assert!(
            (d[across] - d[corner] - std::f64::consts::SQRT_2).abs() < 1e-9,
            "{} {}",
            d[corner],
            d[across]
        );
        assert!(d[5 * 6 + 5].is_finite());
        // In open space no diagonal step is taken: the distance along the diagonal stays the march's.
        let all = vec![true; 36];
        let open = travel_distance(&g, &all, 0, 0.0);
        assert!(open[across] > 3.0 * std::f64::consts::SQRT_2 + 0.1, "{}", open[across]);
    }
}
