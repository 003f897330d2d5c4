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
    /// Repeatedly insert the node, option and position that lengthen the partial tour least. O(n²·k)
    /// expected: every node remembers its few best gaps and rescans the tour only when they are used up.
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

/// Insertion candidates a node remembers between full rescans of the tour.
const KEEP: usize = 8;

/// An insertion candidate: (added cost in metres, gap = the pseudo node it follows, option).
type Cand = (f64, usize, usize);

/// A gap of the partial tour, ready to price insertions (see `cheapest_insertion`).
struct Gap<'m> {
    /// The pseudo node the gap follows.
    x: usize,
    /// Matrix row of the point the gap starts at.
    from: Option<&'m [f64]>,
    /// Matrix row of the point it ends at; `None` for the open end of an open tour.
    to: Option<Option<&'m [f64]>>,
    /// Its current length, metres.
    old: f64,
}

fn by_cost(a: &Cand, b: &Cand) -> std::cmp::Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

/// Cheapest insertion. Every uninserted node keeps its `KEEP` best gaps and `floor`, a lower bound on
/// the cost of every gap it does not list. Gaps never change cost while they exist, so while the best
/// listed gap is no dearer than `floor` it is the node's best; only otherwise is the whole tour rescanned.
/// Each insertion offers the two new gaps to every node (O(n·k)), so the total is O(n²·k) plus the
/// rare rescans (O(n·k) each).
fn cheapest_insertion(inst: &Inst<'_>) -> Vec<usize> {
    let n = inst.n;
    let depot = n; // pseudo node: the tour's start
    let end = n + 1; // pseudo node: the tour's end (the depot again when closed, nothing when open)
    let mut next = vec![end; n + 1];
    let mut chosen = vec![0usize; n];
    let mut inserted = vec![false; n];
    // The gap after pseudo node `x`: where it starts, where it ends (None: the open end), the matrix rows
    // of both (so that offering it to every node reads two cached rows), and its current length.
    let gap = |x: usize, next: &[usize], chosen: &[usize]| -> Gap<'_> {
        let from = if x == depot {
            inst.depot
        } else {
            inst.opt(x, chosen[x]).exit
        };
        let y = next[x];
        let to = if y == end {
            inst.closed.then_some(inst.depot)
        } else {
            Some(inst.opt(y, chosen[y]).entry)
        };
        Gap {
            x,
            from: inst.row(from),
            to: to.map(|p| inst.row(p)),
            old: to.map_or(0.0, |p| inst.d(from, p)),
        }
    };
    // Cheapest way to put `u` into gap `g`.
    let gap_cost = |g: &Gap<'_>, u: usize| -> Cand {
        let mut best: Option<Cand> = None;
        for o in 0..inst.k(u) {
            let t = inst.opt(u, o);
            let into_y = g.to.map_or(0.0, |row| Inst::d_row(row, t.exit));
            let c = (Inst::d_row(g.from, t.entry) + t.cost + into_y - g.old, g.x, o);
            if best.is_none_or(|b| by_cost(&c, &b).is_lt()) {
                best = Some(c);
            }
        }
        best.unwrap_or((f64::INFINITY, g.x, 0))
    };
    let rescan = |u: usize, next: &[usize], chosen: &[usize], list: &mut Vec<Cand>| -> f64 {
        let mut all = Vec::new();
        let mut x = depot;
        loop {
            all.push(gap_cost(&gap(x, next, chosen), u));
            if next[x] == end {
                break;
            }
            x = next[x];
        }
        all.sort_unstable_by(by_cost);
        list.clear();
        list.extend(all.iter().take(KEEP));
        all.get(KEEP).map_or(f64::INFINITY, |c| c.0)
    };
    let mut lists: Vec<Vec<Cand>> = vec![Vec::with_capacity(KEEP); n];
    let mut floor = vec![f64::INFINITY; n];
    for u in 0..n {
        floor[u] = rescan(u, &next, &chosen, &mut lists[u]);
    }
    let best_of = |list: &[Cand]| list.iter().copied().min_by(by_cost);
    for _ in 0..n {
        let pick = (0..n)
            .filter(|&u| !inserted[u])
            .filter_map(|u| best_of(&lists[u]).map(|c| (c, u)))
            .min_by(|a, b| by_cost(&a.0, &b.0).then(a.1.cmp(&b.1)));
        let Some(((_, x, o), v)) = pick else { break };
        inserted[v] = true;
        chosen[v] = o;
        next[v] = next[x];
        next[x] = v;
        let new_gaps = [gap(x, &next, &chosen), gap(v, &next, &chosen)];
        for u in 0..n {
            if inserted[u] {
                continue;
            }
            let list = &mut lists[u];
            list.retain(|c| c.1 != x); // the gap after x was split
            for g in &new_gaps {
                let c = gap_cost(g, u);
                if list.len() < KEEP {
                    list.push(c);
                    continue;
                }
                let worst = (0..list.len()).max_by(|&i, &j| by_cost(&list[i], &list[j]));
                match worst {
                    Some(w) if by_cost(&c, &list[w]).is_lt() => {
                        floor[u] = floor[u].min(list[w].0);
                        list[w] = c;
                    }
                    _ => floor[u] = floor[u].min(c.0),
                }
            }
            if best_of(list).is_none_or(|b| b.0 > floor[u]) {
                floor[u] = rescan(u, &next, &chosen, list);
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
                for m in [Construction::NearestNeighbour, Construction::CheapestInsertion] {
                    let t = construct(&p, m);
                    assert_eq!(t.check(&p), Ok(()), "{m:?} n={n}");
                    assert_eq!(t.cost, super::super::tour_cost(&p, &t.order, &t.options));
                }
            }
        }
    }

    /// The textbook O(n³) cheapest insertion: rescan every gap for every node at every step.
    fn naive_cheapest_insertion(p: &TourProblem) -> Vec<usize> {
        let inst = Inst::new(p);
        let mut tour: Vec<(usize, usize)> = Vec::new(); // (node, option)
        let mut left: Vec<usize> = (0..inst.n).collect();
        let point_after = |tour: &[(usize, usize)], g: usize| {
            if g == 0 {
                inst.depot
            } else {
                inst.opt(tour[g - 1].0, tour[g - 1].1).exit
            }
        };
        while !left.is_empty() {
            let mut best: Option<(f64, usize, usize, usize)> = None; // (cost, gap, node, option)
            for &u in &left {
                for g in 0..=tour.len() {
                    let from = point_after(&tour, g);
                    let to = match tour.get(g) {
                        Some(&(y, o)) => Some(inst.opt(y, o).entry),
                        None => inst.closed.then_some(inst.depot),
                    };
                    for o in 0..inst.k(u) {
                        let t = inst.opt(u, o);
                        let (into, old) = to.map_or((0.0, 0.0), |q| (inst.d(t.exit, q), inst.d(from, q)));
                        let c = inst.d(from, t.entry) + t.cost + into - old;
                        if best.is_none_or(|b| c < b.0) {
                            best = Some((c, g, u, o));
                        }
                    }
                }
            }
            let Some((_, g, u, o)) = best else { break };
            tour.insert(g, (u, o));
            left.retain(|&x| x != u);
        }
        tour.into_iter().map(|(v, _)| v).collect()
    }

    #[test]
    fn cheapest_insertion_matches_the_textbook_version() {
        for seed in 0..20 {
            let p = euclid(5 + 3 * seed as usize, 4, seed % 2 == 0, seed);
            let fast = construct(&p, Construction::CheapestInsertion);
            let naive = naive_cheapest_insertion(&p);
            let (_, naive_cost) = super::super::best_options(&p, &naive);
            assert!(
                (fast.cost - naive_cost).abs() < 1e-9,
                "seed {seed}: {} vs {naive_cost}",
                fast.cost
            );
        }
    }

    #[test]
    fn square_corners() {
        // Depot at (0,0); nodes at the other corners of a 10 m square and at its centre.
        let pts = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0), (5.0, 5.0)];
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
        assert!((ci.cost - (30.0 + 2.0 * 50f64.sqrt())).abs() < 1e-9, "{ci:?}");
        let nn = construct(&p, Construction::NearestNeighbour);
        assert_eq!(nn.order[0], 3, "the centre is nearest to the depot");
    }
}
