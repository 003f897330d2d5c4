//! 2-opt local search with Or-opt moves and exact option assignment (seed 004 §3.4.1).
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

use std::collections::VecDeque;

use super::construct::construct_order;
use super::{Construction, Inst, Meter, Orderer, SolveBudget, Tour, TourProblem, dp_options, improves};

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

/// A tour under search: nodes in visiting order, their options, each node's slot, and the cost (metres,
/// clamped model) kept up to date by move deltas.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct State {
    /// Node in slot s is `order[s − 1]`.
    pub order: Vec<usize>,
    /// Option of `order[s − 1]`.
    pub opt: Vec<usize>,
    /// Slot (1-based) of every node.
    pub pos: Vec<usize>,
    /// Entry point of `order[k]` with `opt[k]` (a cache for the move deltas).
    ent: Vec<usize>,
    /// Exit point of `order[k]` with `opt[k]`.
    ext: Vec<usize>,
    /// Tracked cost, metres; exact after [`Search::optimise`].
    pub cost: f64,
}

impl State {
    pub fn new(inst: &Inst<'_>, order: Vec<usize>, opt: Vec<usize>) -> Self {
        let n = order.len();
        let cost = inst.eval(&order, &opt);
        let mut st = Self {
            order,
            opt,
            pos: vec![0; inst.n],
            ent: vec![0; n],
            ext: vec![0; n],
            cost,
        };
        st.refresh(inst, 0, n);
        st
    }

    /// Recomputes the slot and the entry/exit points of array indices `from..to` after a change there.
    pub fn refresh(&mut self, inst: &Inst<'_>, from: usize, to: usize) {
        for k in from..to {
            let v = self.order[k];
            let t = inst.opt(v, self.opt[k]);
            self.pos[v] = k + 1;
            self.ent[k] = t.entry;
            self.ext[k] = t.exit;
        }
    }
}

/// A local change of a tour. Slots are 1-based node positions; slot 0 is the depot start and slot n+1 the
/// tour's end (the depot when closed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Move {
    /// Reverse slots i+1..=j (0 ≤ i < j ≤ n).
    TwoOpt { i: usize, j: usize },
    /// Move slots a..=b (1 ≤ a ≤ b ≤ n) into the gap after slot t (t ≤ n, t ∉ a−1..=b), reversed
    /// or not;
    /// a single node (a = b) takes option `o`.
    OrOpt {
        a: usize,
        b: usize,
        t: usize,
        reversed: bool,
        o: usize,
    },
    /// Give the node in slot s option o.
    Reopt { s: usize, o: usize },
}

/// Pending nodes of the local search (the depot is pseudo node n).
pub(crate) struct WorkQueue {
    q: VecDeque<usize>,
    queued: Vec<bool>,
}

impl WorkQueue {
    pub fn new(n: usize) -> Self {
        Self {
            q: VecDeque::new(),
            queued: vec![false; n + 1],
        }
    }

    pub fn push(&mut self, v: usize) {
        if let Some(f) = self.queued.get_mut(v)
            && !*f
        {
            *f = true;
            self.q.push_back(v);
        }
    }

    fn pop(&mut self) -> Option<usize> {
        let v = self.q.pop_front()?;
        self.queued[v] = false;
        Some(v)
    }

    fn clear(&mut self) {
        while self.pop().is_some() {}
    }
}

/// Neighbour lists and move machinery over one problem, with the work meter.
pub(crate) struct Search<'p, 'b> {
    pub inst: Inst<'p>,
    /// Flattened neighbour lists: `kn` pseudo nodes per pseudo node (nodes 0..n, depot n), nearest first.
    nb: Vec<usize>,
    /// Node-to-node distance of each entry of `nb`, metres.
    nbd: Vec<f64>,
    kn: usize,
    max_chain: usize,
    pub meter: Meter<'b>,
}

impl<'p, 'b> Search<'p, 'b> {
    pub fn new(inst: Inst<'p>, params: &TwoOptParams, meter: Meter<'b>) -> Self {
        let (nb, nbd, kn) = neighbour_lists(&inst, params.neighbours.max(1));
        Self {
            inst,
            nb,
            nbd,
            kn,
            max_chain: params.max_chain.max(1),
            meter,
        }
    }

