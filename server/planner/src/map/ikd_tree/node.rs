//! Storage: an index arena of nodes and fixed-size leaf buckets, with the lazy labels and their push-down.
//!
//! Invariants (hold between public operations, for every node reachable from a root):
//! - `size` counts the points stored under the node, tombstones included; `invalid` counts the tombstones,
//!   both as seen *at this node*: a pending label on the node itself is already reflected in them, while
//!   the descendants' counts are stale until [`Arena::push_down`] hands the label on.
//! - `bbox` holds every stored point under the node (tombstones included), so it is a safe bound for
//!   pruning; it is tightened when the node is rebuilt.
//! - An internal node has exactly two children; a point of the left child is `<= split` on `axis` and a
//!   point of the right child is `>= split` (ties may sit on either side, so searches use the boxes).
//! - A leaf holds `size <= LEAF_CAP` points in `pts[..size]`; bit `i` of its node's `b` (the tombstone
//!   mask) marks `pts[i]` as deleted, and bits at or above `size` are clear.
//!   Leaves never carry a pending label: labels reaching a leaf are applied to its mask at once.

use super::aabb::{Aabb, Point3};

/// "No node": the child index of nothing, the root of an empty tree.
pub(crate) const NIL: u32 = u32::MAX;
/// Points per leaf bucket.
pub(crate) const LEAF_CAP: usize = 16;

/// The node is a leaf: `a` is its slot in [`Arena::leaves`].
pub(crate) const F_LEAF: u8 = 1;
/// Pending label: every point under this node is deleted (children not yet told).
pub(crate) const F_DEL_ALL: u8 = 2;
/// Pending label: every point under this node is valid again (children not yet told).
pub(crate) const F_RESTORE_ALL: u8 = 4;
/// The root of the subtree a background rebuild is re-making (writes below it are logged).
pub(crate) const F_BG_ROOT: u8 = 8;
/// An ancestor of the background rebuild's root (never rebuilt nor labelled as a whole meanwhile).
pub(crate) const F_BG_ANC: u8 = 16;

/// One node of the tree. 48 bytes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Node {
    /// Bounds of all points stored below (tombstones included), metres.
    pub bbox: Aabb,
    /// Stored points below, tombstones included.
    pub size: u32,
    /// Tombstones below.
    pub invalid: u32,
    /// Internal: left child. Leaf: leaf slot.
    pub a: u32,
    /// Internal: right child. Leaf: tombstone mask (bit `i` set = `pts[i]` deleted).
    pub b: u32,
    /// Split value on `axis`, metres (internal nodes only).
    pub split: f32,
    /// Split axis, 0..3.
    pub axis: u8,
    /// `F_*` flags.
    pub flags: u8,
}

impl Node {
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.flags & F_LEAF != 0
    }

    #[inline(always)]
    pub fn live(&self) -> u32 {
        self.size - self.invalid
    }

    pub fn leaf(slot: u32, size: u32, bbox: Aabb) -> Node {
        Node {
            bbox,
            size,
            invalid: 0,
            a: slot,
            b: 0,
            split: 0.0,
            axis: 0,
            flags: F_LEAF,
        }
    }
}

/// A bucket of up to [`LEAF_CAP`] points: 192 bytes, aligned to a cache line so that a leaf spans exactly
/// three lines. Its tombstone mask lives in its node (`Node::b`), which a search reads anyway.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub(crate) struct Leaf {
    pub pts: [Point3; LEAF_CAP],
}

impl Leaf {
    pub const EMPTY: Leaf = Leaf {
        pts: [Point3::new(0.0, 0.0, 0.0); LEAF_CAP],
    };
}

/// Mask with the low `n` bits set.
#[inline(always)]
pub(crate) fn low_bits(n: u32) -> u32 {
    if n >= 32 { u32::MAX } else { (1u32 << n) - 1 }
}

/// Nodes and leaves of one tree (or of one subtree being built off-thread), addressed by `u32` index, with
/// free lists for slots released by rebuilds.
#[derive(Debug, Clone, Default)]
pub(crate) struct Arena {
    pub nodes: Vec<Node>,
    pub leaves: Vec<Leaf>,
    pub free_nodes: Vec<u32>,
    pub free_leaves: Vec<u32>,
}

impl Arena {
    pub fn with_capacity(nodes: usize, leaves: usize) -> Self {
        Arena {
            nodes: Vec::with_capacity(nodes),
            leaves: Vec::with_capacity(leaves),
            free_nodes: Vec::new(),
            free_leaves: Vec::new(),
        }
    }

    #[inline]
    pub fn alloc_node(&mut self, n: Node) -> u32 {
        if let Some(id) = self.free_nodes.pop() {
            self.nodes[id as usize] = n;
            id
        } else {
            self.nodes.push(n);
            (self.nodes.len() - 1) as u32
        }
    }

