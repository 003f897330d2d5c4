//! Insertion: a whole batch walks down the tree at once (partitioned in place at every node), and the
//! voxel down-sampling rule decides beforehand which points of the batch enter.

use super::aabb::Point3;
use super::node::{F_BG_ROOT, LEAF_CAP, NIL};
use super::rebuild::LogOp;
use super::region::Region;
use super::search::VoxQuery;
use super::{IkdTree, VoxelKey, VoxelShape, voxel_centre_dist2, voxel_key};

/// Offset that makes a voxel coordinate non-negative when packing three into a `u64` (21 bits each).
const PACK_BIAS: i64 = 1 << 20;

/// The voxel key packed into 63 bits, when every coordinate fits in 21 bits (voxel side × ±2^20: ±200 km
/// at 0.2 m).
#[inline]
fn pack(k: &VoxelKey) -> Option<u64> {
    let mut out = 0u64;
    for &c in k {
        let b = c.checked_add(PACK_BIAS)?;
        if !(0..2 * PACK_BIAS).contains(&b) {
            return None;
        }
        out = (out << 21) | b as u64;
    }
    Some(out)
}

/// One candidate per voxel touched by `pts`: (voxel, squared distance to its centre, index in `pts`) of
/// the point nearest the centre, the first among equals. O(m) with a hash table (O(m log m) by sorting
/// for keys too large to pack).
fn group_by_voxel(pts: &[Point3], vs: f32) -> Vec<(VoxelKey, f32, u32)> {
    let items: Vec<(VoxelKey, f32, u32)> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let k = voxel_key(p, vs);
            (k, voxel_centre_dist2(p, &k, vs), i as u32)
        })
        .collect();
    let packed: Option<Vec<u64>> = items.iter().map(|it| pack(&it.0)).collect();
    let mut out = Vec::with_capacity(items.len());
    if let Some(packed) = packed {
        // Open addressing, linear probing; slot value = item index + 1 (0 = empty).
        let bits = (2 * items.len()).max(16).next_power_of_two().trailing_zeros();
        let mask = (1usize << bits) - 1;
        let mut table = vec![(0u64, 0u32); 1 << bits];
        for (i, &key) in packed.iter().enumerate() {
            let mut h = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - bits)) as usize;
            loop {
                let slot = &mut table[h];
                if slot.1 == 0 {
                    *slot = (key, i as u32 + 1);
                    break;
                }
                if slot.0 == key {
                    let cur = slot.1 as usize - 1;
                    if items[i].1 < items[cur].1 {
                        slot.1 = i as u32 + 1;
                    }
                    break;
                }
                h = (h + 1) & mask;
            }
        }
        out.extend(table.iter().filter(|s| s.1 != 0).map(|s| items[s.1 as usize - 1]));
    } else {
        let mut items = items;
        items.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut i = 0;
        while i < items.len() {
            out.push(items[i]);
            let key = items[i].0;
            while i < items.len() && items[i].0 == key {
                i += 1;
            }
        }
    }
    out
}

/// Moves the points that go left to the front of `pts` and returns how many there are. A point goes left
/// when it is below `split` on `axis`, or equal to it and `ties_left`.
fn partition(pts: &mut [Point3], axis: usize, split: f32, ties_left: bool) -> usize {
    let (mut i, mut j) = (0, pts.len());
    while i < j {
        let c = pts[i].get(axis);
        if c < split || (ties_left && c == split) {
            i += 1;
        } else {
            j -= 1;
            pts.swap(i, j);
        }
    }
    i
}

