//! Each node's nearest other nodes, the candidates of the local search's moves.

use super::super::Inst;

/// For every pseudo node (nodes 0..n, depot n) its `k` nearest other pseudo nodes, nearest first (ties by
/// index). Returns the flattened lists, the matching distances and their common length min(k, n).
pub(super) fn neighbour_lists(inst: &Inst<'_>, k: usize) -> (Vec<usize>, Vec<f64>, usize) {
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
