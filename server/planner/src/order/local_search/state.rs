//! A tour under search ([`State`]) and the queue of nodes still to examine ([`WorkQueue`]).

use std::collections::VecDeque;

use super::super::Inst;

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
    pub(super) ent: Vec<usize>,
    /// Exit point of `order[k]` with `opt[k]`.
    pub(super) ext: Vec<usize>,
    /// Tracked cost, metres; exact after [`Search::optimise`](super::Search::optimise).
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

    pub(super) fn pop(&mut self) -> Option<usize> {
        let v = self.q.pop_front()?;
        self.queued[v] = false;
        Some(v)
    }

    pub(super) fn clear(&mut self) {
        while self.pop().is_some() {}
    }
}
