//! The local search's moves ([`Move`]: 2-opt, Or-opt, re-option), their O(1) cost deltas and how they are
//! applied.

use super::{Search, State, WorkQueue};

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

impl Search<'_, '_> {
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
}
