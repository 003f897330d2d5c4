//! Step 1 of [`geodesic_matrix`](super::geodesic_matrix): the multi-source Dijkstra over the grid that labels
//! every reachable cell with its nearest point, the distance to it and the move that reached it.

use super::super::astar::{Graph, ROOT, STEP_CELLS};
use super::{SweepCell, UNREACHED};

/// Multi-source Dijkstra over the grid from the points' cells (bucket queue, exact; see the `geodesic` module
/// docs).
pub(super) fn sweep(graph: &Graph<'_>, seeds: &[(usize, f64, u32)]) -> Vec<SweepCell> {
    let res = graph.resolution;
    let inv_res = 1.0 / res;
    let mut cells = vec![UNREACHED; graph.len()];
    let mut buckets: [Vec<u32>; 4] = Default::default();
    let mut pending = 0usize;
    for &(i, d, label) in seeds {
        if d < cells[i].dist {
            cells[i] = SweepCell {
                dist: d,
                label,
                parent: ROOT,
                done: false,
            };
            // Offsets to the cell centre are below one resolution: bucket 0.
            buckets[0].push(i as u32);
            pending += 1;
        }
    }
    let mut current = 0usize;
    while pending > 0 {
        let slot = current & 3;
        let mut list = std::mem::take(&mut buckets[slot]);
        pending -= list.len();
        // Cells of one bucket are independent; in memory order they share cache lines and pages.
        list.sort_unstable();
        for &u in &list {
            let u = u as usize;
            let cu = cells[u];
            if cu.done {
                continue;
            }
            cells[u].done = true;
            graph.for_each_move(u, |v, d, _, _| {
                let cv = &mut cells[v];
                if cv.done {
                    return;
                }
                let dv = cu.dist + STEP_CELLS[d] * res;
                if dv < cv.dist {
                    *cv = SweepCell {
                        dist: dv,
                        label: cu.label,
                        parent: d as u8,
                        done: false,
                    };
                    // At least the next bucket (exact arithmetic guarantees it; this guards rounding); at
                    // most two ahead since steps are below 1.5 resolutions, so four slots never collide.
                    let b = ((dv * inv_res) as usize).max(current + 1);
                    buckets[b & 3].push(v as u32);
                    pending += 1;
                }
            });
        }
        list.clear();
        if buckets[slot].is_empty() {
            buckets[slot] = list;
        }
        current += 1;
    }
    cells
}
