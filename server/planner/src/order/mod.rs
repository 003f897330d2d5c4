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
//! All strategies are deterministic: the same problem, seed and budget give the same [`Tour`]. Work is bounded
//! by [`SolveBudget::max_iterations`] (moves evaluated); [`SolveBudget::stop`] can only cut it short. Every
//! strategy returns a valid tour, at worst the construction.
//!
//! Non-finite or huge numbers never panic: inside the solvers every distance or option cost that is NaN,
//! infinite or larger than 10¹² m is treated as 10¹² m ("very expensive"); [`tour_cost`] reports such tours
//! as `f64::INFINITY`. Call [`TourProblem::validate`] to reject malformed problems with a clear error.

mod anneal;
mod construct;
mod rrt;
mod two_opt;

pub use anneal::{Anneal, AnnealParams};
pub use construct::{Construction, construct};
pub use rrt::{RecordToRecord, RrtParams};
pub use two_opt::{TwoOpt, TwoOptParams};

use crate::error::{PlannerError, Result};

/// Symmetric distance matrix over "points" (region entry/exit points and the depot), metres.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceMatrix {
    n: usize,
    data: Vec<f64>,
}

impl DistanceMatrix {
    /// An `n` × `n` matrix of zeros.
    ///
    /// # Panics
    /// Only when `n²` values (8 bytes each) cannot be allocated.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            data: vec![0.0; n.saturating_mul(n)],
        }
    }

    /// A matrix whose entry (i, j) is `f(i, j)` for `i < j`, mirrored to (j, i); the diagonal is zero.
    /// `f` is called once per unordered pair, n(n−1)/2 times, in row-major order.
    pub fn from_fn(n: usize, f: impl Fn(usize, usize) -> f64) -> Self {
        let mut m = Self::new(n);
        // Upper triangle row by row (contiguous writes), then mirrored tile by tile so that the strided
        // writes of the lower triangle stay in cache.
        for i in 0..n {
            let row = &mut m.data[i * n..(i + 1) * n];
            for (j, v) in row.iter_mut().enumerate().skip(i + 1) {
                *v = f(i, j);
            }
        }
        const TILE: usize = 64;
        for bi in (0..n).step_by(TILE) {
            for bj in (bi..n).step_by(TILE) {
                for i in bi..(bi + TILE).min(n) {
                    for j in bj.max(i + 1)..(bj + TILE).min(n) {
                        m.data[j * n + i] = m.data[i * n + j];
                    }
                }
            }
        }
        m
    }

    /// Number of points (rows).
    pub fn len(&self) -> usize {
        self.n
    }

    /// True when the matrix has no points.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Distance from point `i` to point `j`, metres; `f64::INFINITY` when either index is outside the matrix.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if i < self.n && j < self.n {
            self.data[i * self.n + j]
        } else {
            f64::INFINITY
        }
    }

    /// Distances from point `i` to every point (row `i`), metres; `None` when `i` is outside the matrix.
    pub fn row(&self, i: usize) -> Option<&[f64]> {
        (i < self.n).then(|| &self.data[i * self.n..(i + 1) * self.n])
    }

    /// Sets the distance between points `i` and `j` (both (i, j) and (j, i)), metres. Indices outside the
    /// matrix are ignored (check them against [`DistanceMatrix::len`]).
    pub fn set(&mut self, i: usize, j: usize, d: f64) {
        if i < self.n && j < self.n {
            self.data[i * self.n + j] = d;
            self.data[j * self.n + i] = d;
        }
    }
}

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
/// [`tour_cost`] of the two, metres.
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
    /// A tour of `order` with `options`, its cost computed by [`tour_cost`].
    pub fn new(problem: &TourProblem, order: Vec<usize>, options: Vec<usize>) -> Self {
        let cost = tour_cost(problem, &order, &options);
        Self { order, options, cost }
    }

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

/// How much work a solver may do.
#[derive(Clone, Copy)]
pub struct SolveBudget<'a> {
    /// Deterministic work bound: moves evaluated (a dynamic-programming pass counts one per node). Zero
    /// returns the construction.
    pub max_iterations: u64,
    /// Polled every 256 moves (and before the first): returning true stops the solver, which then returns
    /// the best tour found so far. For cancellation or a caller's deadline; the solver reads no clock.
    pub stop: Option<&'a dyn Fn() -> bool>,
}

