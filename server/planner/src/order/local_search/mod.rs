//! The local search every strategy shares: 2-opt and Or-opt moves with exact option assignment (seed 004
//! §3.4.1). [`super::TwoOpt`] returns its local optimum; [`super::RecordToRecord`] and [`super::Anneal`] start
//! from it and repair their perturbations with it.
//!
//! The tour is kept as an array of nodes with the option of each; the depot sits at virtual slot 0 and, for
//! a closed tour, at virtual slot n+1. Three kinds of move are evaluated in O(1) from the current options:
//!
//! - **2-opt**: reverse slots i+1..=j. Every node in the reversed segment switches to its `reverse` option
//!   (same route backwards, same cost), so only the two boundary edges change. For an open tour j = n simply
//!   reverses the tail.
//! - **Or-opt**: move a chain of 1–3 consecutive nodes to another gap, forwards or reversed; a single node
//!   may also switch to any of its options on the way.
//! - (annealing only) **re-option**: one node switches option in place.
//!
//! Candidate moves come from neighbour lists: for every node (and the depot) the `neighbours` nearest nodes
//! by point distance (the least distance between any entry/exit point of one and any of the other). Moves
//! that create an edge between a node and one of its neighbours are tried, only for neighbours nearer than
//! the node's longer tour edge (positive-gain pruning: the new edge must be paid for by one of the node's
//! own edges). The best improving move for a node is applied (first improvement over nodes, best over
//! the node's candidates) and the nodes at the changed edges are queued again ("don't-look bits"). When
//! the queue is empty the exact option assignment ([`super::best_options`], O(n·k²)) is run on the
//! order; if it improves, the nodes whose option changed are queued and the search resumes, until
//! neither improves.
//!
//! Complexity, for n nodes, k options per node, K neighbours and chains up to 3:
//! - construction O(n²·k) (nearest neighbour; see [`super::Construction`]);
//! - neighbour lists O(n²·m²) once, m ≤ 2k distinct points per node — we only have a distance matrix,
//!   no coordinates, so every pair is looked at once (matrix rows are read front to back);
//! - examining one node: O(K·(k + 4)) move evaluations of O(1) each, fewer after pruning; applying a
//!   move: O(length moved) array work;
//! - a pass over all nodes: O(n·K·k) evaluations plus one O(n·k²) assignment — not O(n²)·DP. Memory is
//!   O(n·K) besides the caller's matrix.
//!
//! Measured (2-core machine, random Euclidean, ≤ 4 options per node): 200 nodes in under 10 ms,
//! 1000 in ~0.2 s, 3000 in ~1 s, of which construction and neighbour lists take about half.
//!
//! The result is never longer than the initial tour: every applied move and every accepted assignment
//! strictly lowers the cost, and a final check falls back to the initial tour if rounding ever said
//! otherwise.

mod moves;
mod neighbours;
mod search;
mod state;
#[cfg(test)]
mod tests;

pub(super) use moves::Move;
pub(super) use search::Search;
pub(super) use state::{State, WorkQueue};

use super::construct::construct_order;
use super::{Construction, Inst, Meter, SolveBudget, Tour, TourProblem, dp_options};

/// Knobs of the 2-opt local search (also used by the other strategies to repair their perturbations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoOptParams {
    /// How the initial tour is built.
    pub construction: Construction,
    /// Size of each node's neighbour list (candidate moves per node). Larger is slower and slightly better;
    /// with `neighbours ≥ n` every 2-opt and Or-opt move is examined.
    pub neighbours: usize,
    /// Longest chain an Or-opt move relocates (1–3 is usual).
    pub max_chain: usize,
}

impl Default for TwoOptParams {
    fn default() -> Self {
        Self {
            construction: Construction::NearestNeighbour,
            neighbours: 16,
            max_chain: 3,
        }
    }
}

/// The construction, and (when there is budget and more than one node) the search with the 2-opt local
/// optimum reached from it.
pub(crate) fn local_optimum<'p, 'b>(
    problem: &'p TourProblem,
    params: &TwoOptParams,
    budget: &SolveBudget<'b>,
) -> (Tour, Option<(Search<'p, 'b>, State)>) {
    let inst = Inst::new(problem);
    let order = construct_order(&inst, params.construction);
    let (options, _) = dp_options(&inst, &order);
    let initial = Tour::new(problem, order.clone(), options.clone());
    let mut meter = Meter::new(budget);
    // A single node is solved exactly by the assignment; poll the budget before the O(n²) neighbour build.
    if inst.n < 2 || !meter.tick() {
        return (initial, None);
    }
    let mut st = State::new(&inst, order, options);
    let mut search = Search::new(inst, params, meter);
    search.descend(&mut st);
    (initial, Some((search, st)))
}

/// `st` as a [`Tour`], unless its cost is above `fallback`'s (then `fallback`).
pub(crate) fn better(problem: &TourProblem, fallback: Tour, st: &State) -> Tour {
    let tour = Tour::new(problem, st.order.clone(), st.opt.clone());
    if tour.cost.total_cmp(&fallback.cost).is_lt() {
        tour
    } else {
        fallback
    }
}