    /// Neighbours of pseudo node `v` (the depot is n), nearest first.
    pub fn neighbours(&self, v: usize) -> &[usize] {
        &self.nb[v * self.kn..(v + 1) * self.kn]
    }

    /// Longest Or-opt chain.
    pub fn max_chain(&self) -> usize {
        self.max_chain
    }

    /// Slots of pseudo node `v`: a node has one; the depot has slot 0 and, when closed, slot n+1.
    pub fn slots(&self, st: &State, v: usize) -> ([usize; 2], usize) {
        let n = self.inst.n;
        if v == n {
            if self.inst.closed { ([0, n + 1], 2) } else { ([0, 0], 1) }
        } else {
            ([st.pos[v], 0], 1)
        }
    }

    /// Pseudo node in slot `s` (the depot for 0 and n+1).
    pub fn node_at(&self, st: &State, s: usize) -> usize {
        if s == 0 || s > self.inst.n {
            self.inst.n
        } else {
            st.order[s - 1]
        }
    }

    #[inline]
    fn entry(&self, st: &State, s: usize) -> usize {
        st.ent[s - 1]
    }

    #[inline]
    fn exit(&self, st: &State, s: usize) -> usize {
        st.ext[s - 1]
    }

    /// Point the tour leaves slot `s` from (0 ≤ s ≤ n).
    #[inline]
    fn out(&self, st: &State, s: usize) -> usize {
        if s == 0 { self.inst.depot } else { self.exit(st, s) }
    }

    /// Point the tour enters slot `s` at (1 ≤ s ≤ n+1); `None` for the end of an open tour.
    #[inline]
    fn inn(&self, st: &State, s: usize) -> Option<usize> {
        if s > self.inst.n {
            self.inst.closed.then_some(self.inst.depot)
        } else {
            Some(self.entry(st, s))
        }
    }

    #[inline]
    fn w(&self, a: usize, b: Option<usize>) -> f64 {
        b.map_or(0.0, |b| self.inst.d(a, b))
    }

    /// Cost of the edge after slot `s` (0 ≤ s ≤ n), metres.
    #[inline]
    pub fn edge(&self, st: &State, s: usize) -> f64 {
        self.w(self.out(st, s), self.inn(st, s + 1))
    }

    /// (removed, added) cost of `mv` on `st`, metres; the move's delta is added − removed.
    pub fn delta(&self, st: &State, mv: Move) -> (f64, f64) {
        match mv {
            Move::TwoOpt { i, j } => {
                let removed = self.edge(st, i) + self.edge(st, j);
                let out_i = self.out(st, i);
                let added = self.inst.d(out_i, self.exit(st, j)) + self.w(self.entry(st, i + 1), self.inn(st, j + 1));
                (removed, added)
            }
            Move::OrOpt { a, b, t, reversed, o } => {
                let before = self.out(st, a - 1);
                let after = self.inn(st, b + 1);
                let (gap_from, gap_to) = (self.out(st, t), self.inn(st, t + 1));
                let mut removed = self.edge(st, a - 1) + self.edge(st, b) + self.w(gap_from, gap_to);
                let mut added = self.w(before, after);
                if a == b {
                    let cur = self.inst.opt(st.order[a - 1], st.opt[a - 1]);
                    let new = self.inst.opt(st.order[a - 1], o);
                    removed += cur.cost;
                    added += new.cost + self.inst.d(gap_from, new.entry) + self.w(new.exit, gap_to);
                } else if reversed {
                    added += self.inst.d(gap_from, self.exit(st, b)) + self.w(self.entry(st, a), gap_to);
                } else {
                    added += self.inst.d(gap_from, self.entry(st, a)) + self.w(self.exit(st, b), gap_to);
                }
                (removed, added)
            }
            Move::Reopt { s, o } => {
                let v = st.order[s - 1];
                let (cur, new) = (self.inst.opt(v, st.opt[s - 1]), self.inst.opt(v, o));
                let (from, to) = (self.out(st, s - 1), self.inn(st, s + 1));
                let removed = self.inst.d(from, cur.entry) + cur.cost + self.w(cur.exit, to);
                let added = self.inst.d(from, new.entry) + new.cost + self.w(new.exit, to);
                (removed, added)
            }
        }
    }