impl<'a> SolveBudget<'a> {
    /// A budget of `max_iterations` moves without a stop hook.
    pub fn new(max_iterations: u64) -> Self {
        Self {
            max_iterations,
            stop: None,
        }
    }

    /// No bound beyond each strategy's own schedule (which always terminates).
    pub fn unlimited() -> Self {
        Self::new(u64::MAX)
    }

    /// The same budget, also stopped when `stop` returns true.
    pub fn with_stop(self, stop: &'a dyn Fn() -> bool) -> Self {
        Self {
            stop: Some(stop),
            ..self
        }
    }
}

impl std::fmt::Debug for SolveBudget<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolveBudget")
            .field("max_iterations", &self.max_iterations)
            .field("stop", &self.stop.map(|_| "Fn"))
            .finish()
    }
}

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

/// Internal upper bound for any distance or option cost, metres: NaN, infinities and anything larger are
/// replaced by it inside the solvers, so all arithmetic stays finite and comparable.
pub(crate) const BIG: f64 = 1e12;

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

/// The problem as the solvers see it: options flattened, every number clamped to `[−BIG, BIG]` (NaN and
/// infinities become `BIG`), unusable references replaced by harmless ones, so no solver can panic or
/// compare a NaN.
pub(crate) struct Inst<'p> {
    dist: &'p DistanceMatrix,
    pub depot: usize,
    pub closed: bool,
    /// False when some option has no valid reverse (the problem fails `validate`): the solvers then use
    /// no move that reverses a node, so their deltas stay exact.
    pub reversible: bool,
    /// Number of nodes.
    pub n: usize,
    first: Vec<usize>,
    opts: Vec<Opt>,
}

pub(crate) fn clamp(x: f64) -> f64 {
    if x.abs() <= BIG { x } else { BIG }
}

impl<'p> Inst<'p> {
    pub fn new(p: &'p TourProblem) -> Self {
        let mut first = Vec::with_capacity(p.nodes.len() + 1);
        let mut opts = Vec::new();
        let mut reversible = true;
        for node in &p.nodes {
            first.push(opts.len());
            if node.is_empty() {
                // No way to visit it: a placeholder that costs BIG (its option index 0 is reported, and
                // `tour_cost` of the tour is +inf, as for any problem that fails `validate`).
                opts.push(Opt {
                    entry: p.depot,
                    exit: p.depot,
                    cost: BIG,
                    rev: 0,
                });
            }
            for (k, t) in node.iter().enumerate() {
                let opt = match node.get(t.reverse) {
                    // A true reverse pair gets one cost (the higher), so reversal deltas are exact.
                    Some(r) if r.entry == t.exit && r.exit == t.entry && r.reverse == k => Opt {
                        entry: t.entry,
                        exit: t.exit,
                        cost: clamp(t.cost).max(clamp(r.cost)),
                        rev: t.reverse,
                    },
                    _ => {
                        reversible &= t.entry == t.exit;
                        Opt {
                            entry: t.entry,
                            exit: t.exit,
                            cost: clamp(t.cost),
                            rev: k,
                        }
                    }
                };
                opts.push(opt);
            }
        }
        first.push(opts.len());
        Self {
            dist: &p.dist,
            depot: p.depot,
            closed: p.closed,
            reversible,
            n: p.nodes.len(),
            first,
            opts,
        }
    }

    /// Clamped distance between two points, metres.
    #[inline]
    pub fn d(&self, a: usize, b: usize) -> f64 {
        clamp(self.dist.get(a, b))
    }

    /// Clamped distance from point `a` to point `b` read from a row of the matrix (`None` = `a` outside).
    #[inline]
    pub fn d_row(row: Option<&[f64]>, b: usize) -> f64 {
        row.and_then(|r| r.get(b)).map_or(BIG, |&x| clamp(x))
    }

