//! The problem as the solvers see it ([`Inst`]): options flattened, every number clamped to [`BIG`], and the
//! noise-proof improvement test [`improves`].

use super::{CostModel, DistanceMatrix, Opt, TourProblem};

/// Internal upper bound for any distance or option cost, metres: NaN, infinities and anything larger are
/// replaced by it inside the solvers, so all arithmetic stays finite and comparable.
pub(crate) const BIG: f64 = 1e12;

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

    /// Exact (clamped) cost of a tour, metres, in [`tour_cost`](super::tour_cost)'s summation order.
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
