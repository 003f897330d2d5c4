//! Building a perfectly balanced subtree from a list of points (median split on the widest axis).

use super::aabb::{Aabb, Point3};
use super::node::{Arena, F_LEAF, LEAF_CAP, Leaf, NIL, Node};

/// Number of leaves [`Arena::build`] makes for `n` points. O(leaves).
pub(crate) fn leaf_count(n: usize) -> usize {
    if n <= LEAF_CAP {
        1
    } else {
        let h = n / 2;
        leaf_count(h) + leaf_count(n - h)
    }
}

impl Arena {
    /// Builds a balanced subtree holding `pts` (all valid) and returns its root. An empty `pts` gives one
    /// empty leaf. Nodes are allocated in pre-order, so a node's left child usually follows it in memory.
    ///
    /// O(n log n) time; the sizes of sibling subtrees differ by at most one point.
    pub fn build(&mut self, pts: &mut [Point3]) -> u32 {
        if self.free_nodes.is_empty() && self.free_leaves.is_empty() {
            let leaves = leaf_count(pts.len());
            self.nodes.reserve(2 * leaves - 1);
            self.leaves.reserve(leaves);
        }
        let bbox = Aabb::of_points(pts);
        self.build_rec(pts, bbox)
    }

    /// `bounds` is the exact box of `pts`: it chooses the split axis (the widest), so that flat patches
    /// (ground, walls) are never split across their thickness. Measuring it costs a pass per level, like
    /// the selection itself.
    fn build_rec(&mut self, pts: &mut [Point3], bounds: Aabb) -> u32 {
        let n = pts.len();
        if n <= LEAF_CAP {
            let mut leaf = Leaf::EMPTY;
            leaf.pts[..n].copy_from_slice(pts);
            let slot = self.alloc_leaf(leaf);
            return self.alloc_node(Node::leaf(slot, n as u32, Aabb::of_points(pts)));
        }
        let ext = [
            bounds.max.x - bounds.min.x,
            bounds.max.y - bounds.min.y,
            bounds.max.z - bounds.min.z,
        ];
        let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] {
            0
        } else if ext[1] >= ext[2] {
            1
        } else {
            2
        };
        let mid = n / 2;
        // One comparator per axis, so that the axis is not re-dispatched on every comparison.
        match axis {
            0 => pts.select_nth_unstable_by(mid, |p, q| p.x.total_cmp(&q.x)),
            1 => pts.select_nth_unstable_by(mid, |p, q| p.y.total_cmp(&q.y)),
            _ => pts.select_nth_unstable_by(mid, |p, q| p.z.total_cmp(&q.z)),
        };
        let split = pts[mid].get(axis);
        let id = self.alloc_node(Node {
            bbox: bounds,
            size: n as u32,
            invalid: 0,
            a: NIL,
            b: NIL,
            split,
            axis: axis as u8,
            flags: 0,
        });
        debug_assert!(self.nodes[id as usize].flags & F_LEAF == 0);
        let (lo, hi) = pts.split_at_mut(mid);
        let (lb, hb) = (Aabb::of_points(lo), Aabb::of_points(hi));
        let a = self.build_rec(lo, lb);
        let b = self.build_rec(hi, hb);
        let bbox = self.nodes[a as usize].bbox.union(&self.nodes[b as usize].bbox);
        let node = &mut self.nodes[id as usize];
        node.a = a;
        node.b = b;
        node.bbox = bbox;
        id
    }
}
