//! Step 3 of [`divide`](super::divide): who owns each cell, parts made connected, and each part's masks.

use std::collections::VecDeque;

use super::balance::Table;
use super::{NO_OWNER, RobotField};
use crate::map::{Cell, DistanceField};
use crate::space::{CoverageSpace, flood_fill8};

/// Owner of every grid cell some robot can reach, for `weights` ([`NO_OWNER`] elsewhere).
pub(super) fn assign(table: &Table, weights: &[f64], cells: usize) -> Vec<u32> {
    let mut owner = vec![NO_OWNER; cells];
    for (k, &i) in table.cells.iter().enumerate() {
        if let Some(r) = table.owner(k, weights) {
            owner[i as usize] = r as u32;
        }
    }
    owner
}

/// Keeps of each part only what its robot reaches from its start inside the part, then hands the cells
/// this frees to a neighbouring part whose robot can reach them (breadth first from every part at once).
/// Returns how many reachable cells were left to nobody.
pub(super) fn make_connected(fields: &[RobotField], owner: &mut [u32]) -> usize {
    let g = *fields[0].space.geometry();
    let mut queue = VecDeque::new();
    for (r, f) in fields.iter().enumerate() {
        let mine: Vec<bool> = (0..g.len())
            .map(|i| owner[i] == r as u32 && f.space.reachable[i])
            .collect();
        let kept = flood_fill8(&g, &mine, f.start_cell);
        for i in 0..g.len() {
            if owner[i] == r as u32 && !kept[i] {
                owner[i] = NO_OWNER;
            }
        }
    }
    for (i, &o) in owner.iter().enumerate() {
        if o != NO_OWNER {
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        let o = owner[i];
        for n in g.neighbors8(g.cell(i)) {
            let j = g.index(n);
            if owner[j] == NO_OWNER && fields[o as usize].space.reachable[j] {
                owner[j] = o;
                queue.push_back(j);
            }
        }
    }
    (0..g.len())
        .filter(|&i| owner[i] == NO_OWNER && fields.iter().any(|f| f.space.reachable[i]))
        .count()
}

/// Gives every coverable cell that no robot stands on (beside walls and obstacles) to the owner of the
/// reachable cell nearest to it, among the robots that can cover it.
pub(super) fn extend_to_coverable(fields: &[RobotField], owner: &mut [u32]) {
    let n = owner.len();
    let mut ext = vec![NO_OWNER; n];
    for (i, e) in ext.iter_mut().enumerate() {
        if owner[i] != NO_OWNER {
            continue;
        }
        let mut fallback = NO_OWNER;
        for (r, f) in fields.iter().enumerate().filter(|(_, f)| f.space.coverable[i]) {
            let near = f.to_reachable.nearest_site_index(i).map_or(NO_OWNER, |j| owner[j]);
            if near == r as u32 {
                fallback = near;
                break;
            }
            if fallback == NO_OWNER && near != NO_OWNER && fields[near as usize].space.coverable[i] {
                fallback = near;
            }
        }
        *e = fallback;
    }
    for (o, e) in owner.iter_mut().zip(ext) {
        if *o == NO_OWNER {
            *o = e;
        }
    }
}

/// Robot `r`'s masks: where its centre may go, and what it covers.
///
/// It covers the cells it owns plus `seam_cells` cells into its neighbours' parts. Its centre stays on the
/// cells it owns at least `inset_m` (half its tool) from every other part, so that its swath ends at the
/// boundary instead of sweeping half a tool into the neighbour's part (both neighbours would, and the seam
/// would be swept twice a tool wide); it gets back the cells near the corners where a wall meets the
/// boundary (their coverable cells are out of reach of the inset). Pieces the inset cuts off from its start
/// are joined back by the shortest way through its own reachable cells (a doorway beside the boundary);
/// only when that fails does the part keep its full extent.
pub(super) fn part_masks(
    space: &CoverageSpace,
    start_cell: Cell,
    owner: &[u32],
    r: u32,
    seam_cells: usize,
    inset_m: f64,
) -> (Vec<bool>, Vec<bool>) {
    let g = space.geometry();
    let own: Vec<bool> = owner.iter().map(|&o| o == r).collect();
    let mut cover = own.clone();
    for _ in 0..seam_cells {
        let grown: Vec<bool> = (0..g.len())
            .map(|i| cover[i] || (owner[i] != NO_OWNER && g.neighbors8(g.cell(i)).any(|c| cover[g.index(c)])))
            .collect();
        cover = grown;
    }
    let others = DistanceField::compute(*g, |i| owner[i] != NO_OWNER && owner[i] != r, false);
    let mut keep: Vec<bool> = (0..g.len())
        .map(|i| own[i] && space.reachable[i] && others.at(i) >= inset_m - 1e-9)
        .collect();
    // Cells the inset centre cannot reach within half a tool (corners where a wall meets the boundary) get
    // back the reachable cells near them.
    let half = space.robot.tool_width_m / 2.0 + 1e-9;
    let to_keep = DistanceField::compute(*g, |i| keep[i], false);
    let missing: Vec<bool> = (0..g.len())
        .map(|i| own[i] && space.coverable[i] && to_keep.at(i) > half)
        .collect();
    if missing.iter().any(|&m| m) {
        let to_missing = DistanceField::compute(*g, |i| missing[i], false);
        for (i, k) in keep.iter_mut().enumerate() {
            *k |= own[i] && space.reachable[i] && to_missing.at(i) <= half;
        }
    }
    let connected = flood_fill8(g, &keep, start_cell);
    if keep.iter().zip(&connected).all(|(k, c)| k == c) {
        return (keep, cover);
    }
    // Pieces the inset cut off from the start (a cell or two behind an obstacle's corner, most often) are
    // joined back by the shortest way through the part's own reachable cells: the centre may leave the inset
    // there and nowhere else (before, one such cell gave the whole part its full extent, and its swath half a
    // tool into every neighbour).
    let passable: Vec<bool> = (0..g.len()).map(|i| own[i] && space.reachable[i]).collect();
    let mut joined = connected;
    let mut parent = vec![usize::MAX; g.len()];
    let mut queue: VecDeque<usize> = (0..g.len()).filter(|&i| joined[i]).collect();
    let mut seen = joined.clone();
    while let Some(i) = queue.pop_front() {
        for n in g.neighbors8(g.cell(i)) {
            let j = g.index(n);
            if seen[j] || !passable[j] {
                continue;
            }
            seen[j] = true;
            parent[j] = i;
            if keep[j] {
                // A cut-off cell: keep the way back to the joined set.
                let mut k = j;
                while k != usize::MAX && !joined[k] {
                    joined[k] = true;
                    k = parent[k];
                }
            }
            queue.push_back(j);
        }
    }
    if keep.iter().zip(&joined).all(|(k, j)| !k || *j) {
        (joined, cover)
    } else {
        (own, cover)
    }
}
