//! Initial tours: nearest neighbour and cheapest insertion, each followed by the exact option assignment
//! ([`super::best_options`]). Both are O(n²·k) for n nodes with k options each and use no randomness.

use super::{Inst, Tour, TourProblem, dp_options};

/// How the initial tour is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Construction {
    /// From the depot, repeatedly go to the unvisited node whose option is cheapest to reach and drive
    /// (distance to its entry plus its inner cost). O(n²·k).
    #[default]
    NearestNeighbour,
    /// Repeatedly insert the node, option and position that lengthen the partial tour least. O(n²·k) expected
    /// (a node rescans the whole tour only when the gap it wanted was split).
    CheapestInsertion,
}

/// The initial tour `method` builds for `problem`, with optimal options for its order. Never panics; nodes
/// without options or with out-of-range points make the cost `+∞` (see [`TourProblem::validate`]).
pub fn construct(problem: &TourProblem, method: Construction) -> Tour {
    let inst = Inst::new(problem);
    let order = construct_order(&inst, method);
    let (options, _) = dp_options(&inst, &order);
    Tour::new(problem, order, options)
}

/// The visiting order `method` builds (options are chosen afterwards by the dynamic programme).
pub(crate) fn construct_order(inst: &Inst<'_>, method: Construction) -> Vec<usize> {
    match method {
        Construction::NearestNeighbour => nearest_neighbour(inst),
        Construction::CheapestInsertion => cheapest_insertion(inst),
    }
}

fn nearest_neighbour(inst: &Inst<'_>) -> Vec<usize> {
    let n = inst.n;
    let mut visited = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut at = inst.depot;
    for _ in 0..n {
        // (score, node, exit point); ties go to the lowest node and option index.
        let mut best: Option<(f64, usize, usize)> = None;
        let row = inst.row(at);
        for v in (0..n).filter(|&v| !visited[v]) {
            for o in 0..inst.k(v) {
                let t = inst.opt(v, o);
                let score = Inst::d_row(row, t.entry) + t.cost;
                if best.is_none_or(|b| score.total_cmp(&b.0).is_lt()) {
                    best = Some((score, v, t.exit));
                }
            }
        }
        let Some((_, v, exit)) = best else { break };
        visited[v] = true;
        order.push(v);
        at = exit;
    }
    order
}

fn cheapest_insertion(inst: &Inst<'_>) -> Vec<usize> {
    let n = inst.n;
    let depot = n; // pseudo node: the tour's start
    let end = n + 1; // pseudo node: the tour's end (the depot again when closed, nothing when open)
    let mut next = vec![end; n + 1];
    let mut chosen = vec![0usize; n];
    let mut inserted = vec![false; n];
    let out = |x: usize, chosen: &[usize]| {
        if x == depot {
            inst.depot
        } else {
            inst.opt(x, chosen[x]).exit
        }
    };
    let gap_cost = |x: usize, v: usize, o: usize, next: &[usize], chosen: &[usize]| -> f64 {
        let from = out(x, chosen);
        let y = next[x];
        let t = inst.opt(v, o);
        let to = if y == end {
            inst.closed.then_some(inst.depot)
        } else {
            Some(inst.opt(y, chosen[y]).entry)
        };
        let (into_y, old) = match to {
            Some(p) => (inst.d(t.exit, p), inst.d(from, p)),
            None => (0.0, 0.0),
        };
        inst.d(from, t.entry) + t.cost + into_y - old
    };
    // best[v] = (insertion cost, gap after this pseudo node, option)
    let scan = |v: usize, next: &[usize], chosen: &[usize]| -> (f64, usize, usize) {
        let mut best = (f64::INFINITY, depot, 0usize);
        let mut first = true;
        let mut x = depot;
        loop {
            for o in 0..inst.k(v) {
                let c = gap_cost(x, v, o, next, chosen);
                if first || c.total_cmp(&best.0).is_lt() {
                    best = (c, x, o);
                    first = false;
                }
            }
            if next[x] == end {
                break;
            }
            x = next[x];
        }
        best
    };
    let mut best: Vec<(f64, usize, usize)> = (0..n).map(|v| scan(v, &next, &chosen)).collect();
    for _ in 0..n {
        let pick = (0..n)
            .filter(|&v| !inserted[v])
            .min_by(|&a, &b| best[a].0.total_cmp(&best[b].0).then(a.cmp(&b)));
        let Some(v) = pick else { break };
        let (_, x, o) = best[v];
        inserted[v] = true;
        chosen[v] = o;
        next[v] = next[x];
        next[x] = v;
        for u in 0..n {
            if inserted[u] {
                continue;
            }
            if best[u].1 == x {
                best[u] = scan(u, &next, &chosen);
                continue;
            }
            for g in [x, v] {
                for o in 0..inst.k(u) {
                    let c = gap_cost(g, u, o, &next, &chosen);
                    if c.total_cmp(&best[u].0).is_lt() {
                        best[u] = (c, g, o);
                    }
                }
            }
        }
    }
    let mut order = Vec::with_capacity(n);
    let mut x = next[depot];
    while x != end && order.len() < n {
        order.push(x);
        x = next[x];
    }
    order
}

#[cfg(test)]
mod tests {
    use super::super::testutil::euclid;
    use super::super::{DistanceMatrix, TourOption};
    use super::*;

    #[test]
    fn both_constructions_visit_every_node_once() {
        for n in [0, 1, 2, 7, 50] {
            for closed in [true, false] {
                let p = euclid(n, 4, closed, n as u64);
                for m in [
                    Construction::NearestNeighbour,
                    Construction::CheapestInsertion,
                ] {
                    let t = construct(&p, m);
                    assert_eq!(t.check(&p), Ok(()), "{m:?} n={n}");
                    assert_eq!(t.cost, super::super::tour_cost(&p, &t.order, &t.options));
                }
            }
        }
    }

    #[test]
    fn square_corners() {
        // Depot at (0,0); nodes at the other corners of a 10 m square and at its centre.
        let pts = [
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 10.0),
            (0.0, 10.0),
            (5.0, 5.0),
        ];
        let dist = DistanceMatrix::from_fn(5, |i, j| {
            let (a, b): ((f64, f64), (f64, f64)) = (pts[i], pts[j]);
            (a.0 - b.0).hypot(a.1 - b.1)
        });
        let nodes = (1..5)
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
        let ci = construct(&p, Construction::CheapestInsertion);
        // The perimeter with one detour through the centre: 30 + 2·√50.
        assert!(
            (ci.cost - (30.0 + 2.0 * 50f64.sqrt())).abs() < 1e-9,
            "{ci:?}"
        );
        let nn = construct(&p, Construction::NearestNeighbour);
        assert_eq!(nn.order[0], 3, "the centre is nearest to the depot");
    }
}
