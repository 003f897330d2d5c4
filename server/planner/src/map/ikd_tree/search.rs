//! Read-only queries: k-nearest, radius, box, obstacle distance. All take `&self` and honour pending lazy
//! labels on the way down (a subtree under an "all restored" label is read as all valid) without writing.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::aabb::{Aabb, Point3};
use super::node::{F_RESTORE_ALL, NIL};
use super::{IkdTree, VoxelShape};

/// Up to `k` best candidates so far, sorted ascending by squared distance (small `k`), or a max-heap.
enum Best {
    Sorted { k: usize, items: Vec<(f32, Point3)> },
    Heap { k: usize, heap: BinaryHeap<Cand> },
}

#[derive(Clone, Copy)]
struct Cand(f32, Point3);
impl PartialEq for Cand {
    fn eq(&self, o: &Self) -> bool {
        self.0.total_cmp(&o.0) == Ordering::Equal
    }
}
impl Eq for Cand {}
impl PartialOrd for Cand {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Cand {
    fn cmp(&self, o: &Self) -> Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// Largest `k` kept in a sorted vector; above it a binary heap.
const SORTED_MAX_K: usize = 48;

struct Knn {
    best: Best,
    /// Squared radius bound: candidates farther than this are never taken.
    max2: f32,
    /// Current pruning bound: `max2` until `k` candidates are held, then the k-th distance.
    bound: f32,
}

impl Knn {
    fn new(k: usize, max2: f32) -> Self {
        let best = if k <= SORTED_MAX_K {
            Best::Sorted {
                k,
                items: Vec::with_capacity(k + 1),
            }
        } else {
            Best::Heap {
                k,
                heap: BinaryHeap::with_capacity(k + 1),
            }
        };
        Knn {
            best,
            max2,
            bound: max2,
        }
    }

    #[inline(always)]
    fn offer(&mut self, d2: f32, p: Point3) {
        if d2 > self.bound {
            return;
        }
        match &mut self.best {
            Best::Sorted { k, items } => {
                if items.len() == *k {
                    if d2 >= self.bound {
                        return;
                    }
                    items.pop();
                }
                let mut i = items.len();
                while i > 0 && items[i - 1].0 > d2 {
                    i -= 1;
                }
                items.insert(i, (d2, p));
                if items.len() == *k {
                    self.bound = items[*k - 1].0;
                }
            }
            Best::Heap { k, heap } => {
                if heap.len() == *k {
                    if d2 >= self.bound {
                        return;
                    }
                    heap.pop();
                }
                heap.push(Cand(d2, p));
                if heap.len() == *k {
                    self.bound = heap.peek().map_or(self.max2, |c| c.0);
                }
            }
        }
    }

    fn into_sorted(self) -> Vec<(Point3, f32)> {
        match self.best {
            Best::Sorted { items, .. } => items.into_iter().map(|(d, p)| (p, d)).collect(),
            Best::Heap { heap, .. } => heap.into_sorted_vec().into_iter().map(|c| (c.1, c.0)).collect(),
        }
    }
}

impl IkdTree {
    /// The `k` valid points nearest to `q`, nearest first, each with its squared distance (m²). Fewer when
    /// the tree holds fewer; empty when `k == 0` or `q` is not finite. Among equidistant points which ones
    /// are returned is unspecified.
    ///
    /// O(log n + k log k) expected.
    pub fn nearest(&self, q: &Point3, k: usize) -> Vec<(Point3, f32)> {
        self.nearest_within(q, k, f32::INFINITY)
    }

    /// Like [`IkdTree::nearest`], keeping only points at most `max_dist` metres from `q` (inclusive). A
    /// negative or NaN `max_dist` gives nothing.
    ///
    /// O(log n + k log k) expected.
    pub fn nearest_within(&self, q: &Point3, k: usize, max_dist: f32) -> Vec<(Point3, f32)> {
        if k == 0 || !q.is_finite() || max_dist.is_nan() || max_dist < 0.0 || self.root == NIL {
            return Vec::new();
        }
        let mut knn = Knn::new(k, max_dist * max_dist);
        self.knn_rec(self.root, q, false, &mut knn);
        knn.into_sorted()
    }