    /// Row `a` of the distance matrix, if `a` is a point of it.
    #[inline]
    pub fn row(&self, a: usize) -> Option<&'p [f64]> {
        self.dist.row(a)
    }

    /// Number of options of `node`.
    #[inline]
    pub fn k(&self, node: usize) -> usize {
        self.first[node + 1] - self.first[node]
    }

    /// Option `o` of `node`.
    #[inline]
    pub fn opt(&self, node: usize, o: usize) -> Opt {
        self.opts[self.first[node] + o]
    }

    /// Exact (clamped) cost of a tour, metres, in [`tour_cost`]'s summation order.
    pub fn eval(&self, order: &[usize], opt: &[usize]) -> f64 {
        let mut acc = 0.0;
        let mut prev = self.depot;
        for (&v, &o) in order.iter().zip(opt) {
            let t = self.opt(v, o);
            acc += self.d(prev, t.entry);
            acc += t.cost;
            prev = t.exit;
        }
        if self.closed && !order.is_empty() {
            acc += self.d(prev, self.depot);
        }
        acc
    }
}

impl CostModel for Inst<'_> {
    fn depot(&self) -> usize {
        self.depot
    }
    fn closed(&self) -> bool {
        self.closed
    }
    fn dist(&self, a: usize, b: usize) -> f64 {
        self.d(a, b)
    }
    fn n_options(&self, node: usize) -> usize {
        self.k(node)
    }
    fn option(&self, node: usize, o: usize) -> Opt {
        self.opt(node, o)
    }
}

/// True when going from cost `old` to cost `new` is a real improvement, not floating-point noise: by more
/// than 10⁻⁹ m plus 10⁻¹² of the magnitudes involved (so moves across `BIG` edges cannot cycle on
/// rounding errors).
#[inline]
pub(crate) fn improves(old: f64, new: f64) -> bool {
    old - new > 1e-9 + 1e-12 * (old.abs() + new.abs())
}

/// Counts work against a [`SolveBudget`] and polls its stop hook every [`Meter::POLL`] units.
pub(crate) struct Meter<'a> {
    used: u64,
    max: u64,
    next_poll: u64,
    stop: Option<&'a dyn Fn() -> bool>,
    halted: bool,
}

impl<'a> Meter<'a> {
    const POLL: u64 = 256;

    pub fn new(budget: &SolveBudget<'a>) -> Self {
        Self {
            used: 0,
            max: budget.max_iterations,
            next_poll: 0,
            stop: budget.stop,
            halted: false,
        }
    }

    /// Charges `units` of work; false (from then on) once the budget is spent or the caller said stop.
    #[inline]
    pub fn spend(&mut self, units: u64) -> bool {
        if self.halted {
            return false;
        }
        if self.used >= self.max {
            self.halted = true;
            return false;
        }
        if self.used >= self.next_poll {
            self.next_poll = self.used.saturating_add(Self::POLL);
            if self.stop.is_some_and(|f| f()) {
                self.halted = true;
                return false;
            }
        }
        self.used = self.used.saturating_add(units);
        true
    }

    /// Charges one move evaluation.
    #[inline]
    pub fn tick(&mut self) -> bool {
        self.spend(1)
    }

    /// True once the budget is spent or the caller said stop.
    pub fn halted(&self) -> bool {
        self.halted
    }

    /// Work units left (0 when halted).
    pub fn remaining(&self) -> u64 {
        if self.halted {
            0
        } else {
            self.max.saturating_sub(self.used)
        }
    }
}

/// Instances and exhaustive solvers shared by the tests of every strategy.
#[cfg(test)]
pub(crate) mod testutil {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::{DistanceMatrix, TourOption, TourProblem, best_options};

