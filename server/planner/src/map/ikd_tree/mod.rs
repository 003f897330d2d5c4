//! The live map: an incremental k-d tree of 3-D points with the semantics of ikd-Tree (Cai, Xu, Zhang 2021).
//!
//! What it gives the planner, and what each operation costs (n = points stored, tombstones included;
//! m = points in the call; k = neighbours asked for; r = points reported):
//!
//! | operation | cost |
//! | --- | --- |
//! | [`IkdTree::build`] | O(n log n), perfectly balanced |
//! | [`IkdTree::add_points`] | amortised O(m log n); down-sampling adds O(m) hashing and two more walks |
//! | [`IkdTree::delete_box`], [`IkdTree::restore_box`] | O(log n + boundary nodes); a subtree wholly inside the box is labelled in O(1) |
//! | [`IkdTree::delete_points`] | O(m log n) expected |
//! | [`IkdTree::nearest`], [`IkdTree::nearest_within`], [`IkdTree::nearest_distance`] | O(log n + k log k) expected |
//! | [`IkdTree::within_radius`], [`IkdTree::within_box`] | O(log n + r) expected |
//!
//! # Design
//!
//! - **Layout.** An index arena (`Vec` of 48-byte nodes with `u32` child indices) over leaf buckets of up
//!   to 16 points (192 bytes, aligned to cache lines), no pointers and no `unsafe`. Every node keeps the
//!   bounding box of the points below it, the number stored and the number deleted; a leaf's node also
//!   holds its tombstone mask. About 19 bytes per point after a build, at most about 2.5 times that after
//!   heavy churn (free slots are compacted away, see Memory).
//! - **Lazy labels.** Deletion only marks points (a tombstone bit per point in a leaf). A box that swallows
//!   a whole subtree labels its root "all deleted" in O(1); the label is pushed down to the children the
//!   next time a write walks through that node, never by a read (reads honour pending labels on the way
//!   down). [`IkdTree::restore_box`] clears tombstones the same way.
//! - **Down-sampling on the tree.** With `downsample`, each voxel of side `voxel_size` (cells
//!   `floor(x / voxel_size)`, per axis) keeps at most one new point: the one nearest the voxel centre. A
//!   new point enters only if it is strictly nearer the centre than every valid point already in its voxel,
//!   and then replaces them all (they become tombstones). Within one call the points are taken in order, so
//!   among equally near new points the first wins.
//! - **Partial rebuild.** After every write the nodes on its path are checked against the two scapegoat
//!   criteria of ikd-Tree: a subtree is *unbalanced* when one child holds more than `alpha_bal` of its
//!   points, and *dirty* when more than `alpha_del` of its points are tombstones. Criteria are evaluated
//!   bottom-up as in ikd-Tree; because rebuilding a subtree also rebuilds every violating subtree inside it,
//!   only the topmost violating node of the path is rebuilt, which is the smallest subtree whose rebuild
//!   restores both criteria on the whole path. Rebuilding flattens the valid points (dropping tombstones)
//!   and rebuilds a balanced subtree in place. Subtrees below 64 points are not checked for balance.
//! - **Background rebuild.** A rebuild that must re-sort at least `background_rebuild_min` valid points
//!   runs on a named thread (`ikd-rebuild`) while the old subtree stays in place and keeps answering
//!   queries. Writes that reach that subtree meanwhile are applied to it and appended to an operation
//!   log; when the thread is done, the next write (or [`IkdTree::wait_rebuild`]) replays the log onto the
//!   new subtree and swaps it in. Only one background rebuild runs at a time; others run in place. The
//!   writer still pays two O(size) copies (the points handed to the thread, the finished subtree moved
//!   into the arena); the thread takes the O(size log size) sorting off it.
//! - **Batches.** A call walks the tree once for all its points, not once per point: the batch is
//!   partitioned in place at every node (inserts), or the boxes that can reach a node are carried down on
//!   a stack (deletes, voxel look-ups). Down-sampling groups the batch by voxel with a hash table, looks up
//!   every candidate voxel in one walk, deletes the voxels it wins in a second and inserts in a third.
//! - **Memory.** Slots released by rebuilds go to free lists; once a third of the arena is free, the tree
//!   is compacted (O(n), amortised over the frees), so deleting most of the map gives its memory back.
//!
//! # Thread model
//!
//! One writer, many readers: every write takes `&mut self` and every query `&self`, and [`IkdTree`] is
//! `Send + Sync`, so a site keeps it in a `std::sync::RwLock` (queries under the read lock, in parallel;
//! map updates under the write lock). The background rebuild thread never touches the tree: it owns a copy
//! of the points it re-sorts and hands back a finished subtree, which the writer swaps in under its
//! `&mut self`, so readers never see a half-built subtree.
//!
//! # Determinism
//!
//! The set of valid points after any sequence of writes, and hence every query's distances, does not
//! depend on when background rebuilds finish. Which of several equidistant points a k-nearest query
//! returns, and which tombstones [`IkdTree::restore_box`] can still bring back, may.

