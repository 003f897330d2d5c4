//! Grid decomposition (seed 004 §3.3.2): the open area's bounding box is cut into equal blocks, no smaller
//! than four robot footprints on a side, and each block's reachable cells become regions (one per connected
//! piece — a block cut by a wall gives two regions, never one region in two rooms).

use super::{DecomposeParams, Decomposer, NO_REGION};
use crate::space::CoverageSpace;

/// The grid strategy.
#[derive(Debug, Clone, Copy, Default)]
pub struct GridBlocks;

impl Decomposer for GridBlocks {
    fn label(&self, space: &CoverageSpace, params: &DecomposeParams) -> Vec<u32> {
        let g = space.geometry();
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        for i in (0..g.len()).filter(|&i| space.reachable[i]) {
            let c = g.cell(i);
            (x0, y0, x1, y1) = (x0.min(c.x), y0.min(c.y), x1.max(c.x), y1.max(c.y));
        }
        if x0 == usize::MAX {
            return vec![NO_REGION; g.len()];
        }
        let min_side_cells = 4.0 * 2.0 * space.robot.radius_m / g.resolution;
        let side = (params.target_area(space).sqrt() / g.resolution)
            .max(min_side_cells)
            .max(1.0);
        // Equal blocks: n parts along each axis, each at least `side` cells.
        let nx = (((x1 - x0 + 1) as f64 / side).floor() as usize).max(1);
        let ny = (((y1 - y0 + 1) as f64 / side).floor() as usize).max(1);
        let (bw, bh) = ((x1 - x0 + 1) as f64 / nx as f64, (y1 - y0 + 1) as f64 / ny as f64);
        (0..g.len())
            .map(|i| {
                if !space.reachable[i] {
                    return NO_REGION;
                }
                let c = g.cell(i);
                let bx = (((c.x - x0) as f64 / bw) as usize).min(nx - 1);
                let by = (((c.y - y0) as f64 / bh) as usize).min(ny - 1);
                (by * nx + bx) as u32
            })
            .collect()
    }
}