impl IkdTree {
    /// Adds the finite points of `points` (others are skipped) and returns how many of them are valid in
    /// the tree when the call returns.
    ///
    /// Without `downsample` every finite point is stored, duplicates included. With `downsample`, the
    /// voxel rule of the [module documentation](crate::map::ikd_tree) applies: a point enters only when it is strictly
    /// nearer its voxel's centre than every valid point already in that voxel, and replaces them; of several
    /// points of the call in one voxel, the nearest to the centre (the first among equals) is the candidate.
    ///
    /// Amortised O(m log n) for m points, in one walk down the tree; down-sampling adds O(m) hashing and
    /// two more walks (voxel look-ups, deletes). May rebuild the subtrees that the new points unbalance or
    /// dirty, or start a background rebuild.
    pub fn add_points(&mut self, points: &[Point3], downsample: bool) -> usize {
        self.poll_background(false);
        let pts: Vec<Point3> = points.iter().filter(|p| p.is_finite()).copied().collect();
        let mut pts = if downsample { self.downsample_select(&pts) } else { pts };
        let n = pts.len();
        self.insert_points(&mut pts);
        self.finish_write();
        n
    }

    /// Applies the voxel rule to `pts` against the current tree: deletes the valid points of every voxel
    /// that a new point wins and returns the winners (at most one per voxel). Three walks: group the batch
    /// by voxel, find every candidate voxel's best valid point in one pass down the tree, then delete the
    /// won voxels in one more pass.
    fn downsample_select(&mut self, pts: &[Point3]) -> Vec<Point3> {
        let vs = self.params.voxel_size;
        let cands = group_by_voxel(pts, vs);
        let mut qs: Vec<VoxQuery> = cands
            .iter()
            .map(|&(key, _, _)| VoxQuery {
                shape: VoxelShape::new(key, vs),
                best: f32::INFINITY,
            })
            .collect();
        self.voxel_best_multi(&mut qs);
        let mut winners = Vec::with_capacity(cands.len());
        let mut regions = Vec::new();
        for (&(_, d2, idx), q) in cands.iter().zip(&qs) {
            if d2 < q.best {
                if q.best.is_finite() {
                    regions.push(Region::Voxel { shape: q.shape, vs });
                }
                winners.push(pts[idx as usize]);
            }
        }
        self.delete_regions(&regions);
        winners
    }

    /// Inserts every point of `pts` (finite, no down-sampling), then rebuilds what the criteria ask for.
    pub(crate) fn insert_points(&mut self, pts: &mut [Point3]) {
        if pts.is_empty() {
            return;
        }
        if self.root == NIL {
            self.root = self.arena.build(pts);
            return;
        }
        let mut path = Vec::with_capacity(64);
        if self.insert_rec(self.root, pts, &mut path, false) {
            self.rebuild(self.root, &[]);
        }
    }

    fn insert_rec(&mut self, id: u32, pts: &mut [Point3], path: &mut Vec<u32>, inside_bg: bool) -> bool {
        if pts.is_empty() {
            return false;
        }
        let n = self.arena.nodes[id as usize];
        let inside = inside_bg || n.flags & F_BG_ROOT != 0;
        if n.flags & F_BG_ROOT != 0 {
            self.log(LogOp::Insert(pts.to_vec()));
        }
        if n.is_leaf() {
            let size = n.size as usize;
            if size + pts.len() <= LEAF_CAP {
                let node = &mut self.arena.nodes[id as usize];
                let leaf = &mut self.arena.leaves[n.a as usize];
                for (slot, p) in leaf.pts[size..size + pts.len()].iter_mut().zip(pts.iter()) {
                    *slot = *p;
                    node.bbox.expand(p);
                }
                node.size += pts.len() as u32;
                return !inside && self.violates(id);
            }
            // The bucket overflows: it becomes a balanced subtree of its valid points and the new ones.
            self.rebuild_with(id, pts);
            return false;
        }
        self.arena.push_down(id);
        let (a, b) = (n.a, n.b);
        let ties_left = self.arena.nodes[a as usize].size <= self.arena.nodes[b as usize].size;
        let mid = partition(pts, n.axis as usize, n.split, ties_left);
        let (lo, hi) = pts.split_at_mut(mid);
        path.push(id);
        let va = self.insert_rec(a, lo, path, inside);
        let vb = self.insert_rec(b, hi, path, inside);
        path.pop();
        self.arena.pull_up(id);
        self.resolve(id, va, vb, path, inside)
    }
}