mod aabb;
mod build;
mod delete;
mod insert;
mod node;
mod rebuild;
mod region;
mod search;
#[cfg(test)]
mod tests;

pub use aabb::{Aabb, Point3};

use node::{Arena, NIL};
use rebuild::BgJob;
use thiserror::Error;

/// Why an [`IkdTree`] could not be made.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum IkdError {
    /// A parameter is outside its valid range.
    #[error("invalid ikd-tree parameter {name} = {value}: {reason}")]
    InvalidParam {
        /// Field of [`IkdParams`].
        name: &'static str,
        /// The value given.
        value: f64,
        /// The valid range.
        reason: &'static str,
    },
}

/// Knobs of an [`IkdTree`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkdParams {
    /// Balance criterion: a subtree is rebuilt when one child holds more than this fraction of its points
    /// (tombstones included). In [0.5, 1]; 1 disables balance rebuilds. Default 0.6.
    pub alpha_bal: f32,
    /// Deletion criterion: a subtree is rebuilt when more than this fraction of its points are tombstones.
    /// In (0, 1]; 1 disables deletion rebuilds. Default 0.5.
    pub alpha_del: f32,
    /// Side of the down-sampling voxels, metres (> 0, finite). Default 0.2 m.
    pub voxel_size: f32,
    /// Rebuilds that re-sort at least this many valid points run on the background thread; use
    /// `usize::MAX` to rebuild everything in place (fully deterministic tree shape). Default 1500.
    pub background_rebuild_min: usize,
}

impl Default for IkdParams {
    fn default() -> Self {
        Self {
            alpha_bal: 0.6,
            alpha_del: 0.5,
            voxel_size: 0.2,
            background_rebuild_min: 1500,
        }
    }
}

impl IkdParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), IkdError> {
        let bad = |name, value: f32, reason| {
            Err(IkdError::InvalidParam {
                name,
                value: value as f64,
                reason,
            })
        };
        if !(0.5..=1.0).contains(&self.alpha_bal) {
            return bad("alpha_bal", self.alpha_bal, "must be in [0.5, 1]");
        }
        if !(self.alpha_del > 0.0 && self.alpha_del <= 1.0) {
            return bad("alpha_del", self.alpha_del, "must be in (0, 1]");
        }
        if !(self.voxel_size.is_finite() && self.voxel_size > 0.0) {
            return bad(
                "voxel_size",
                self.voxel_size,
                "must be a positive finite number of metres",
            );
        }
        Ok(())
    }
}

/// Counters of the work the tree did, for tests and metrics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IkdStats {
    /// Subtrees rebuilt in place by the writer.
    pub rebuilds_in_place: u64,
    /// Subtrees rebuilt on the background thread and swapped in.
    pub rebuilds_background: u64,
    /// Operations replayed onto background-built subtrees.
    pub replayed_ops: u64,
    /// Arena compactions.
    pub compactions: u64,
}

/// An incremental k-d tree of 3-D points (metres, in the frame of the points given, the map frame for a
/// site's live map). See the [module documentation](self) for the design, costs and thread model.
#[derive(Debug)]
pub struct IkdTree {
    params: IkdParams,
    arena: Arena,
    /// Root node, `NIL` when nothing was ever stored.
    root: u32,
    /// The background rebuild in flight, if any.
    bg: Option<BgJob>,
    stats: IkdStats,
}

impl Default for IkdTree {
    fn default() -> Self {
        Self {
            params: IkdParams::default(),
            arena: Arena::default(),
            root: NIL,
            bg: None,
            stats: IkdStats::default(),
        }
    }
}

/// Integer voxel coordinates `floor(c / voxel_size)` per axis.
pub(crate) type VoxelKey = [i64; 3];

/// The voxel that holds `p`.
#[inline]
pub(crate) fn voxel_key(p: &Point3, vs: f32) -> VoxelKey {
    let vs = vs as f64;
    [
        floor_i64(p.x as f64 / vs),
        floor_i64(p.y as f64 / vs),
        floor_i64(p.z as f64 / vs),
    ]
}

/// `q.floor() as i64` without a libm call (baseline x86-64 has no rounding instruction); saturating.
#[inline(always)]
fn floor_i64(q: f64) -> i64 {
    let t = q as i64;
    if (t as f64) > q { t.saturating_sub(1) } else { t }
}

/// Centre of voxel `key`, metres.
#[inline]
pub(crate) fn voxel_centre(key: &VoxelKey, vs: f32) -> Point3 {
    let vs = vs as f64;
    let c = |k: i64| ((k as f64 + 0.5) * vs) as f32;
    Point3::new(c(key[0]), c(key[1]), c(key[2]))
}

/// Squared distance from `p` to the centre of voxel `key`, square metres.
#[inline]
pub(crate) fn voxel_centre_dist2(p: &Point3, key: &VoxelKey, vs: f32) -> f32 {
    p.dist2(&voxel_centre(key, vs))
}