    /// Applies `mv` whose (removed, added) is `delta`, and queues the nodes at the changed edges.
    pub fn apply(&self, st: &mut State, mv: Move, delta: (f64, f64), queue: &mut WorkQueue) {
        let touched: [usize; 6] = match mv {
            Move::TwoOpt { i, j } => [i, i + 1, j, j + 1, i, i],
            Move::OrOpt { a, b, t, .. } => [a - 1, a, b, b + 1, t, t + 1],
            Move::Reopt { s, .. } => [s - 1, s, s + 1, s, s, s],
        };
        for s in touched {
            queue.push(self.node_at(st, s));
        }
        match mv {
            Move::TwoOpt { i, j } => self.reverse(st, i, j),
            Move::OrOpt { a, b, t, reversed, o } => {
                let len = b - a + 1;
                let (lo, hi, start) = if t < a { (t, b, t) } else { (a - 1, t, t - len) };
                if t < a {
                    st.order[lo..hi].rotate_right(len);
                    st.opt[lo..hi].rotate_right(len);
                } else {
                    st.order[lo..hi].rotate_left(len);
                    st.opt[lo..hi].rotate_left(len);
                }
                if len == 1 {
                    st.opt[start] = o;
                } else if reversed {
                    self.reverse(st, start, start + len);
                }
                st.refresh(&self.inst, lo, hi);
            }
            Move::Reopt { s, o } => {
                st.opt[s - 1] = o;
                st.refresh(&self.inst, s - 1, s);
            }
        }
        st.cost += delta.1 - delta.0;
    }

    /// Reverses slots i+1..=j (array indices i..j) and flips their options.
    fn reverse(&self, st: &mut State, i: usize, j: usize) {
        st.order[i..j].reverse();
        st.opt[i..j].reverse();
        for k in i..j {
            st.opt[k] = self.inst.opt(st.order[k], st.opt[k]).rev;
        }
        st.refresh(&self.inst, i, j);
    }

