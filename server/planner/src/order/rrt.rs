//! Record-to-record travel (seed 004 §3.4.2, after Dueck 1993).
//!
//! Starts from the [`super::TwoOpt`] local optimum, which is the first record. Each round copies the
//! current tour, perturbs it — a segment-local double bridge (A B C D → A C B D with B and C of at most
//! `max_segment` nodes) or, as in the seed, a swap of two nodes at most `max_segment` slots apart — and
//! repairs it with the 2-opt/Or-opt local search started from the nodes at the broken edges only. The
//! candidate becomes the current tour when its cost is below `record × (1 + deviation)`; when it beats the
//! record it is polished with the exact option assignment and becomes the new record. The record is
//! returned, so the result is never worse than the 2-opt result for the same seed and budget.
//!
//! One round costs O(n) for the copy plus the repair, typically O(K·k) move evaluations per touched node.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::local_search::{Search, State, WorkQueue, better, local_optimum};
use super::{Orderer, SolveBudget, Tour, TourProblem, TwoOptParams, improves};

/// Knobs of record-to-record travel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RrtParams {
    /// The local search that makes the start and repairs each perturbation.
    pub two_opt: TwoOptParams,
    /// Rounds (perturbation + repair); `None` = 500 + 5 per node. The budget may end them earlier.
    pub rounds: Option<u64>,
    /// A candidate is accepted when its cost is below record × (1 + deviation).
    pub deviation: f64,
    /// Longest segment moved by one perturbation, nodes.
    pub max_segment: usize,
}

impl Default for RrtParams {
    fn default() -> Self {
        Self {
            two_opt: TwoOptParams::default(),
            rounds: None,
            deviation: 0.005,
            max_segment: 30,
        }
    }
}

/// Record-to-record travel (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RecordToRecord {
    /// Its parameters.
    pub params: RrtParams,
}

impl Orderer for RecordToRecord {
    fn solve(&self, problem: &TourProblem, seed: u64, budget: &SolveBudget<'_>) -> Tour {
        let (initial, result) = local_optimum(problem, &self.params.two_opt, budget);
        let Some((mut search, start)) = result else {
            return initial;
        };
        let two_opt = better(problem, initial, &start);
        let n = search.inst.n;
        let rounds = self.params.rounds.unwrap_or(500 + 5 * n as u64);
        let deviation = if self.params.deviation.is_finite() {
            self.params.deviation.max(0.0)
        } else {
            0.0
        };
        let max_segment = self.params.max_segment.max(1);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut queue = WorkQueue::new(n);
        let mut record = start.clone();
        let mut current = start.clone();
        let mut cand = start;
        for _ in 0..rounds {
            if !search.meter.tick() {
                break;
            }
            cand.clone_from(&current);
            perturb(&search, &mut cand, &mut rng, max_segment, &mut queue);
            search.local_search(&mut cand, &mut queue);
            if improves(record.cost, cand.cost) {
                search.optimise(&mut cand, &mut queue);
                if improves(record.cost, cand.cost) {
                    record.clone_from(&cand);
                }
                std::mem::swap(&mut current, &mut cand);
            } else if cand.cost < record.cost + deviation * record.cost.abs() {
                std::mem::swap(&mut current, &mut cand);
            }
        }
        better(problem, two_opt, &record)
    }
}

/// Perturbs `st` in place (cost kept exact up to rounding) and queues the nodes at the changed edges.
pub(crate) fn perturb(
    search: &Search<'_, '_>,
    st: &mut State,
    rng: &mut ChaCha8Rng,
    max_segment: usize,
    queue: &mut WorkQueue,
) {
    let n = st.order.len();
    if n < 2 {
        return;
    }
    let touched = if n >= 8 && rng.random_bool(0.5) {
        // Double bridge on slots p1+1..=p3: B = p1+1..=p2, C = p2+1..=p3 → C B.
        let lmax = max_segment.min(n / 2).max(1);
        let len_b = rng.random_range(1..=lmax);
        let len_c = rng.random_range(1..=lmax).min(n - len_b);
        let p1 = rng.random_range(0..=n - len_b - len_c);
        let (p2, p3) = (p1 + len_b, p1 + len_b + len_c);
        let before = [p1, p2, p3];
        let removed: f64 = before.iter().map(|&s| search.edge(st, s)).sum();
        let touched = [p1, p1 + 1, p2, p2 + 1, p3, p3 + 1];
        let touched = touched.map(|s| search.node_at(st, s));
        st.order[p1..p3].rotate_left(len_b);
        st.opt[p1..p3].rotate_left(len_b);
        st.refresh(&search.inst, p1, p3);
        let after = [p1, p1 + len_c, p3];
        let added: f64 = after.iter().map(|&s| search.edge(st, s)).sum();
        st.cost += added - removed;
        touched
    } else {
        // Swap the nodes in slots x < y.
        let x = rng.random_range(1..=n);
        let lo = x.saturating_sub(max_segment).max(1);
        let hi = (x + max_segment).min(n);
        let mut y = rng.random_range(lo..=hi - 1);
        if y >= x {
            y += 1;
        }
        let (x, y) = (x.min(y), x.max(y));
        let mut edges = [x - 1, x, y - 1, y];
        let count = if y == x + 1 {
            edges = [x - 1, x, y, y];
            3
        } else {
            4
        };
        let removed: f64 = edges[..count].iter().map(|&s| search.edge(st, s)).sum();
        let touched = [x - 1, x, x + 1, y - 1, y, y + 1].map(|s| search.node_at(st, s));
        st.order.swap(x - 1, y - 1);
        st.opt.swap(x - 1, y - 1);
        st.refresh(&search.inst, x - 1, x);
        st.refresh(&search.inst, y - 1, y);
        let added: f64 = edges[..count].iter().map(|&s| search.edge(st, s)).sum();
        st.cost += added - removed;
        touched
    };
    for v in touched {
        queue.push(v);
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::super::testutil::{euclid, random_matrix};
    use super::super::{Anneal, OrderMethod, TwoOpt};
    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// Record-to-record travel and annealing keep the best tour, so for the same seed and budget they
        /// are never worse than 2-opt.
        #[test]
        fn never_worse_than_two_opt(
            n in 0usize..50, k in 1usize..=4, closed: bool, metric: bool, seed: u64,
            max_iterations in prop::sample::select(vec![0u64, 1, 300, 5_000, 60_000, u64::MAX]),
        ) {
            let p = if metric { euclid(n, k, closed, seed) } else { random_matrix(n, k, closed, seed) };
            let budget = SolveBudget::new(max_iterations);
            let base = TwoOpt::default().solve(&p, seed, &budget);
            let rrt = RecordToRecord::default().solve(&p, seed, &budget);
            for t in [rrt, Anneal::default().solve(&p, seed, &budget)] {
                prop_assert_eq!(t.check(&p), Ok(()));
                prop_assert!(t.cost <= base.cost, "{} > {}", t.cost, base.cost);
            }
        }
    }

    #[test]
    fn metaheuristics_improve_on_two_opt_at_100_nodes() {
        let mut gains = [0.0f64; 2];
        for seed in 0..3 {
            let p = euclid(100, 4, true, 40 + seed);
            let base = TwoOpt::default().solve(&p, seed, &SolveBudget::unlimited()).cost;
            for (g, m) in gains.iter_mut().zip([OrderMethod::RecordToRecord, OrderMethod::Anneal]) {
                *g += base - m.orderer().solve(&p, seed, &SolveBudget::unlimited()).cost;
            }
        }
        assert!(gains.iter().all(|&g| g > 0.0), "{gains:?}");
    }
}
