//! Visiting order (DESIGN §4 "Order", seed 004 §3.4): in which order, and in which direction, the robot
//! visits the coverage regions (or, inside a region, its lanes) before it returns to the dock.
//!
//! The problem is a *generalised* travelling-salesman problem. Every node has one or more traversal
//! [`TourOption`]s; an option enters at one point and leaves at another, both indices into a symmetric
//! [`DistanceMatrix`] of metres (real grid-path lengths, so obstacles are already priced in). A tour starts
//! at the depot point, visits every node once with one chosen option and, when the problem is `closed`,
//! returns to the depot. Its cost is
//!
//! ```text
//! d(depot, entry_1) + cost_1 + d(exit_1, entry_2) + cost_2 + … + cost_n [+ d(exit_n, depot) if closed]
//! ```
//!
//! Strategies (each an [`Orderer`], chosen with [`OrderMethod`]):
//! - [`TwoOpt`] — construction ([`construct`]), then 2-opt and Or-opt local search with O(1) move deltas,
//!   alternating with the exact option assignment [`best_options`] until neither improves (seed 004 §3.4.1);
//! - [`RecordToRecord`] — from the 2-opt result: perturb (segment-local double bridge or a random swap),
//!   repair by local search, accept when within a deviation of the record (seed 004 §3.4.2);
//! - [`Anneal`] — from the 2-opt result: Metropolis acceptance over random 2-opt / Or-opt / option moves with
//!   a geometric cooling schedule (seed 004 §3.4.3).
//!
//! The three share one local search (`local_search/`: the tour state, the moves and their O(1) deltas,
//! neighbour lists, the descent); [`TwoOpt`] is its solver face.
//!
//! All strategies are deterministic: the same problem, seed and budget give the same [`Tour`]. Work is bounded
//! by [`SolveBudget::max_iterations`] (moves evaluated); [`SolveBudget::stop`] can only cut it short. Every
//! strategy returns a valid tour, at worst the construction.
//!
//! Non-finite or huge numbers never panic: inside the solvers every distance or option cost that is NaN,
//! infinite or larger than 10¹² m is treated as 10¹² m ("very expensive"); [`tour_cost`] reports such tours
//! as `f64::INFINITY`. Call [`TourProblem::validate`] to reject malformed problems with a clear error.

mod anneal;
mod budget;
mod construct;
mod cost;
mod instance;
mod local_search;
mod matrix;
mod problem;
mod rrt;
#[cfg(test)]
mod tests;
#[cfg(test)]
pub(crate) mod testutil;
mod two_opt;

pub use anneal::{Anneal, AnnealParams};
pub use budget::SolveBudget;
pub use construct::{Construction, construct};
pub use cost::{best_options, tour_cost};
pub use local_search::TwoOptParams;
pub use matrix::DistanceMatrix;
pub use problem::{Tour, TourOption, TourProblem};
pub use rrt::{RecordToRecord, RrtParams};
pub use two_opt::TwoOpt;

use budget::Meter;
use cost::{CostModel, Opt, dp_options};
use instance::{BIG, Inst, improves};

/// A visiting-order strategy.
pub trait Orderer: Send + Sync {
    /// Solves `problem` deterministically for `seed` within `budget`. Always returns a tour that visits
    /// every node once (at worst the construction), whose `cost` equals [`tour_cost`] of it.
    fn solve(&self, problem: &TourProblem, seed: u64, budget: &SolveBudget<'_>) -> Tour;
}

/// The visiting-order strategies, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum OrderMethod {
    /// 2-opt + Or-opt local search with exact option assignment ([`TwoOpt`]).
    TwoOpt,
    /// Record-to-record travel ([`RecordToRecord`]). The default: it starts from the 2-opt optimum and
    /// returns its record, so it is never longer than 2-opt alone, and it escapes the local optima 2-opt
    /// stops in on sites with many regions.
    #[default]
    RecordToRecord,
    /// Simulated annealing ([`Anneal`]).
    Anneal,
}

impl OrderMethod {
    /// Every method, in documentation order.
    pub const ALL: [OrderMethod; 3] = [OrderMethod::TwoOpt, OrderMethod::RecordToRecord, OrderMethod::Anneal];

    /// The method's name as users spell it: `"two-opt"`, `"rrt"` or `"anneal"`.
    pub fn name(self) -> &'static str {
        match self {
            OrderMethod::TwoOpt => "two-opt",
            OrderMethod::RecordToRecord => "rrt",
            OrderMethod::Anneal => "anneal",
        }
    }

    /// The strategy with its default parameters.
    pub fn orderer(self) -> Box<dyn Orderer> {
        match self {
            OrderMethod::TwoOpt => Box::new(TwoOpt::default()),
            OrderMethod::RecordToRecord => Box::new(RecordToRecord::default()),
            OrderMethod::Anneal => Box::new(Anneal::default()),
        }
    }
}

impl std::fmt::Display for OrderMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for OrderMethod {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, Self::Err> {
        OrderMethod::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<&str> = OrderMethod::ALL.iter().map(|m| m.name()).collect();
            format!("unknown order method {s:?}; expected one of {}", names.join(", "))
        })
    }
}
