//! Lazy deletion (box, exact point, voxel) and restoration of tombstones.

use super::aabb::{Aabb, Point3};
use super::node::{F_BG_ANC, F_BG_ROOT, NIL};
use super::rebuild::LogOp;
use super::{IkdTree, VoxelKey, voxel_key};

/// What a delete removes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Region {
    /// Every valid point inside the closed box.
    Box(Aabb),
    /// Every valid point of voxel `key` (of side `vs` metres); `search` bounds the voxel.
    Voxel { key: VoxelKey, vs: f32, search: Aabb },
    /// Every valid point with exactly these coordinates.
    Point(Point3),
}

impl Region {
    #[inline]
    fn intersects(&self, b: &Aabb) -> bool {
        match self {
            Region::Box(r) => r.intersects(b),
            Region::Voxel { search, .. } => search.intersects(b),
            Region::Point(p) => b.contains(p),
        }
    }

    #[inline]
    fn matches(&self, p: &Point3) -> bool {
        match self {
            Region::Box(r) => r.contains(p),
            Region::Voxel { key, vs, search } => search.contains(p) && voxel_key(p, *vs) == *key,
            Region::Point(q) => p == q,
        }
    }

    /// True when every point inside `b` matches (only boxes can say so).
    #[inline]
    fn swallows(&self, b: &Aabb) -> bool {
        match self {
            Region::Box(r) => r.contains_box(b),
            _ => false,
        }
    }
}

impl IkdTree {
    /// Deletes (lazily) every valid point inside the closed box `b` and returns how many. A subtree wholly
    /// inside `b` is labelled in O(1); the tombstones are reclaimed by the rebuilds this triggers (in the
    /// background for large subtrees). An empty or NaN box deletes nothing.
    ///
    /// O(log n + nodes on the box's boundary), plus the amortised rebuilds.
    pub fn delete_box(&mut self, b: &Aabb) -> usize {
        if !b.is_valid() {
            return 0;
        }
        self.poll_background(false);
        let n = self.delete_region(&Region::Box(*b));
        self.finish_write();
        n
    }

    /// Deletes (lazily) every valid point whose coordinates equal one of `points` exactly, duplicates
    /// included, and returns how many were deleted. Non-finite entries match nothing.
    ///
    /// O(m log n) expected for m entries.
    pub fn delete_points(&mut self, points: &[Point3]) -> usize {
        self.poll_background(false);
        let mut n = 0;
        for p in points.iter().filter(|p| p.is_finite()) {
            n += self.delete_region(&Region::Point(*p));
        }
        self.finish_write();
        n
    }

    /// Makes valid again the tombstones inside the closed box `b` that no rebuild has reclaimed yet, and
    /// returns how many. Points deleted and then reclaimed by a rebuild (or by a background rebuild in
    /// flight, whose subtree this skips) are gone for good. Restoring can break down-sampling's
    /// one-point-per-voxel rule; later down-sampled inserts compare against all valid points.
    ///
    /// O(log n + nodes on the box's boundary); a subtree wholly inside `b` is labelled in O(1).
    pub fn restore_box(&mut self, b: &Aabb) -> usize {
        if !b.is_valid() || self.root == NIL {
            return 0;
        }
        self.poll_background(false);
        let n = if self.root == NIL { 0 } else { self.restore_rec(self.root, b) };
        self.finish_write();
        n
    }

    /// Deletes what `region` covers, rebuilding the root if it then violates a criterion.
    pub(crate) fn delete_region(&mut self, region: &Region) -> usize {
        if self.root == NIL {
            return 0;
        }
        let mut path = Vec::with_capacity(64);
        let (n, v) = self.delete_rec(self.root, region, &mut path, false);
        if v {
            self.rebuild(self.root, &[]);
        }
        n
    }

    fn delete_rec(&mut self, id: u32, region: &Region, path: &mut Vec<u32>, inside_bg: bool) -> (usize, bool) {
        let n = self.arena.nodes[id as usize];
        if n.invalid == n.size || !region.intersects(&n.bbox) {
            return (0, false);
        }
        let inside = inside_bg || n.flags & F_BG_ROOT != 0;
        if n.flags & F_BG_ROOT != 0 {
            self.log(LogOp::Delete(*region));
        }
        if n.flags & F_BG_ANC == 0 && region.swallows(&n.bbox) {
            let cnt = n.live() as usize;
            self.arena.label_all(id, true);
            return (cnt, !inside && self.violates(id));
        }
        if n.is_leaf() {
            let leaf = &mut self.arena.leaves[n.a as usize];
            let mut cnt = 0;
            for i in 0..n.size as usize {
                if leaf.dead & (1 << i) == 0 && region.matches(&leaf.pts[i]) {
                    leaf.dead |= 1 << i;
                    cnt += 1;
                }
            }
            self.arena.nodes[id as usize].invalid += cnt as u32;
            return (cnt, cnt > 0 && !inside && self.violates(id));
        }
        self.arena.push_down(id);
        path.push(id);
        let (ca, va) = self.delete_rec(n.a, region, path, inside);
        let (cb, vb) = self.delete_rec(n.b, region, path, inside);
        path.pop();
        self.arena.pull_up(id);
        let v = self.resolve(id, va, vb, path, inside);
        (ca + cb, v)
    }

    fn restore_rec(&mut self, id: u32, b: &Aabb) -> usize {
        let n = self.arena.nodes[id as usize];
        if n.invalid == 0 || n.flags & F_BG_ROOT != 0 || !b.intersects(&n.bbox) {
            return 0;
        }
        if n.flags & F_BG_ANC == 0 && b.contains_box(&n.bbox) {
            self.arena.label_all(id, false);
            return n.invalid as usize;
        }
        if n.is_leaf() {
            let leaf = &mut self.arena.leaves[n.a as usize];
            let mut cnt = 0;
            for i in 0..n.size as usize {
                if leaf.dead & (1 << i) != 0 && b.contains(&leaf.pts[i]) {
                    leaf.dead &= !(1 << i);
                    cnt += 1;
                }
            }
            self.arena.nodes[id as usize].invalid -= cnt;
            return cnt as usize;
        }
        self.arena.push_down(id);
        let c = self.restore_rec(n.a, b) + self.restore_rec(n.b, b);
        self.arena.pull_up(id);
        c
    }
}
