//! What a tour costs ([`tour_cost`]) and the exact option assignment for a fixed order ([`best_options`],
//! [`dp_options`]), over a [`CostModel`]: the caller's problem as given, or the solvers' clamped instance.

use super::{Tour, TourProblem};

impl Tour {
    /// A tour of `order` with `options`, its cost computed by [`tour_cost`].
    pub fn new(problem: &TourProblem, order: Vec<usize>, options: Vec<usize>) -> Self {
        let cost = tour_cost(problem, &order, &options);
        Self { order, options, cost }
    }
}

/// Cost of visiting `order` with `options`, metres (formula in the module docs). An empty tour costs 0.
/// Distances or option costs that are NaN or infinite count as `+∞`, so the result is never NaN; a node or
/// option index out of range, or slices of different lengths, also give `+∞`. O(n).
pub fn tour_cost(problem: &TourProblem, order: &[usize], options: &[usize]) -> f64 {
    if order.len() != options.len() {
        return f64::INFINITY;
    }
    let view = RawView(problem);
    let mut acc = 0.0;
    let mut prev = problem.depot;
    for (&v, &o) in order.iter().zip(options) {
        if o >= view.n_options(v) {
            return f64::INFINITY;
        }
        let opt = view.option(v, o);
        acc += view.dist(prev, opt.entry);
        acc += opt.cost;
        prev = opt.exit;
    }
    if problem.closed && !order.is_empty() {
        acc += view.dist(prev, problem.depot);
    }
    acc
}

/// Optimal options for a fixed order (dynamic programming over the sequence, O(n·k²) time, O(n·k) memory
/// for k options per node). Returns the option index for each `order[k]` and the resulting [`tour_cost`].
/// Ties go to the lowest option index. Out-of-range node indices get option 0 and make the cost `+∞`.
pub fn best_options(problem: &TourProblem, order: &[usize]) -> (Vec<usize>, f64) {
    let (options, _) = dp_options(&RawView(problem), order);
    let cost = tour_cost(problem, order, &options);
    (options, cost)
}

/// An option as the cost models see it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Opt {
    pub entry: usize,
    pub exit: usize,
    pub cost: f64,
    pub rev: usize,
}

/// What the dynamic programme needs to know about a problem.
pub(crate) trait CostModel {
    fn depot(&self) -> usize;
    fn closed(&self) -> bool;
    fn dist(&self, a: usize, b: usize) -> f64;
    fn n_options(&self, node: usize) -> usize;
    fn option(&self, node: usize, o: usize) -> Opt;
}

/// The caller's problem with non-finite values mapped to `+∞` and missing nodes/options to one unusable
/// option (used by the public [`tour_cost`] and [`best_options`]).
struct RawView<'p>(&'p TourProblem);

fn raw(x: f64) -> f64 {
    if x.is_finite() { x } else { f64::INFINITY }
}

impl CostModel for RawView<'_> {
    fn depot(&self) -> usize {
        self.0.depot
    }
    fn closed(&self) -> bool {
        self.0.closed
    }
    fn dist(&self, a: usize, b: usize) -> f64 {
        raw(self.0.dist.get(a, b))
    }
    fn n_options(&self, node: usize) -> usize {
        self.0.nodes.get(node).map_or(1, |o| o.len().max(1))
    }
    fn option(&self, node: usize, o: usize) -> Opt {
        match self.0.nodes.get(node).and_then(|opts| opts.get(o)) {
            Some(t) => Opt {
                entry: t.entry,
                exit: t.exit,
                cost: raw(t.cost),
                rev: t.reverse,
            },
            None => Opt {
                entry: usize::MAX,
                exit: usize::MAX,
                cost: f64::INFINITY,
                rev: o,
            },
        }
    }
}

/// The dynamic programme behind [`best_options`]: f[k][o] = min over o' of f[k−1][o'] + d(exit o', entry o)
/// + cost o, summed in the same order as [`tour_cost`] so the two agree to the last bit.
pub(crate) fn dp_options<C: CostModel>(m: &C, order: &[usize]) -> (Vec<usize>, f64) {
    if order.is_empty() {
        return (Vec::new(), 0.0);
    }
    let mut start = Vec::with_capacity(order.len() + 1);
    start.push(0usize);
    for &v in order {
        let s = start.last().copied().unwrap_or(0);
        start.push(s + m.n_options(v));
    }
    let total = start.last().copied().unwrap_or(0);
    let mut f = vec![0.0f64; total];
    let mut back = vec![0usize; total];
    for (o, f0) in f.iter_mut().take(m.n_options(order[0])).enumerate() {
        let opt = m.option(order[0], o);
        *f0 = m.dist(m.depot(), opt.entry) + opt.cost;
    }
    for k in 1..order.len() {
        let (prev, cur) = (order[k - 1], order[k]);
        for o in 0..m.n_options(cur) {
            let opt = m.option(cur, o);
            let mut best = (f64::INFINITY, 0usize, false);
            for p in 0..m.n_options(prev) {
                let x = f[start[k - 1] + p] + m.dist(m.option(prev, p).exit, opt.entry);
                if !best.2 || x.total_cmp(&best.0).is_lt() {
                    best = (x, p, true);
                }
            }
            f[start[k] + o] = best.0 + opt.cost;
            back[start[k] + o] = best.1;
        }
    }
    let last = order.len() - 1;
    let mut best = (f64::INFINITY, 0usize, false);
    for o in 0..m.n_options(order[last]) {
        let mut x = f[start[last] + o];
        if m.closed() {
            x += m.dist(m.option(order[last], o).exit, m.depot());
        }
        if !best.2 || x.total_cmp(&best.0).is_lt() {
            best = (x, o, true);
        }
    }
    let mut options = vec![0usize; order.len()];
    options[last] = best.1;
    for k in (1..order.len()).rev() {
        options[k - 1] = back[start[k] + options[k]];
    }
    (options, best.0)
}
