//! Lazy deletion (box, exact point, voxel) and restoration of tombstones.

use super::IkdTree;
use super::aabb::{Aabb, Point3};
use super::node::{F_BG_ANC, F_BG_ROOT, NIL};
use super::rebuild::LogOp;
use super::region::Region;

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
        let n = self.delete_regions(&[Region::Box(*b)]);
        self.finish_write();
        n
    }

    /// Deletes (lazily) every valid point whose coordinates equal one of `points` exactly, duplicates
    /// included, and returns how many were deleted. Non-finite entries match nothing.
    ///
    /// O(m log n) expected for m entries.
    pub fn delete_points(&mut self, points: &[Point3]) -> usize {
        self.poll_background(false);
        let regions: Vec<Region> = points
            .iter()
            .filter(|p| p.is_finite())
            .map(|p| Region::Point(*p))
            .collect();
        let n = self.delete_regions(&regions);
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
        let n = if self.root == NIL {
            0
        } else {
            self.restore_rec(self.root, b)
        };
        self.finish_write();
        n
    }

    /// Deletes what any of `regions` covers in one walk down the tree (each node is visited once, with the
    /// regions that reach it), rebuilding the root if it then violates a criterion.
    pub(crate) fn delete_regions(&mut self, regions: &[Region]) -> usize {
        if self.root == NIL || regions.is_empty() {
            return 0;
        }
        let mut scratch: Vec<(Aabb, u32)> = regions
            .iter()
            .enumerate()
            .map(|(i, r)| (r.search_box(), i as u32))
            .collect();
        let mut path = Vec::with_capacity(64);
        let (n, v) = self.delete_multi_rec(self.root, 0, regions.len(), &mut scratch, regions, &mut path, false);
        if v {
            self.rebuild(self.root, &[]);
        }
        n
    }

    /// `scratch[lo..hi]` (the top of the stack) indexes the regions that reach node `id`.
    #[allow(clippy::too_many_arguments)]
    fn delete_multi_rec(
        &mut self,
        id: u32,
        lo: usize,
        hi: usize,
        scratch: &mut Vec<(Aabb, u32)>,
        regions: &[Region],
        path: &mut Vec<u32>,
        inside_bg: bool,
    ) -> (usize, bool) {
        let n = self.arena.nodes[id as usize];
        if n.invalid == n.size {
            return (0, false);
        }
        let inside = inside_bg || n.flags & F_BG_ROOT != 0;
        if n.flags & F_BG_ROOT != 0 {
            for i in lo..hi {
                self.log(LogOp::Delete(regions[scratch[i].1 as usize]));
            }
        }
        if n.flags & F_BG_ANC == 0 && scratch[lo..hi].iter().any(|r| regions[r.1 as usize].swallows(&n.bbox)) {
            let cnt = n.live() as usize;
            self.arena.label_all(id, true);
            return (cnt, !inside && self.violates(id));
        }
        if n.is_leaf() {
            let leaf = &self.arena.leaves[n.a as usize];
            let mut dead = n.b;
            let mut cnt = 0;
            for &(sb, r) in &scratch[lo..hi] {
                if !sb.intersects(&n.bbox) {
                    continue;
                }
                let pts = &leaf.pts[..n.size as usize];
                let mut hit = sb.inside_mask(pts) & !dead;
                if let Region::Voxel { shape, vs } = &regions[r as usize] {
                    // The search box is a little larger than the voxel: check the candidates exactly.
                    let mut m = hit;
                    while m != 0 {
                        let i = m.trailing_zeros();
                        m &= m - 1;
                        if !shape.holds(&pts[i as usize], *vs) {
                            hit &= !(1 << i);
                        }
                    }
                }
                dead |= hit;
                cnt += hit.count_ones() as usize;
            }
            let node = &mut self.arena.nodes[id as usize];
            node.b = dead;
            node.invalid += cnt as u32;
            return (cnt, cnt > 0 && !inside && self.violates(id));
        }
        self.arena.push_down(id);
        path.push(id);
        let mut total = 0;
        let mut v = [false; 2];
        // Route by the split plane: left points are <= split, right points >= split on `axis`.
        let (axis, split) = (n.axis as usize, n.split);
        for (ci, child) in [n.a, n.b].into_iter().enumerate() {
            let start = scratch.len();
            for i in lo..hi {
                let it = scratch[i];
                if (ci == 0 && it.0.min.get(axis) <= split) || (ci == 1 && it.0.max.get(axis) >= split) {
                    scratch.push(it);
                }
            }
            let end = scratch.len();
            if end > start {
                let (c, vv) = self.delete_multi_rec(child, start, end, scratch, regions, path, inside);
                total += c;
                v[ci] = vv;
            }
            scratch.truncate(start);
        }
        path.pop();
        self.arena.pull_up(id);
        let r = self.resolve(id, v[0], v[1], path, inside);
        (total, r)
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
            let leaf = &self.arena.leaves[n.a as usize];
            let back = b.inside_mask(&leaf.pts[..n.size as usize]) & n.b;
            let cnt = back.count_ones();
            let node = &mut self.arena.nodes[id as usize];
            node.b &= !back;
            node.invalid -= cnt;
            return cnt as usize;
        }
        self.arena.push_down(id);
        let c = self.restore_rec(n.a, b) + self.restore_rec(n.b, b);
        self.arena.pull_up(id);
        c
    }
}