    /// Evaluates the moves that put pseudo node `u` next to one of its neighbours and applies the best
    /// improving one. Returns whether a move was applied.
    fn improve(&mut self, st: &mut State, u: usize, queue: &mut WorkQueue) -> bool {
        let n = self.inst.n;
        let mut best: Option<(f64, Move, (f64, f64))> = None;
        let mut consider = |search: &mut Self, st: &State, mv: Move| -> bool {
            if !search.meter.tick() {
                return false;
            }
            let (removed, added) = search.delta(st, mv);
            if improves(removed, added) && best.is_none_or(|b| (removed - added).total_cmp(&b.0).is_gt()) {
                best = Some((removed - added, mv, (removed, added)));
            }
            true
        };
        let (us, nu) = self.slots(st, u);
        let reversible = self.inst.reversible;
        // Positive-gain pruning: a move that adds an edge between u and v must drop one of u's edges, so
        // only neighbours nearer than u's longer tour edge are worth trying (the lists are sorted).
        let mut bound = 0.0f64;
        for &x in &us[..nu] {
            if x >= 1 {
                bound = bound.max(self.edge(st, x - 1));
            }
            if x <= n {
                bound = bound.max(self.edge(st, x));
            }
        }
        let row = u * self.kn;
        let near = self.nbd[row..row + self.kn].iter().take_while(|&&d| d < bound).count();
        'scan: {
            for idx in (0..near).filter(|_| reversible) {
                let v = self.nb[u * self.kn + idx];
                let (vs, nv) = self.slots(st, v);
                for &x in &us[..nu] {
                    for &y in &vs[..nv] {
                        if x == y {
                            continue;
                        }
                        let (lo, hi) = (x.min(y), x.max(y));
                        if hi <= n && !consider(self, st, Move::TwoOpt { i: lo, j: hi }) {
                            break 'scan;
                        }
                        if lo >= 1 && !consider(self, st, Move::TwoOpt { i: lo - 1, j: hi - 1 }) {
                            break 'scan;
                        }
                    }
                }
            }
            if u == n {
                break 'scan;
            }
            let x = st.pos[u];
            if !self.inst.closed && reversible {
                // Tails: make u the last node, or the one before the reversed tail.
                for i in [x - 1, x] {
                    if i < n && !consider(self, st, Move::TwoOpt { i, j: n }) {
                        break 'scan;
                    }
                }
            }
            let mut gaps: Vec<usize> = Vec::with_capacity(4 * self.kn + 1);
            for idx in 0..near {
                let v = self.nb[u * self.kn + idx];
                let (vs, nv) = self.slots(st, v);
                for &y in &vs[..nv] {
                    if y >= 1 {
                        gaps.push(y - 1);
                    }
                    if y <= n {
                        gaps.push(y);
                    }
                }
            }
            if !self.inst.closed {
                gaps.push(n);
            }
            gaps.sort_unstable();
            gaps.dedup();
            for len in 1..=self.max_chain {
                // The chain starting at u and (for len ≥ 2) the one ending at u.
                let mut chains = [(0, 0); 2];
                let mut nc = 0;
                if x + len - 1 <= n {
                    chains[nc] = (x, x + len - 1);
                    nc += 1;
                }
                if len >= 2 && x >= len {
                    chains[nc] = (x + 1 - len, x);
                    nc += 1;
                }
                for &(a, b) in &chains[..nc] {
                    for &t in &gaps {
                        if t + 1 >= a && t <= b {
                            continue;
                        }
                        if len == 1 {
                            for o in 0..self.inst.k(u) {
                                if !consider(
                                    self,
                                    st,
                                    Move::OrOpt {
                                        a,
                                        b,
                                        t,
                                        reversed: false,
                                        o,
                                    },
                                ) {
                                    break 'scan;
                                }
                            }
                        } else {
                            for reversed in [false, true].into_iter().take(1 + usize::from(reversible)) {
                                if !consider(
                                    self,
                                    st,
                                    Move::OrOpt {
                                        a,
                                        b,
                                        t,
                                        reversed,
                                        o: 0,
                                    },
                                ) {
                                    break 'scan;
                                }
                            }
                        }
                    }
                }
            }
        }
        match best {
            Some((_, mv, delta)) => {
                self.apply(st, mv, delta, queue);
                true
            }
            None => false,
        }
    }

    /// Runs the queue empty (or until the budget ends).
    pub fn local_search(&mut self, st: &mut State, queue: &mut WorkQueue) {
        while let Some(u) = queue.pop() {
            if self.meter.halted() {
                queue.clear();
                break;
            }
            if self.improve(st, u, queue) {
                queue.push(u);
            }
        }
    }

    /// Local search and exact option assignment, alternated until neither improves. Leaves `st.cost`
    /// exact.
    pub fn optimise(&mut self, st: &mut State, queue: &mut WorkQueue) {
        loop {
            self.local_search(st, queue);
            let exact = self.inst.eval(&st.order, &st.opt);
            st.cost = exact;
            if !self.meter.spend(self.inst.n as u64) {
                break;
            }
            let (opt, cost) = dp_options(&self.inst, &st.order);
            if !improves(exact, cost) {
                break;
            }
            for s in 1..=self.inst.n {
                if opt[s - 1] != st.opt[s - 1] {
                    for t in [s - 1, s, s + 1] {
                        queue.push(self.node_at(st, t));
                    }
                }
            }
            st.opt = opt;
            st.refresh(&self.inst, 0, self.inst.n);
            st.cost = cost;
        }
    }

    /// Full descent from `st`: every node queued, then [`Search::optimise`]. Never leaves `st` worse.
    pub fn descend(&mut self, st: &mut State) {
        let start = st.clone();
        let mut queue = WorkQueue::new(self.inst.n);
        queue.push(self.inst.n);
        for k in 0..st.order.len() {
            queue.push(st.order[k]);
        }
        self.optimise(st, &mut queue);
        if improves(st.cost, start.cost) {
            *st = start;
        }
    }
}

