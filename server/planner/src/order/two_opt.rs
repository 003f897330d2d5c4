//! The 2-opt strategy ([`TwoOpt`], `"two-opt"`): the shared local search (2-opt and Or-opt moves with exact
//! option assignment, `order/local_search/`) run once from the construction (seed 004 §3.4.1).

use super::local_search::{TwoOptParams, better, local_optimum};
use super::{Orderer, SolveBudget, Tour, TourProblem};

/// 2-opt + Or-opt local search with exact option assignment (see the module docs). The seed is not used:
/// the search is deterministic by construction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TwoOpt {
    /// Its parameters.
    pub params: TwoOptParams,
}

impl Orderer for TwoOpt {
    fn solve(&self, problem: &TourProblem, _seed: u64, budget: &SolveBudget<'_>) -> Tour {
        let (initial, result) = local_optimum(problem, &self.params, budget);
        match result {
            Some((_, st)) => better(problem, initial, &st),
            None => initial,
        }
    }
}