    fn knn_rec(&self, id: u32, q: &Point3, forced: bool, knn: &mut Knn) {
        let n = &self.arena.nodes[id as usize];
        if !forced && n.invalid == n.size {
            return;
        }
        if n.is_leaf() {
            let leaf = &self.arena.leaves[n.a as usize];
            let dead = if forced { 0 } else { n.b };
            for (i, p) in leaf.pts[..n.size as usize].iter().enumerate() {
                let d2 = p.dist2(q);
                if d2 <= knn.bound && dead & (1 << i) == 0 {
                    knn.offer(d2, *p);
                }
            }
            return;
        }
        let forced = forced || n.flags & F_RESTORE_ALL != 0;
        // Near side first (by the split plane); the far side only if its box is within the bound. The
        // plane test comes first because it needs no memory access.
        let diff = q.get(n.axis as usize) - n.split;
        let (near, far) = if diff < 0.0 { (n.a, n.b) } else { (n.b, n.a) };
        self.knn_rec(near, q, forced, knn);
        if diff * diff <= knn.bound && self.arena.nodes[far as usize].bbox.dist2(q) <= knn.bound {
            self.knn_rec(far, q, forced, knn);
        }
    }

    /// Distance in metres from `q` to the nearest valid point: the obstacle distance the planner's
    /// potential field and IKD-SWOpt use. `None` when the tree is empty or `q` is not finite.
    ///
    /// O(log n) expected; allocates nothing.
    pub fn nearest_distance(&self, q: &Point3) -> Option<f32> {
        if !q.is_finite() || self.root == NIL {
            return None;
        }
        let mut best = f32::INFINITY;
        self.nn1_rec(self.root, q, false, &mut best);
        best.is_finite().then(|| best.sqrt())
    }

    /// The valid point nearest to `q` with its squared distance (m²), like [`IkdTree::nearest`] with `k = 1`
    /// but without allocating. `None` when the tree is empty or `q` is not finite.
    ///
    /// O(log n) expected.
    pub fn nearest_point(&self, q: &Point3) -> Option<(Point3, f32)> {
        if !q.is_finite() || self.root == NIL {
            return None;
        }
        let mut best = (Point3::default(), f32::INFINITY);
        self.nn1p_rec(self.root, q, false, &mut best);
        best.1.is_finite().then_some(best)
    }

    fn nn1p_rec(&self, id: u32, q: &Point3, forced: bool, best: &mut (Point3, f32)) {
        let n = &self.arena.nodes[id as usize];
        if !forced && n.invalid == n.size {
            return;
        }
        if n.is_leaf() {
            let leaf = &self.arena.leaves[n.a as usize];
            let dead = if forced { 0 } else { n.b };
            for (i, p) in leaf.pts[..n.size as usize].iter().enumerate() {
                let d2 = p.dist2(q);
                if d2 < best.1 && dead & (1 << i) == 0 {
                    *best = (*p, d2);
                }
            }
            return;
        }
        let forced = forced || n.flags & F_RESTORE_ALL != 0;
        let diff = q.get(n.axis as usize) - n.split;
        let (near, far) = if diff < 0.0 { (n.a, n.b) } else { (n.b, n.a) };
        self.nn1p_rec(near, q, forced, best);
        if diff * diff < best.1 && self.arena.nodes[far as usize].bbox.dist2(q) < best.1 {
            self.nn1p_rec(far, q, forced, best);
        }
    }

    fn nn1_rec(&self, id: u32, q: &Point3, forced: bool, best: &mut f32) {
        let n = &self.arena.nodes[id as usize];
        if !forced && n.invalid == n.size {
            return;
        }
        if n.is_leaf() {
            let leaf = &self.arena.leaves[n.a as usize];
            let dead = if forced { 0 } else { n.b };
            for (i, p) in leaf.pts[..n.size as usize].iter().enumerate() {
                let d2 = p.dist2(q);
                if d2 < *best && dead & (1 << i) == 0 {
                    *best = d2;
                }
            }
            return;
        }
        let forced = forced || n.flags & F_RESTORE_ALL != 0;
        let diff = q.get(n.axis as usize) - n.split;
        let (near, far) = if diff < 0.0 { (n.a, n.b) } else { (n.b, n.a) };
        self.nn1_rec(near, q, forced, best);
        if diff * diff < *best && self.arena.nodes[far as usize].bbox.dist2(q) < *best {
            self.nn1_rec(far, q, forced, best);
        }
    }

    /// Every valid point at most `r` metres from `q` (inclusive), nearest first, with squared distances
    /// (m²). Empty for a negative or NaN `r` or a non-finite `q`.
    ///
    /// O(log n + m log m) expected for m points reported.
    pub fn within_radius(&self, q: &Point3, r: f32) -> Vec<(Point3, f32)> {
        let mut out = Vec::new();
        if !q.is_finite() || r.is_nan() || r < 0.0 || self.root == NIL {
            return out;
        }
        self.radius_rec(self.root, q, r * r, false, &mut out);
        out.sort_by(|a, b| a.1.total_cmp(&b.1));
        out
    }