    /// A random Euclidean instance in a 100 m square: point 0 is the depot; every node is a point (one
    /// option, entry = exit, cost 0), a lane (two options, both directions, cost = its length), a lane with
    /// a there-and-back option (three options, the loop costs twice the lane) or a rectangle swept with a
    /// 1 m tool (four options: two diagonals, both directions, cost ≈ its area), up to `max_options`.
    pub fn euclid(n: usize, max_options: usize, closed: bool, seed: u64) -> TourProblem {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut pts: Vec<(f64, f64)> = vec![(rng.random_range(0.0..100.0), rng.random_range(0.0..100.0))];
        let mut nodes = Vec::with_capacity(n);
        let add = |pts: &mut Vec<(f64, f64)>, p: (f64, f64)| {
            pts.push(p);
            pts.len() - 1
        };
        for _ in 0..n {
            let c = (rng.random_range(0.0..100.0), rng.random_range(0.0..100.0));
            let kind = rng.random_range(0..max_options.clamp(1, 4));
            let (w, h) = (rng.random_range(0.5..8.0), rng.random_range(0.5..8.0));
            let area = w * h;
            let opt = |entry, exit, cost, reverse| TourOption {
                entry,
                exit,
                cost,
                reverse,
            };
            let node = match kind {
                0 => {
                    let p = add(&mut pts, c);
                    vec![opt(p, p, 0.0, 0)]
                }
                1 => {
                    let a = add(&mut pts, c);
                    let b = add(&mut pts, (c.0 + w, c.1 + h));
                    let len = w.hypot(h);
                    vec![opt(a, b, len, 1), opt(b, a, len, 0)]
                }
                2 => {
                    let a = add(&mut pts, c);
                    let b = add(&mut pts, (c.0 + w, c.1));
                    vec![opt(a, b, w, 1), opt(b, a, w, 0), opt(a, a, 2.0 * w, 2)]
                }
                _ => {
                    let c0 = add(&mut pts, c);
                    let c1 = add(&mut pts, (c.0 + w, c.1));
                    let c2 = add(&mut pts, (c.0 + w, c.1 + h));
                    let c3 = add(&mut pts, (c.0, c.1 + h));
                    let (inner, other) = (area, area * rng.random_range(0.8..1.2));
                    vec![
                        opt(c0, c2, inner, 1),
                        opt(c2, c0, inner, 0),
                        opt(c1, c3, other, 3),
                        opt(c3, c1, other, 2),
                    ]
                }
            };
            nodes.push(node);
        }
        let dist = DistanceMatrix::from_fn(pts.len(), |i, j| {
            let (a, b) = (pts[i], pts[j]);
            ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt()
        });
        TourProblem {
            dist,
            depot: 0,
            nodes,
            closed,
        }
    }

    /// A random non-metric instance: symmetric distances uniform in [0, 100) m, random multi-option nodes.
    pub fn random_matrix(n: usize, max_options: usize, closed: bool, seed: u64) -> TourProblem {
        let mut p = euclid(n, max_options, closed, seed);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let m = p.dist.len();
        p.dist = DistanceMatrix::from_fn(m, |_, _| 0.0);
        for i in 0..m {
            for j in i + 1..m {
                p.dist.set(i, j, rng.random_range(0.0..100.0));
            }
        }
        p
    }

    /// The optimum by enumerating every order (with optimal options for each); n ≤ 8.
    pub fn brute_force(p: &TourProblem) -> f64 {
        let mut order: Vec<usize> = (0..p.nodes.len()).collect();
        let mut best = f64::INFINITY;
        permute(&mut order, 0, &mut |o| best = best.min(best_options(p, o).1));
        best
    }

    fn permute(a: &mut Vec<usize>, k: usize, f: &mut dyn FnMut(&[usize])) {
        if k == a.len() {
            f(a);
            return;
        }
        for i in k..a.len() {
            a.swap(k, i);
            permute(a, k + 1, f);
            a.swap(k, i);
        }
    }