/// The voxel's box grown (`grow = 1`) or shrunk (`grow = -1`) by a margin that covers `f32` rounding:
/// the grown box holds every `f32` point whose key is `key`; every `f32` point inside the shrunk box has
/// key `key`.
fn voxel_box(key: &VoxelKey, vs: f32, grow: f64) -> Aabb {
    let vs = vs as f64;
    let lo = |k: i64| {
        let v = k as f64 * vs;
        (v - grow * (vs * 1e-3 + v.abs() * 1e-6)) as f32
    };
    let hi = |k: i64| {
        let v = (k as f64 + 1.0) * vs;
        (v + grow * (vs * 1e-3 + v.abs() * 1e-6)) as f32
    };
    Aabb::new(
        Point3::new(lo(key[0]), lo(key[1]), lo(key[2])),
        Point3::new(hi(key[0]), hi(key[1]), hi(key[2])),
    )
}

/// The three boxes and centre down-sampling needs to test membership of voxel `key` cheaply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct VoxelShape {
    /// The voxel.
    pub key: VoxelKey,
    /// Holds every point of the voxel (search bound).
    pub outer: Aabb,
    /// Every point inside is in the voxel (no division needed).
    pub inner: Aabb,
    /// The voxel's centre, metres.
    pub centre: Point3,
}

impl VoxelShape {
    pub(crate) fn new(key: VoxelKey, vs: f32) -> Self {
        Self {
            key,
            outer: voxel_box(&key, vs, 1.0),
            inner: voxel_box(&key, vs, -1.0),
            centre: voxel_centre(&key, vs),
        }
    }

    /// True when `p` lies in the voxel (exactly as `voxel_key(p) == key`).
    #[inline(always)]
    pub(crate) fn holds(&self, p: &Point3, vs: f32) -> bool {
        // Most points tested are outside the voxel: the outer box turns them away first.
        self.outer.contains(p) && (self.inner.contains(p) || voxel_key(p, vs) == self.key)
    }
}

impl IkdTree {
    /// An empty tree with `params` (checked: see [`IkdParams`]).
    pub fn new(params: IkdParams) -> Result<Self, IkdError> {
        params.validate()?;
        Ok(Self {
            params,
            ..Self::default()
        })
    }

    /// The parameters the tree was made with.
    pub fn params(&self) -> &IkdParams {
        &self.params
    }

    /// Replaces the whole content with a balanced tree of the finite points of `points` (non-finite points
    /// are skipped; no down-sampling). Any background rebuild in flight is abandoned. Returns the number of
    /// points stored.
    ///
    /// O(n log n).
    pub fn build(&mut self, points: &[Point3]) -> usize {
        self.bg = None;
        let mut pts: Vec<Point3> = points.iter().filter(|p| p.is_finite()).copied().collect();
        self.arena = Arena::default();
        self.root = if pts.is_empty() {
            NIL
        } else {
            self.arena.build(&mut pts)
        };
        pts.len()
    }

    /// Number of valid (not deleted) points. O(1).
    pub fn len(&self) -> usize {
        self.root_node().map_or(0, |n| n.live() as usize)
    }

    /// True when the tree holds no valid point. O(1).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of points stored, tombstones (deleted but not yet reclaimed) included. O(1).
    pub fn tree_size(&self) -> usize {
        self.root_node().map_or(0, |n| n.size as usize)
    }

    /// Nodes on the longest root-to-leaf path (0 for an empty tree; a leaf bucket counts as one node).
    /// O(nodes).
    pub fn depth(&self) -> usize {
        if self.root == NIL {
            0
        } else {
            self.arena.depth(self.root)
        }
    }

    /// Heap bytes held by the tree's arena (capacities, so what the allocator actually holds), plus the
    /// operation log of a background rebuild in flight. The thread's own copy is not counted. O(1).
    pub fn memory_bytes(&self) -> usize {
        size_of::<Self>() + self.arena.memory_bytes() + self.bg.as_ref().map_or(0, |b| b.log_bytes())
    }

    /// Work counters since the tree was made.
    pub fn stats(&self) -> IkdStats {
        self.stats
    }

    /// True while a background rebuild is in flight (started and not yet swapped in).
    pub fn rebuild_in_flight(&self) -> bool {
        self.bg.is_some()
    }

    /// Blocks until the background rebuild in flight, if any, has finished, then replays its log and swaps
    /// it in. Queries are exact with or without this; it only settles memory and shape (tests, shutdown).
    pub fn wait_rebuild(&mut self) {
        // Swapping one in may start another (an ancestor found dirty or unbalanced): settle them all.
        while self.bg.is_some() {
            self.poll_background(true);
        }
        self.finish_write();
    }

    /// Every valid point, in tree order (unspecified but deterministic for a given tree shape). O(n).
    pub fn flatten(&self) -> Vec<Point3> {
        let mut out = Vec::with_capacity(self.len());
        if self.root != NIL {
            self.arena.collect_live(self.root, false, &mut out);
        }
        out
    }

    fn root_node(&self) -> Option<&node::Node> {
        if self.root == NIL {
            None
        } else {
            Some(&self.arena.nodes[self.root as usize])
        }
    }
}