    fn radius_rec(&self, id: u32, q: &Point3, r2: f32, forced: bool, out: &mut Vec<(Point3, f32)>) {
        let n = &self.arena.nodes[id as usize];
        if (!forced && n.invalid == n.size) || n.bbox.dist2(q) > r2 {
            return;
        }
        if n.is_leaf() {
            let leaf = &self.arena.leaves[n.a as usize];
            let dead = if forced { 0 } else { n.b };
            for (i, p) in leaf.pts[..n.size as usize].iter().enumerate() {
                let d2 = p.dist2(q);
                if d2 <= r2 && dead & (1 << i) == 0 {
                    out.push((*p, d2));
                }
            }
            return;
        }
        let forced = forced || n.flags & F_RESTORE_ALL != 0;
        self.radius_rec(n.a, q, r2, forced, out);
        self.radius_rec(n.b, q, r2, forced, out);
    }

    /// Every valid point inside the closed box `b`, in tree order. Empty for an empty or NaN box.
    ///
    /// O(log n + m) expected for m points reported; a subtree wholly inside `b` is copied without tests.
    pub fn within_box(&self, b: &Aabb) -> Vec<Point3> {
        let mut out = Vec::new();
        if b.is_valid() && self.root != NIL {
            self.box_rec(self.root, b, false, &mut out);
        }
        out
    }

    fn box_rec(&self, id: u32, b: &Aabb, forced: bool, out: &mut Vec<Point3>) {
        let n = &self.arena.nodes[id as usize];
        if (!forced && n.invalid == n.size) || !n.bbox.intersects(b) {
            return;
        }
        if b.contains_box(&n.bbox) {
            self.arena.collect_live(id, forced, out);
            return;
        }
        if n.is_leaf() {
            let leaf = &self.arena.leaves[n.a as usize];
            let dead = if forced { 0 } else { n.b };
            for (i, p) in leaf.pts[..n.size as usize].iter().enumerate() {
                if dead & (1 << i) == 0 && b.contains(p) {
                    out.push(*p);
                }
            }
            return;
        }
        let forced = forced || n.flags & F_RESTORE_ALL != 0;
        self.box_rec(n.a, b, forced, out);
        self.box_rec(n.b, b, forced, out);
    }

    /// For every query, the smallest squared distance (m²) from its voxel's centre to a valid point of that
    /// voxel (+inf when none), in one walk down the tree: each node is visited once, with the queries whose
    /// search box may meet it (copied onto a stack, so the walk reads memory in order).
    pub(crate) fn voxel_best_multi(&self, qs: &mut [VoxQuery]) {
        if self.root == NIL || qs.is_empty() {
            return;
        }
        let mut scratch: Vec<(Aabb, u32)> = qs.iter().enumerate().map(|(i, q)| (q.shape.outer, i as u32)).collect();
        self.voxel_multi_rec(self.root, 0, qs.len(), &mut scratch, qs, false);
    }

    fn voxel_multi_rec(
        &self,
        id: u32,
        lo: usize,
        hi: usize,
        scratch: &mut Vec<(Aabb, u32)>,
        qs: &mut [VoxQuery],
        forced: bool,
    ) {
        let n = &self.arena.nodes[id as usize];
        if !forced && n.invalid == n.size {
            return;
        }
        if n.is_leaf() {
            let vs = self.params.voxel_size;
            let leaf = &self.arena.leaves[n.a as usize];
            let dead = if forced { 0 } else { n.b };
            for &(sb, qi) in &scratch[lo..hi] {
                if !sb.intersects(&n.bbox) {
                    continue;
                }
                let q = &mut qs[qi as usize];
                let pts = &leaf.pts[..n.size as usize];
                let mut m = sb.inside_mask(pts) & !dead;
                while m != 0 {
                    let p = &pts[m.trailing_zeros() as usize];
                    m &= m - 1;
                    if q.shape.holds(p, vs) {
                        let d2 = p.dist2(&q.shape.centre);
                        if d2 < q.best {
                            q.best = d2;
                        }
                    }
                }
            }
            return;
        }
        let forced = forced || n.flags & F_RESTORE_ALL != 0;
        // Route by the split plane: left points are <= split, right points >= split on `axis`.
        let (axis, split) = (n.axis as usize, n.split);
        for (child, left) in [(n.a, true), (n.b, false)] {
            let start = scratch.len();
            for i in lo..hi {
                let it = scratch[i];
                if (left && it.0.min.get(axis) <= split) || (!left && it.0.max.get(axis) >= split) {
                    scratch.push(it);
                }
            }
            let end = scratch.len();
            if end > start {
                self.voxel_multi_rec(child, start, end, scratch, qs, forced);
            }
            scratch.truncate(start);
        }
    }
}

/// One voxel's question for [`IkdTree::voxel_best_multi`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct VoxQuery {
    /// The voxel.
    pub shape: VoxelShape,
    /// Answer: best squared distance to the voxel centre among its valid points, +inf when none.
    pub best: f32,
}