    /// The cheapest option assignment for `order` by enumerating all of them.
    pub fn brute_force_options(p: &TourProblem, order: &[usize]) -> f64 {
        let mut options = vec![0usize; order.len()];
        let mut best = f64::INFINITY;
        loop {
            best = best.min(super::tour_cost(p, order, &options));
            let mut k = 0;
            loop {
                if k == order.len() {
                    return best;
                }
                options[k] += 1;
                if options[k] < p.nodes[order[k]].len() {
                    break;
                }
                options[k] = 0;
                k += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::testutil::{brute_force, brute_force_options, euclid, random_matrix};
    use super::*;

    fn opt(entry: usize, exit: usize, cost: f64, reverse: usize) -> TourOption {
        TourOption {
            entry,
            exit,
            cost,
            reverse,
        }
    }

    /// Depot at 0 and nodes at x = 1..=k on a line (one point each).
    fn line(k: usize, closed: bool) -> TourProblem {
        let dist = DistanceMatrix::from_fn(k + 1, |i, j| (j as f64 - i as f64).abs());
        let nodes = (1..=k).map(|p| vec![opt(p, p, 0.0, 0)]).collect();
        TourProblem {
            dist,
            depot: 0,
            nodes,
            closed,
        }
    }

    fn budgets() -> [SolveBudget<'static>; 2] {
        [SolveBudget::unlimited(), SolveBudget::new(3_000)]
    }

    #[test]
    fn distance_matrix_basics() {
        let m = DistanceMatrix::from_fn(3, |i, j| (10 * i + j) as f64);
        assert_eq!(m.len(), 3);
        assert!(!m.is_empty() && DistanceMatrix::new(0).is_empty());
        assert_eq!(
            (m.get(0, 1), m.get(1, 0), m.get(1, 2), m.get(2, 1), m.get(2, 2)),
            (1.0, 1.0, 12.0, 12.0, 0.0)
        );
        assert_eq!(m.get(3, 0), f64::INFINITY);
        let mut m = DistanceMatrix::new(2);
        m.set(0, 1, 5.0);
        m.set(7, 1, 9.0); // ignored
        assert_eq!((m.get(1, 0), m.get(0, 0)), (5.0, 0.0));
    }

    #[test]
    fn method_names_round_trip() {
        for m in OrderMethod::ALL {
            assert_eq!(m.name().parse::<OrderMethod>(), Ok(m));
            assert_eq!(m.to_string(), m.name());
        }
        assert_eq!(OrderMethod::default(), OrderMethod::RecordToRecord);
        let err = "2opt".parse::<OrderMethod>().err().unwrap_or_default();
        assert!(err.contains("two-opt, rrt, anneal"), "{err}");
    }

    #[test]
    fn validate_reports_each_defect() {
        let good = euclid(6, 4, true, 1);
        assert_eq!(good.validate(), Ok(()));
        let mut cases: Vec<(TourProblem, &str)> = Vec::new();
        let mut p = good.clone();
        p.depot = p.dist.len();
        cases.push((p, "depot point"));
        let mut p = good.clone();
        p.nodes[2].clear();
        cases.push((p, "no traversal option"));
        let mut p = good.clone();
        p.nodes[1][0].entry = 10_000;
        cases.push((p, "outside the distance matrix"));
        let mut p = good.clone();
        p.nodes[1][0].reverse = 9;
        cases.push((p, "reverse 9 out of range"));
        let mut p = good.clone();
        p.nodes.push(vec![opt(1, 2, 1.0, 0)]);
        cases.push((p, "is not its reverse"));
        let mut p = good.clone();
        p.nodes.push(vec![opt(1, 2, 1.0, 1), opt(2, 1, 2.0, 0)]);
        cases.push((p, "is not its reverse"));
        let mut p = good.clone();
        p.nodes.push(vec![opt(1, 1, f64::NAN, 0)]);
        cases.push((p, "cost NaN"));
        let mut p = good.clone();
        p.dist.set(0, 3, f64::NAN);
        cases.push((p, "distance between points 0 and 3"));
        let mut p = good.clone();
        p.dist.set(2, 3, -1.0);
        cases.push((p, "distance between points 2 and 3"));
        for (p, needle) in cases {
            let err = p.validate().err().map(|e| e.to_string()).unwrap_or_default();
            assert!(err.contains(needle), "{needle:?} not in {err:?}");
        }
        let mut p = good;
        p.dist.set(0, 3, f64::INFINITY);
        p.nodes[0][0].cost = f64::INFINITY;
        let r = p.nodes[0][0].reverse;
        p.nodes[0][r].cost = f64::INFINITY;
        assert_eq!(p.validate(), Ok(()), "+inf means very expensive, not invalid");
    }

    #[test]
    fn tour_cost_by_hand_closed_and_open() {
        // Points on a line: depot 0 at x=0, node 0 is a lane 1→2 (x=1..3, cost 2), node 1 a point at x=5.
        let xs: [f64; 4] = [0.0, 1.0, 3.0, 5.0];
        let dist = DistanceMatrix::from_fn(4, |i, j| (xs[j] - xs[i]).abs());
        let nodes = vec![vec![opt(1, 2, 2.0, 1), opt(2, 1, 2.0, 0)], vec![opt(3, 3, 0.5, 0)]];
        let mut p = TourProblem {
            dist,
            depot: 0,
            nodes,
            closed: true,
        };
        assert_eq!(tour_cost(&p, &[0, 1], &[0, 0]), 1.0 + 2.0 + 2.0 + 0.5 + 5.0);
        assert_eq!(tour_cost(&p, &[0, 1], &[1, 0]), 3.0 + 2.0 + 4.0 + 0.5 + 5.0);
        assert_eq!(tour_cost(&p, &[], &[]), 0.0);
        assert_eq!(tour_cost(&p, &[0, 1], &[0]), f64::INFINITY);
        assert_eq!(tour_cost(&p, &[0, 7], &[0, 0]), f64::INFINITY);
        assert_eq!(tour_cost(&p, &[0, 1], &[0, 3]), f64::INFINITY);
        assert_eq!(best_options(&p, &[0, 1]), (vec![0, 0], 10.5));
        p.closed = false;
        assert_eq!(tour_cost(&p, &[0, 1], &[0, 0]), 5.5, "an open tour has no return leg");
        assert_eq!(best_options(&p, &[1, 0]), (vec![0, 1], 5.0 + 0.5 + 2.0 + 2.0));
    }

    #[test]
    fn non_finite_values_never_give_nan() {
        let mut p = line(4, true);
        p.dist.set(0, 2, f64::INFINITY);
        p.dist.set(1, 2, f64::NAN);
        p.dist.set(3, 4, f64::NEG_INFINITY);
        assert_eq!(tour_cost(&p, &[0, 1, 2, 3], &[0; 4]), f64::INFINITY);
        assert_eq!(best_options(&p, &[0, 1, 2, 3]).1, f64::INFINITY);
        for m in OrderMethod::ALL {
            let t = m.orderer().solve(&p, 3, &SolveBudget::unlimited());
            assert_eq!(t.check(&p), Ok(()));
            assert_eq!(t.cost.to_bits(), tour_cost(&p, &t.order, &t.options).to_bits());
            assert!(!t.cost.is_nan());
        }
        // Huge but finite distances everywhere: still a valid tour, and infinite edges are avoided
        // when a finite tour exists.
        let mut p = line(6, true);
        for j in 1..=6 {
            p.dist.set(0, j, 1e300);
        }
        p.dist.set(0, 1, 1.0);
        p.dist.set(2, 5, f64::INFINITY);
        for m in OrderMethod::ALL {
            let t = m.orderer().solve(&p, 3, &SolveBudget::unlimited());
            assert_eq!(t.check(&p), Ok(()));
            assert!(t.cost.is_finite(), "{m}: {t:?}");
        }
    }

    #[test]
    fn invalid_problems_do_not_panic() {
        let mut p = euclid(7, 4, true, 5);
        p.nodes[0][0].reverse = 99;
        p.nodes[1][0].entry = 99_999;
        p.nodes[2].clear();
        p.nodes[3][0].cost = f64::NAN;
        let bad_depot = TourProblem {
            depot: 10_000,
            ..p.clone()
        };
        for p in [&p, &bad_depot] {
            assert!(p.validate().is_err());
            for m in OrderMethod::ALL {
                let t = m.orderer().solve(p, 1, &SolveBudget::unlimited());
                assert_eq!(t.order.len(), p.nodes.len());
                assert_eq!(t.cost, f64::INFINITY);
            }
            let _ = best_options(p, &[0, 1, 2, 3, 4, 5, 6, 99]);
        }
    }

    #[test]
    fn zero_and_one_node() {
        let empty = TourProblem {
            dist: DistanceMatrix::new(1),
            depot: 0,
            nodes: vec![],
            closed: true,
        };
        let one = TourProblem {
            dist: DistanceMatrix::from_fn(3, |i, j| [[0.0, 4.0, 1.0], [4.0, 0.0, 3.0], [1.0, 3.0, 0.0]][i][j]),
            depot: 0,
            nodes: vec![vec![opt(1, 2, 3.0, 1), opt(2, 1, 3.0, 0)]],
            closed: true,
        };
        for m in OrderMethod::ALL {
            let t = m.orderer().solve(&empty, 0, &SolveBudget::unlimited());
            assert_eq!(
                t,
                Tour {
                    order: vec![],
                    options: vec![],
                    cost: 0.0
                }
            );
            let t = m.orderer().solve(&one, 0, &SolveBudget::unlimited());
            assert_eq!((t.order, t.cost), (vec![0], 8.0));
            let open = TourProblem {
                closed: false,
                ..one.clone()
            };
            let t = m.orderer().solve(&open, 0, &SolveBudget::unlimited());
            assert_eq!(
                (t.order, t.options, t.cost),
                (vec![0], vec![1], 4.0),
                "enter near the depot"
            );
        }
    }

    #[test]
    fn identical_options_and_coincident_points() {
        // Every node has three identical self-reverse options at the same point as the depot.
        let p = TourProblem {
            dist: DistanceMatrix::new(2),
            depot: 0,
            nodes: vec![vec![opt(1, 1, 2.0, 0), opt(1, 1, 2.0, 1), opt(1, 1, 2.0, 2)]; 9],
            closed: true,
        };
        assert_eq!(p.validate(), Ok(()));
        for m in OrderMethod::ALL {
            let t = m.orderer().solve(&p, 9, &SolveBudget::unlimited());
            assert_eq!(t.check(&p), Ok(()));
            assert_eq!(t.cost, 18.0);
        }
    }

    #[test]
    fn open_tours_ignore_the_return_leg() {
        for m in OrderMethod::ALL {
            let t = m.orderer().solve(&line(5, false), 2, &SolveBudget::unlimited());
            assert_eq!((t.order.clone(), t.cost), (vec![0, 1, 2, 3, 4], 5.0), "{m}");
            let t = m.orderer().solve(&line(5, true), 2, &SolveBudget::unlimited());
            assert_eq!(t.cost, 10.0, "{m}");
        }
        let p = euclid(9, 4, false, 8);
        let closed = TourProblem {
            closed: true,
            ..p.clone()
        };
        let t = TwoOpt::default().solve(&p, 0, &SolveBudget::unlimited());
        let last = p.nodes[t.order[8]][t.options[8]].exit;
        let with_return = tour_cost(&closed, &t.order, &t.options);
        assert!((with_return - t.cost - p.dist.get(last, 0)).abs() < 1e-9);
    }

    #[test]
    fn zero_budget_and_immediate_stop_return_the_construction() {
        let p = euclid(40, 4, true, 11);
        let nn = construct(&p, Construction::NearestNeighbour);
        let stop_now = || true;
        for m in OrderMethod::ALL {
            for budget in [SolveBudget::new(0), SolveBudget::unlimited().with_stop(&stop_now)] {
                let t = m.orderer().solve(&p, 4, &budget);
                assert_eq!(t, nn, "{m} {budget:?}");
            }
        }
        // A stop that fires later still yields a valid tour, never worse than the construction.
        let calls = std::cell::Cell::new(0u32);
        let stop_later = || {
            calls.set(calls.get() + 1);
            calls.get() > 5
        };
        for m in OrderMethod::ALL {
            calls.set(0);
            let t = m
                .orderer()
                .solve(&p, 4, &SolveBudget::unlimited().with_stop(&stop_later));
            assert_eq!(t.check(&p), Ok(()));
            assert!(t.cost <= nn.cost);
        }
    }

    #[test]
    fn tiny_instances_are_near_optimal() {
        // worst[metric][method]: cost / brute-force optimum over 60 instances with n ≤ 6, ≤ 4 options.
        let mut worst = [[1.0f64; 3]; 2];
        for seed in 0..60 {
            let n = 2 + (seed as usize % 5);
            let metric = seed % 3 != 0;
            let p = if metric {
                euclid(n, 4, seed % 2 == 0, seed)
            } else {
                random_matrix(n, 4, seed % 2 == 0, seed)
            };
            let opt = brute_force(&p);
            for (k, m) in OrderMethod::ALL.into_iter().enumerate() {
                let t = m.orderer().solve(&p, seed, &SolveBudget::unlimited());
                assert!(t.cost >= opt - 1e-9, "{m} beat brute force on seed {seed}");
                let w = &mut worst[usize::from(metric)][k];
                *w = w.max(t.cost / opt);
            }
        }
        // 2-opt + Or-opt + DP is a local optimum (measured worst: 1.00 Euclidean, 1.30 non-metric); the
        // metaheuristics find (nearly) the optimum at these sizes (measured worst 1.011).
        let [non_metric, metric] = worst;
        assert!(metric[0] <= 1.10 && non_metric[0] <= 1.5, "two-opt {worst:?}");
        assert!(metric[1] <= 1.05 && non_metric[1] <= 1.05, "rrt {worst:?}");
        assert!(metric[2] <= 1.05 && non_metric[2] <= 1.05, "anneal {worst:?}");
    }

    #[test]
    fn large_instance_uses_neighbour_lists() {
        let p = euclid(1500, 4, true, 21);
        let nn = construct(&p, Construction::NearestNeighbour);
        let t = TwoOpt::default().solve(&p, 0, &SolveBudget::unlimited());
        assert_eq!(t.check(&p), Ok(()));
        assert!(t.cost < 0.95 * nn.cost, "{} vs {}", t.cost, nn.cost);
    }

    /// Solution quality and time on 200-node random Euclidean instances (run with `--ignored --nocapture`,
    /// in release-like `test` profile). Reports the mean over 5 seeds of cost / nearest-neighbour cost.
    #[test]
    #[ignore = "measurement, prints a table"]
    fn quality_report_200() {
        for (label, k) in [("points (k=1)", 1), ("mixed options (k≤4)", 4)] {
            let seeds = 0..5u64;
            let mut rows: Vec<(String, f64, f64)> = Vec::new();
            let problems: Vec<TourProblem> = seeds.clone().map(|s| euclid(200, k, true, 1000 + s)).collect();
            let nn: Vec<f64> = problems
                .iter()
                .map(|p| construct(p, Construction::NearestNeighbour).cost)
                .collect();
            let mut measure = |name: String, f: &dyn Fn(&TourProblem, u64) -> Tour| {
                let start = std::time::Instant::now();
                let mut ratio = 0.0;
                for (i, p) in problems.iter().enumerate() {
                    let t = f(p, i as u64);
                    assert_eq!(t.check(p), Ok(()));
                    ratio += t.cost / nn[i];
                }
                let ms = start.elapsed().as_secs_f64() * 1e3 / problems.len() as f64;
                rows.push((name, ratio / problems.len() as f64, ms));
            };
            measure("nearest neighbour".into(), &|p, _| {
                construct(p, Construction::NearestNeighbour)
            });
            measure("cheapest insertion".into(), &|p, _| {
                construct(p, Construction::CheapestInsertion)
            });
            for m in OrderMethod::ALL {
                measure(m.name().into(), &|p, s| {
                    m.orderer().solve(p, s, &SolveBudget::unlimited())
                });
            }
            println!("200 nodes, {label}: cost / nearest-neighbour cost, mean of 5 seeds");
            for (name, r, ms) in rows {
                println!("  {name:<20} {r:.4}  {ms:8.1} ms");
            }
        }
        // Large n: neighbour lists keep the local search near-linear per pass.
        for n in [1000, 3000] {
            let p = euclid(n, 4, true, 7);
            let start = std::time::Instant::now();
            let nn = construct(&p, Construction::NearestNeighbour);
            let nn_ms = start.elapsed().as_secs_f64() * 1e3;
            let start = std::time::Instant::now();
            let t = TwoOpt::default().solve(&p, 0, &SolveBudget::unlimited());
            let ms = start.elapsed().as_secs_f64() * 1e3;
            println!(
                "{n} nodes: nearest neighbour {nn_ms:.0} ms; two-opt {:.4} of it in {ms:.0} ms",
                t.cost / nn.cost
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn best_options_equals_brute_force(
            n in 0usize..6, k in 1usize..=4, closed: bool, seed: u64, metric: bool,
        ) {
            let p = if metric { euclid(n, k, closed, seed) } else { random_matrix(n, k, closed, seed) };
            let order: Vec<usize> = (0..n).rev().collect();
            let (options, cost) = best_options(&p, &order);
            prop_assert_eq!(cost.to_bits(), tour_cost(&p, &order, &options).to_bits());
            prop_assert!((cost - brute_force_options(&p, &order)).abs() <= 1e-9 * cost.max(1.0));
        }

        #[test]
        fn results_are_valid_exact_and_deterministic(
            n in 0usize..40, k in 1usize..=4, closed: bool, seed: u64, metric: bool, method in 0usize..3,
        ) {
            let p = if metric { euclid(n, k, closed, seed) } else { random_matrix(n, k, closed, seed) };
            let m = OrderMethod::ALL[method];
            for budget in budgets() {
                let t = m.orderer().solve(&p, seed, &budget);
                prop_assert_eq!(t.check(&p), Ok(()));
                prop_assert_eq!(t.cost.to_bits(), tour_cost(&p, &t.order, &t.options).to_bits());
                prop_assert_eq!(&t, &m.orderer().solve(&p, seed, &budget));
            }
        }
    }
}
