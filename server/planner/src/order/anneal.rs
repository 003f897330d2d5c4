//! Simulated annealing (seed 004 §3.4.3, Metropolis acceptance with geometric cooling).
//!
//! Starts from the [`super::TwoOpt`] local optimum. Each step draws a random node u and one move around it:
//! a 2-opt move that makes u adjacent to a random neighbour of u (45 %), an Or-opt move of the chain of 1–3
//! nodes starting at u to a gap next to a random neighbour, reversed at random or with a random option for a
//! single node (45 %), or a new option for u in place (10 %). A move of delta Δ metres is accepted when
//! Δ ≤ 0 or with probability exp(−Δ / T).
//!
//! **Temperature.** Before annealing, `samples` random moves are evaluated at the 2-opt optimum; Δ⁺ is the
//! mean of their positive deltas (moves across "very expensive" edges are left out), the typical cost of
//! leaving the optimum. T₀ = −Δ⁺ / ln(p₀) makes such a move accepted with probability p₀
//! (`initial_acceptance`, default 0.03), and the schedule ends at T_end = `cooling` × T₀ (default 0.01).
//! The temperature is multiplied by α = (T_end / T₀)^(1 / steps) after each step — a geometric schedule
//! that reaches T_end at the last planned step, where steps = min(`steps`, budget left). The defaults were
//! chosen on 200-node random Euclidean instances (p₀ from 0.01 to 0.3 and cooling from 10⁻⁴ to 10⁻² all
//! landed within 0.5 % of each other).
//!
//! The best tour seen is kept (copied just before the walk leaves it by an uphill move), polished with
//! local search and the exact option assignment, and returned if it beats the 2-opt result.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::local_search::{Move, Search, State, WorkQueue, better, local_optimum};
use super::{BIG, Orderer, SolveBudget, Tour, TourProblem, TwoOptParams, improves};

/// Knobs of simulated annealing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnnealParams {
    /// The local search that makes the start and polishes the result.
    pub two_opt: TwoOptParams,
    /// Annealing steps (one move evaluated each); `None` = 2000 per node. The budget may end them earlier.
    pub steps: Option<u64>,
    /// Probability p₀ of accepting a mean uphill move at the start, in (0, 1).
    pub initial_acceptance: f64,
    /// Final temperature as a fraction of the initial one, in (0, 1].
    pub cooling: f64,
    /// Random moves evaluated to calibrate the temperature.
    pub samples: usize,
}

impl Default for AnnealParams {
    fn default() -> Self {
        Self {
            two_opt: TwoOptParams::default(),
            steps: None,
            initial_acceptance: 0.03,
            cooling: 1e-2,
            samples: 1000,
        }
    }
}

/// Simulated annealing (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Anneal {
    /// Its parameters.
    pub params: AnnealParams,
}

impl Orderer for Anneal {
    fn solve(&self, problem: &TourProblem, seed: u64, budget: &SolveBudget<'_>) -> Tour {
        let (initial, result) = local_optimum(problem, &self.params.two_opt, budget);
        let Some((mut search, start)) = result else {
            return initial;
        };
        let two_opt = better(problem, initial, &start);
        let n = search.inst.n;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);

        let mut sum = 0.0;
        let mut count = 0u32;
        for _ in 0..self.params.samples {
            if !search.meter.tick() {
                break;
            }
            if let Some(mv) = random_move(&search, &start, &mut rng) {
                let (removed, added) = search.delta(&start, mv);
                let d = added - removed;
                if d > 0.0 && d < BIG / 2.0 {
                    sum += d;
                    count += 1;
                }
            }
        }
        let p0 = clamp_probability(self.params.initial_acceptance, 0.03);
        let cooling = if self.params.cooling > 0.0 && self.params.cooling <= 1.0 {
            self.params.cooling
        } else {
            1e-2
        };
        let steps = self
            .params
            .steps
            .unwrap_or(2000 * n as u64)
            .min(search.meter.remaining());
        if count == 0 || sum <= 0.0 || steps == 0 {
            return two_opt;
        }
        let mean_up = sum / f64::from(count);
        let t0 = -mean_up / p0.ln();
        let t_end = t0 * cooling;
        let alpha = (t_end / t0).powf(1.0 / steps as f64);

