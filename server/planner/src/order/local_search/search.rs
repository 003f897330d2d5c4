//! The search over one problem ([`Search`]): neighbour lists, the best move around a node, and the descent
//! that alternates local search with the exact option assignment.

use super::super::{Inst, Meter, dp_options, improves};
use super::neighbours::neighbour_lists;
use super::{Move, State, TwoOptParams, WorkQueue};

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
