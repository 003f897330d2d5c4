//! A visiting-order problem (the depot, the nodes with their traversal options, the distances) and its
//! solution, a [`Tour`].

use super::DistanceMatrix;
use crate::error::{PlannerError, Result};

/// One way to traverse a node: enter at point `entry`, leave at point `exit` (indices into the matrix),
/// paying `cost` metres inside. `reverse` is the index (within the same node's option list) of the option
/// that traverses the same route backwards (entry/exit swapped, same cost); it may be the option itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TourOption {
    /// Point where the robot enters the node (index into the [`DistanceMatrix`]).
    pub entry: usize,
    /// Point where the robot leaves the node (index into the [`DistanceMatrix`]).
    pub exit: usize,
    /// Length travelled inside the node with this option, metres.
    pub cost: f64,
    /// Index, in the same node's option list, of the same route driven backwards.
    pub reverse: usize,
}

/// A visiting-order problem: a depot, the nodes with their options, and the distances between points.
#[derive(Debug, Clone, PartialEq)]
pub struct TourProblem {
    /// Symmetric point-to-point distances, metres.
    pub dist: DistanceMatrix,
    /// Point index where the tour starts (and ends when `closed`).
    pub depot: usize,
    /// The nodes to visit; each has at least one option.
    pub nodes: Vec<Vec<TourOption>>,
    /// True: return to the depot at the end; false: open path ending at the last exit.
    pub closed: bool,
}

/// Relative tolerance for "the reverse option has the same cost" in [`TourProblem::validate`].
const REVERSE_COST_TOL: f64 = 1e-9;

impl TourProblem {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True when there is no node to visit.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Checks everything a solver relies on: the depot and every entry/exit point lie in the matrix, every
    /// node has an option, costs and distances are not NaN and not negative (`+∞` is allowed and means "very
    /// expensive"), and every `reverse` is in range, swaps entry and exit, has the same cost (relative
    /// tolerance 10⁻⁹) and reverses back. O(points² + options).
    ///
    /// Solvers never panic on a problem that fails this check, but their tours may then be poor or cost
    /// `f64::INFINITY`.
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| {
            Err(PlannerError::InvalidParam {
                name: "order problem",
                reason,
            })
        };
        let points = self.dist.len();
        if self.depot >= points {
            return bad(format!(
                "depot point {} is outside the distance matrix ({points} points)",
                self.depot
            ));
        }
        for i in 0..points {
            for j in i..points {
                let d = self.dist.get(i, j);
                if d.is_nan() || d < 0.0 {
                    return bad(format!(
                        "distance between points {i} and {j} is {d}; it must be ≥ 0 or +inf"
                    ));
                }
            }
        }
        for (v, opts) in self.nodes.iter().enumerate() {
            if opts.is_empty() {
                return bad(format!("node {v} has no traversal option"));
            }
            for (k, o) in opts.iter().enumerate() {
                if o.entry >= points || o.exit >= points {
                    return bad(format!(
                        "node {v} option {k}: entry {} / exit {} outside the distance matrix ({points} points)",
                        o.entry, o.exit
                    ));
                }
                if o.cost.is_nan() || o.cost < 0.0 {
                    return bad(format!("node {v} option {k}: cost {} must be ≥ 0 or +inf", o.cost));
                }
                let Some(r) = opts.get(o.reverse) else {
                    return bad(format!(
                        "node {v} option {k}: reverse {} out of range ({} options)",
                        o.reverse,
                        opts.len()
                    ));
                };
                let same_cost = r.cost == o.cost
                    || (r.cost - o.cost).abs() <= REVERSE_COST_TOL * r.cost.abs().max(o.cost.abs()).max(1.0);
                if r.entry != o.exit || r.exit != o.entry || !same_cost || r.reverse != k {
                    return bad(format!(
                        "node {v} option {k}: option {} is not its reverse \
                         (needs entry {}, exit {}, cost {}, reverse {k})",
                        o.reverse, o.exit, o.entry, o.cost
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A visiting order: `order[k]` is the k-th node visited, with option `options[k]`; `cost` is
/// [`super::tour_cost`] of the two, metres.
#[derive(Clone, Debug, PartialEq)]
pub struct Tour {
    /// Node indices in visiting order (a permutation of `0..problem.nodes.len()`).
    pub order: Vec<usize>,
    /// Option index (into `problem.nodes[order[k]]`) used for `order[k]`.
    pub options: Vec<usize>,
    /// Total cost, metres (see the module docs).
    pub cost: f64,
}

impl Tour {
    /// Checks that the tour visits every node of `problem` exactly once with an existing option.
    pub fn check(&self, problem: &TourProblem) -> Result<()> {
        let bad = |reason: String| Err(PlannerError::InvalidParam { name: "tour", reason });
        let n = problem.nodes.len();
        if self.order.len() != n || self.options.len() != n {
            return bad(format!(
                "{} nodes and {} options for a problem of {n} nodes",
                self.order.len(),
                self.options.len()
            ));
        }
        let mut seen = vec![false; n];
        for (&v, &o) in self.order.iter().zip(&self.options) {
            if v >= n || seen[v] {
                return bad(format!("node {v} is out of range or visited twice"));
            }
            seen[v] = true;
            if o >= problem.nodes[v].len() {
                return bad(format!("node {v} has no option {o}"));
            }
        }
        Ok(())
    }
}