    #[inline]
    pub fn alloc_leaf(&mut self, l: Leaf) -> u32 {
        if let Some(id) = self.free_leaves.pop() {
            self.leaves[id as usize] = l;
            id
        } else {
            self.leaves.push(l);
            (self.leaves.len() - 1) as u32
        }
    }

    /// Nodes in use.
    pub fn used_nodes(&self) -> usize {
        self.nodes.len() - self.free_nodes.len()
    }

    /// Leaves in use.
    pub fn used_leaves(&self) -> usize {
        self.leaves.len() - self.free_leaves.len()
    }

    /// Heap bytes held (capacities, not lengths).
    pub fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<Node>()
            + self.leaves.capacity() * size_of::<Leaf>()
            + (self.free_nodes.capacity() + self.free_leaves.capacity()) * size_of::<u32>()
    }

    /// Releases every node and leaf strictly below `id` (and `id`'s own leaf slot if it is a leaf); `id`
    /// itself stays allocated so that its parent's link remains valid. O(nodes below).
    pub fn free_below(&mut self, id: u32) {
        let n = self.nodes[id as usize];
        if n.is_leaf() {
            self.free_leaves.push(n.a);
            return;
        }
        let mut stack = vec![n.a, n.b];
        while let Some(c) = stack.pop() {
            let cn = self.nodes[c as usize];
            if cn.is_leaf() {
                self.free_leaves.push(cn.a);
            } else {
                stack.push(cn.a);
                stack.push(cn.b);
            }
            self.free_nodes.push(c);
        }
    }

    /// Sets every point under `id` to deleted (`del`) or valid, lazily: O(1).
    #[inline]
    pub fn label_all(&mut self, id: u32, del: bool) {
        let n = &mut self.nodes[id as usize];
        if n.is_leaf() {
            n.invalid = if del { n.size } else { 0 };
            n.b = if del { low_bits(n.size) } else { 0 };
        } else {
            n.flags &= !(F_DEL_ALL | F_RESTORE_ALL);
            n.flags |= if del { F_DEL_ALL } else { F_RESTORE_ALL };
            n.invalid = if del { n.size } else { 0 };
        }
    }

    /// Hands a pending label of internal node `id` on to its children. O(1).
    #[inline]
    pub fn push_down(&mut self, id: u32) {
        let n = self.nodes[id as usize];
        if n.is_leaf() || n.flags & (F_DEL_ALL | F_RESTORE_ALL) == 0 {
            return;
        }
        let del = n.flags & F_DEL_ALL != 0;
        self.label_all(n.a, del);
        self.label_all(n.b, del);
        self.nodes[id as usize].flags &= !(F_DEL_ALL | F_RESTORE_ALL);
    }

    /// Recomputes an internal node's counts and box from its children (which must be up to date).
    #[inline]
    pub fn pull_up(&mut self, id: u32) {
        let n = self.nodes[id as usize];
        if n.is_leaf() {
            return;
        }
        let (l, r) = (self.nodes[n.a as usize], self.nodes[n.b as usize]);
        let n = &mut self.nodes[id as usize];
        n.size = l.size + r.size;
        n.invalid = l.invalid + r.invalid;
        n.bbox = l.bbox.union(&r.bbox);
    }

    /// Appends the valid points under `id` to `out`, honouring pending labels. O(nodes below).
    pub fn collect_live(&self, id: u32, forced_valid: bool, out: &mut Vec<Point3>) {
        let n = &self.nodes[id as usize];
        if !forced_valid && n.invalid == n.size {
            return;
        }
        if n.is_leaf() {
            let leaf = &self.leaves[n.a as usize];
            let dead = if forced_valid { 0 } else { n.b };
            for (i, p) in leaf.pts[..n.size as usize].iter().enumerate() {
                if dead & (1 << i) == 0 {
                    out.push(*p);
                }
            }
            return;
        }
        let forced = forced_valid || n.flags & F_RESTORE_ALL != 0;
        self.collect_live(n.a, forced, out);
        self.collect_live(n.b, forced, out);
    }

    /// Copies the subtree `src_id` of `src` into this arena and returns the new root's index. O(size).
    pub fn import(&mut self, src: &Arena, src_id: u32) -> u32 {
        let mut n = src.nodes[src_id as usize];
        if n.is_leaf() {
            n.a = self.alloc_leaf(src.leaves[n.a as usize]);
            return self.alloc_node(n);
        }
        let id = self.alloc_node(n);
        let a = self.import(src, n.a);
        let b = self.import(src, n.b);
        let m = &mut self.nodes[id as usize];
        m.a = a;
        m.b = b;
        id
    }

    /// Maximum number of nodes on a root-to-leaf path below `id` (1 for a leaf).
    pub fn depth(&self, id: u32) -> usize {
        let n = &self.nodes[id as usize];
        if n.is_leaf() {
            1
        } else {
            1 + self.depth(n.a).max(self.depth(n.b))
        }
    }
}