        let mut queue = WorkQueue::new(n);
        let mut best = start.clone();
        let mut cur = start;
        let mut temp = t0;
        for _ in 0..steps {
            if !search.meter.tick() {
                break;
            }
            if let Some(mv) = random_move(&search, &cur, &mut rng) {
                let (removed, added) = search.delta(&cur, mv);
                let d = added - removed;
                let accept = d <= 0.0 || rng.random::<f64>() < (-d / temp).exp();
                if accept {
                    if d > 0.0 && improves(best.cost, cur.cost) {
                        best.clone_from(&cur);
                    }
                    search.apply(&mut cur, mv, (removed, added), &mut queue);
                }
            }
            temp *= alpha;
        }
        if improves(best.cost, cur.cost) {
            best = cur;
        }
        // The walk queued nodes as it went; polish the best from scratch instead.
        let mut queue = WorkQueue::new(n);
        queue.push(n);
        for &v in &best.order {
            queue.push(v);
        }
        search.optimise(&mut best, &mut queue);
        better(problem, two_opt, &best)
    }
}

fn clamp_probability(p: f64, default: f64) -> f64 {
    if p.is_finite() && p > 0.0 && p < 1.0 {
        p
    } else {
        default
    }
}

/// A random move around a random node of `st` (see the module docs), or `None` when the draw is not a
/// valid move.
pub(crate) fn random_move(search: &Search<'_, '_>, st: &State, rng: &mut ChaCha8Rng) -> Option<Move> {
    let n = st.order.len();
    let closed = search.inst.closed;
    let u = rng.random_range(0..n);
    let x = st.pos[u];
    let random_slot = |v: usize, rng: &mut ChaCha8Rng| {
        let (slots, count) = search.slots(st, v);
        slots[rng.random_range(0..count)]
    };
    let nb = search.neighbours(u);
    let kind = rng.random_range(0..20);
    if kind < 9 {
        if !search.inst.reversible {
            return None;
        }
        if !closed && rng.random_range(0..10) == 0 {
            let i = x - rng.random_range(0..2);
            return (i < n).then_some(Move::TwoOpt { i, j: n });
        }
        let v = *nb.get(rng.random_range(0..nb.len().max(1)))?;
        let y = random_slot(v, rng);
        let (lo, hi) = (x.min(y), x.max(y));
        if lo == hi {
            return None;
        }
        if rng.random_bool(0.5) {
            (hi <= n).then_some(Move::TwoOpt { i: lo, j: hi })
        } else {
            (lo >= 1).then(|| Move::TwoOpt { i: lo - 1, j: hi - 1 })
        }
    } else if kind < 18 {
        let len = rng.random_range(1..=search.max_chain());
        let (a, b) = (x, x + len - 1);
        if b > n {
            return None;
        }
        let t = if !closed && rng.random_range(0..10) == 0 {
            n
        } else {
            let v = *nb.get(rng.random_range(0..nb.len().max(1)))?;
            let y = random_slot(v, rng);
            if rng.random_bool(0.5) { y.checked_sub(1)? } else { y }
        };
        if t > n || (t + 1 >= a && t <= b) {
            return None;
        }
        if len == 1 {
            let o = rng.random_range(0..search.inst.k(u));
            Some(Move::OrOpt {
                a,
                b,
                t,
                reversed: false,
                o,
            })
        } else {
            let reversed = rng.random_bool(0.5) && search.inst.reversible;
            Some(Move::OrOpt {
                a,
                b,
                t,
                reversed,
                o: 0,
            })
        }
    } else {
        let k = search.inst.k(u);
        if k < 2 {
            return None;
        }
        let o = rng.random_range(0..k);
        (o != st.opt[x - 1]).then_some(Move::Reopt { s: x, o })
    }
}
