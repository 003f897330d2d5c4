//! The outline a decomposition should see: the reachable set without the details smaller than the tool.
//!
//! Real maps have ragged walls, ray fans and specks of noise. Each bay in a ragged wall and each speck is a
//! critical point for the boustrophedon sweep, so the raw reachable set splits into many thin cells — and
//! every cell costs a transit, lane ends and a frame. The sweep therefore runs on a simplified outline:
//! 1. a morphological opening by a disc of radius `rho` removes bays and spurs narrower than `2 rho`;
//! 2. holes smaller than `max_hole_cells` (specks, thin posts) are filled — lanes split around them and the
//!    in-region routing links the pieces, which is cheaper than separate cells.
//!
//! [`assign_rest`] then gives every reachable cell outside the outline the label of its nearest labelled
//! cell (breadth-first through reachable cells), so the partition still covers the whole reachable set.

use std::collections::VecDeque;

use super::NO_REGION;
use crate::map::DistanceField;
use crate::space::CoverageSpace;

/// The simplified reachable mask (see the module docs). `rho` in metres.
pub fn outline(space: &CoverageSpace, rho: f64, max_hole_cells: usize) -> Vec<bool> {
    let g = *space.geometry();
    let r = space.robot.radius_m;
    // Erosion: reachable cells at least rho deeper than the traversable limit.
    let eroded: Vec<bool> = (0..g.len())
        .map(|i| space.reachable[i] && space.clearance.at(i) >= r + rho - 1e-9)
        .collect();
    if !eroded.iter().any(|&e| e) {
        return space.reachable.clone();
    }
    // Dilation back by rho, inside the reachable set.
    let near = DistanceField::compute(g, |i| eroded[i], false);
    let mut mask: Vec<bool> = (0..g.len())
        .map(|i| space.reachable[i] && near.at(i) <= rho + 1e-9)
        .collect();
    // Fill small holes: 4-connected components of the complement that do not touch the map edge.
    let mut seen = vec![false; g.len()];
    let mut queue = VecDeque::new();
    let mut comp = Vec::new();
    for s in 0..g.len() {
        if mask[s] || seen[s] {
            continue;
        }
        seen[s] = true;
        queue.push_back(s);
        comp.clear();
        let mut touches_edge = false;
        while let Some(i) = queue.pop_front() {
            comp.push(i);
            let c = g.cell(i);
            if g.neighbors4(c).count() < 4 {
                touches_edge = true;
            }
            for n in g.neighbors4(c) {
                let j = g.index(n);
                if !mask[j] && !seen[j] {
                    seen[j] = true;
                    queue.push_back(j);
                }
            }
        }
        if !touches_edge && comp.len() <= max_hole_cells {
            for &i in &comp {
                mask[i] = true;
            }
        }
    }
    mask
}

/// Gives every reachable cell without a label the label of its nearest labelled reachable cell (breadth-first
/// through 8-connected reachable cells, deterministic). Cells no labelled cell reaches keep `NO_REGION`.
pub fn assign_rest(space: &CoverageSpace, labels: &mut [u32]) {
    let g = *space.geometry();
    let mut queue: VecDeque<usize> = (0..g.len())
        .filter(|&i| space.reachable[i] && labels[i] != NO_REGION)
        .collect();
    while let Some(i) = queue.pop_front() {
        for n in g.neighbors8(g.cell(i)) {
            let j = g.index(n);
            if space.reachable[j] && labels[j] == NO_REGION {
                labels[j] = labels[i];
                queue.push_back(j);
            }
        }
    }
}
