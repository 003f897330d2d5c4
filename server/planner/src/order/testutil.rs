//! Instances and exhaustive solvers shared by the tests of every strategy.

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