/// For every pseudo node (nodes 0..n, depot n) its `k` nearest other pseudo nodes, nearest first (ties by
/// index). Returns the flattened lists, the matching distances and their common length min(k, n).
fn neighbour_lists(inst: &Inst<'_>, k: usize) -> (Vec<usize>, Vec<f64>, usize) {
    let n = inst.n;
    // Distinct entry/exit points of every pseudo node, flattened: points[first[v]..first[v + 1]].
    let mut first = Vec::with_capacity(n + 2);
    let mut points = Vec::new();
    for v in 0..=n {
        first.push(points.len());
        let mut p: Vec<usize> = if v == n {
            vec![inst.depot]
        } else {
            (0..inst.k(v))
                .flat_map(|o| [inst.opt(v, o).entry, inst.opt(v, o).exit])
                .collect()
        };
        p.sort_unstable();
        p.dedup();
        points.extend(p);
    }
    first.push(points.len());
    let kn = k.min(n);
    let mut nb = Vec::with_capacity((n + 1) * kn);
    let mut nbd = Vec::with_capacity((n + 1) * kn);
    let mut near = vec![f64::INFINITY; n + 1];
    let mut row: Vec<(f64, usize)> = Vec::with_capacity(n + 1);
    let cmp = |x: &(f64, usize), y: &(f64, usize)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
    for a in 0..=n {
        near.fill(f64::INFINITY);
        // One matrix row per point of `a`, read front to back.
        for &p in &points[first[a]..first[a + 1]] {
            let dist = inst.row(p);
            for (b, best) in near.iter_mut().enumerate() {
                for &q in &points[first[b]..first[b + 1]] {
                    *best = best.min(Inst::d_row(dist, q));
                }
            }
        }
        row.clear();
        row.extend(near.iter().enumerate().filter(|&(b, _)| b != a).map(|(b, &d)| (d, b)));
        if kn < row.len() && kn > 0 {
            row.select_nth_unstable_by(kn - 1, cmp);
            row.truncate(kn);
        }
        row.sort_unstable_by(cmp);
        nb.extend(row.iter().take(kn).map(|&(_, b)| b));
        nbd.extend(row.iter().take(kn).map(|&(d, _)| d));
    }
    (nb, nbd, kn)
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::super::testutil::{euclid, random_matrix};
    use super::super::{DistanceMatrix, SolveBudget, TourOption, construct};
    use super::*;

    /// A random order with random options of `p`.
    fn random_state(inst: &Inst<'_>, rng: &mut ChaCha8Rng) -> State {
        let mut order: Vec<usize> = (0..inst.n).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, rng.random_range(0..=i));
        }
        let opt = order.iter().map(|&v| rng.random_range(0..inst.k(v))).collect();
        State::new(inst, order, opt)
    }

    /// Every 2-opt, Or-opt and re-option move of a state with n nodes.
    fn all_moves(inst: &Inst<'_>, st: &State) -> Vec<Move> {
        let n = inst.n;
        let mut moves = Vec::new();
        for i in 0..n {
            for j in i + 1..=n {
                moves.push(Move::TwoOpt { i, j });
            }
        }
        for a in 1..=n {
            for b in a..=(a + 2).min(n) {
                for t in (0..=n).filter(|&t| t + 1 < a || t > b) {
                    if a == b {
                        for o in 0..inst.k(st.order[a - 1]) {
                            moves.push(Move::OrOpt {
                                a,
                                b,
                                t,
                                reversed: false,
                                o,
                            });
                        }
                    } else {
                        for reversed in [false, true] {
                            moves.push(Move::OrOpt {
                                a,
                                b,
                                t,
                                reversed,
                                o: 0,
                            });
                        }
                    }
                }
            }
            for o in 0..inst.k(st.order[a - 1]) {
                moves.push(Move::Reopt { s: a, o });
            }
        }
        moves
    }

    fn full(p: &TourProblem) -> TwoOptParams {
        TwoOptParams {
            neighbours: p.nodes.len() + 1,
            ..TwoOptParams::default()
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The O(1) delta of every move equals the change of the exact cost, and `apply` keeps the cached
        /// points, slots and tracked cost consistent.
        #[test]
        fn deltas_match_exact_costs(n in 1usize..9, k in 1usize..=4, closed: bool, metric: bool, seed: u64) {
            let p = if metric { euclid(n, k, closed, seed) } else { random_matrix(n, k, closed, seed) };
            let inst = Inst::new(&p);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let st = random_state(&inst, &mut rng);
            let budget = SolveBudget::unlimited();
            let search = Search::new(Inst::new(&p), &full(&p), Meter::new(&budget));
            let mut queue = WorkQueue::new(n);
            for mv in all_moves(&inst, &st) {
                let mut after = st.clone();
                let delta = search.delta(&st, mv);
                search.apply(&mut after, mv, delta, &mut queue);
                let exact = inst.eval(&after.order, &after.opt);
                let tracked = after.cost;
                prop_assert!((tracked - exact).abs() <= 1e-9 * exact.max(1.0), "{mv:?}: {tracked} vs {exact}");
                let fresh = State::new(&inst, after.order.clone(), after.opt.clone());
                prop_assert_eq!(&fresh.pos, &after.pos);
                prop_assert_eq!((&fresh.ent, &fresh.ext), (&after.ent, &after.ext));
                let mut seen = after.order.clone();
                seen.sort_unstable();
                prop_assert_eq!(seen, (0..n).collect::<Vec<_>>());
            }
        }

        /// 2-opt never returns a tour longer than its construction, for any neighbour-list size.
        #[test]
        fn never_lengthens_the_initial_tour(
            n in 0usize..60, k in 1usize..=4, closed: bool, metric: bool, seed: u64,
            neighbours in prop::sample::select(vec![1usize, 3, 8, 16, 100]), insertion: bool,
        ) {
            let p = if metric { euclid(n, k, closed, seed) } else { random_matrix(n, k, closed, seed) };
            let construction =
                if insertion { Construction::CheapestInsertion } else { Construction::NearestNeighbour };
            let params = TwoOptParams { construction, neighbours, max_chain: 3 };
            let initial = construct(&p, construction);
            let budgets = [0, 97, 2_000, u64::MAX].map(SolveBudget::new);
            for budget in budgets {
                let t = TwoOpt { params }.solve(&p, seed, &budget);
                prop_assert_eq!(t.check(&p), Ok(()));
                prop_assert!(t.cost <= initial.cost, "{} > {}", t.cost, initial.cost);
            }
        }
    }

    #[test]
    fn neighbour_lists_are_sorted_and_bounded() {
        let p = euclid(40, 4, true, 3);
        let inst = Inst::new(&p);
        let (nb, nbd, kn) = neighbour_lists(&inst, 8);
        assert_eq!((kn, nb.len(), nbd.len()), (8, 41 * 8, 41 * 8));
        for v in 0..=40 {
            let row = &nb[v * kn..(v + 1) * kn];
            assert!(!row.contains(&v));
            assert!(nbd[v * kn..(v + 1) * kn].windows(2).all(|w| w[0] <= w[1]));
        }
        // With k ≥ n every other pseudo node is listed.
        let (nb, _, kn) = neighbour_lists(&inst, 100);
        assert_eq!(kn, 40);
        let mut row = nb[..kn].to_vec();
        row.sort_unstable();
        assert_eq!(row, (1..=40).collect::<Vec<_>>());
    }

    #[test]
    fn one_way_options_skip_reversals_but_still_improve() {
        // Lanes that may only be driven one way (reverse = itself, entry ≠ exit) fail validation; the solver
        // still returns a valid tour no worse than its construction, without reversing any of them.
        let mut p = euclid(30, 2, true, 17);
        for node in &mut p.nodes {
            let first = node[0];
            *node = vec![TourOption { reverse: 0, ..first }];
        }
        let inst = Inst::new(&p);
        assert!(!inst.reversible, "the instance has one-way lanes");
        let initial = construct(&p, Construction::NearestNeighbour);
        let t = TwoOpt::default().solve(&p, 0, &SolveBudget::unlimited());
        assert_eq!(t.check(&p), Ok(()));
        assert!(t.cost <= initial.cost);
    }

    #[test]
    fn complete_lists_reach_a_two_opt_optimum_on_a_circle() {
        // Points on a circle, visited in a scrambled order: the optimum is the circle itself.
        let n = 24;
        let pts: Vec<(f64, f64)> = (0..=n)
            .map(|i| {
                let a = (i * 7 % (n + 1)) as f64 / (n + 1) as f64 * std::f64::consts::TAU;
                (10.0 * a.cos(), 10.0 * a.sin())
            })
            .collect();
        let dist = DistanceMatrix::from_fn(n + 1, |i, j| (pts[i].0 - pts[j].0).hypot(pts[i].1 - pts[j].1));
        let nodes = (1..=n)
            .map(|q| {
                vec![TourOption {
                    entry: q,
                    exit: q,
                    cost: 0.0,
                    reverse: 0,
                }]
            })
            .collect();
        let p = TourProblem {
            dist,
            depot: 0,
            nodes,
            closed: true,
        };
        let perimeter = 2.0 * (n + 1) as f64 * 10.0 * (std::f64::consts::PI / (n + 1) as f64).sin();
        let t = TwoOpt::default().solve(&p, 0, &SolveBudget::unlimited());
        assert!((t.cost - perimeter).abs() < 1e-6, "{} vs {perimeter}", t.cost);
    }
}
