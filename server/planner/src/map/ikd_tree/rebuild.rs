//! Partial rebuilds: the scapegoat criteria, in-place rebuilds, the background rebuild with its operation
//! log and replay, and arena compaction.

use std::thread::JoinHandle;

use super::aabb::{Aabb, Point3};
use super::node::{Arena, F_BG_ANC, F_BG_ROOT, LEAF_CAP, NIL};
use super::region::Region;
use super::{IkdParams, IkdTree};

/// Subtrees with fewer points than this are not checked for balance (a handful of leaves).
const BALANCE_MIN: u32 = 4 * super::node::LEAF_CAP as u32;

/// Name of the background rebuild thread.
pub(crate) const REBUILD_THREAD: &str = "ikd-rebuild";

/// A write that reached the subtree of a background rebuild, to replay onto its new copy.
#[derive(Debug, Clone)]
pub(crate) enum LogOp {
    /// Points routed into the subtree.
    Insert(Vec<Point3>),
    /// A delete that reached the subtree.
    Delete(Region),
}

/// The background rebuild in flight.
#[derive(Debug)]
pub(crate) struct BgJob {
    /// Node being rebuilt (its slot is kept; the new subtree is swapped into it).
    root: u32,
    /// Its ancestors, root first.
    ancestors: Vec<u32>,
    /// Writes that reached `root` since the thread took its copy.
    log: Vec<LogOp>,
    /// The thread, returning the new subtree in its own arena and its root.
    handle: JoinHandle<(Arena, u32)>,
}

impl BgJob {
    /// Heap bytes of the log.
    pub fn log_bytes(&self) -> usize {
        self.log.capacity() * size_of::<LogOp>()
            + self
                .log
                .iter()
                .map(|op| match op {
                    LogOp::Insert(v) => v.capacity() * size_of::<Point3>(),
                    LogOp::Delete(_) => 0,
                })
                .sum::<usize>()
    }
}

impl IkdTree {
    /// True when node `id` breaks a criterion and may be rebuilt (never the background subtree's root or
    /// its ancestors while it is in flight).
    pub(crate) fn violates(&self, id: u32) -> bool {
        let n = &self.arena.nodes[id as usize];
        if n.size == 0 || n.flags & (F_BG_ROOT | F_BG_ANC) != 0 {
            return false;
        }
        let size = n.size as f32;
        if n.invalid > 0 && n.invalid as f32 > self.params.alpha_del * size {
            return true;
        }
        if n.is_leaf() || n.size < BALANCE_MIN {
            return false;
        }
        // One point of slack: a fresh build splits an odd count one-off, which must pass even at 0.5.
        let big = self.arena.nodes[n.a as usize]
            .size
            .max(self.arena.nodes[n.b as usize].size);
        big as f32 > self.params.alpha_bal * size + 1.0
    }

    /// Called on internal node `id` after a write below it, with whether each child violates a criterion.
    /// Returns true when `id` itself violates (its parent decides); otherwise rebuilds the violating
    /// children. `path` holds `id`'s ancestors. Inside a background subtree nothing is rebuilt.
    pub(crate) fn resolve(&mut self, id: u32, va: bool, vb: bool, path: &mut Vec<u32>, inside_bg: bool) -> bool {
        if inside_bg {
            return false;
        }
        if self.violates(id) {
            return true;
        }
        if va || vb {
            let n = self.arena.nodes[id as usize];
            path.push(id);
            if va {
                self.rebuild(n.a, path);
            }
            if vb {
                self.rebuild(n.b, path);
            }
            path.pop();
            self.arena.pull_up(id);
        }
        false
    }

    /// Rebuilds subtree `id` (whose ancestors, root first, are `ancestors` and carry no pending label):
    /// on the background thread when it holds at least `background_rebuild_min` valid points and no other
    /// background rebuild is in flight, in place otherwise.
    pub(crate) fn rebuild(&mut self, id: u32, ancestors: &[u32]) {
        let live = self.arena.nodes[id as usize].live() as usize;
        if live >= self.params.background_rebuild_min && self.bg.is_none() && !self.arena.nodes[id as usize].is_leaf() {
            self.launch_background(id, ancestors, live);
        } else {
            self.rebuild_with(id, &[]);
            self.stats.rebuilds_in_place += 1;
        }
    }

    /// Rebuilds subtree `id` in place from its valid points plus `extra`, dropping its tombstones. The
    /// node keeps its slot. O(s log s) for s points.
    pub(crate) fn rebuild_with(&mut self, id: u32, extra: &[Point3]) {
        let n = self.arena.nodes[id as usize];
        if n.is_leaf() && n.live() as usize + extra.len() <= LEAF_CAP {
            // Still one bucket: compact it where it is (no allocation).
            let leaf = &mut self.arena.leaves[n.a as usize];
            let mut bbox = Aabb::empty();
            let mut w = 0;
            for i in 0..n.size as usize {
                if n.b & (1 << i) == 0 {
                    leaf.pts[w] = leaf.pts[i];
                    bbox.expand(&leaf.pts[w]);
                    w += 1;
                }
            }
            for p in extra {
                leaf.pts[w] = *p;
                bbox.expand(p);
                w += 1;
            }
            let node = &mut self.arena.nodes[id as usize];
            node.size = w as u32;
            node.invalid = 0;
            node.b = 0;
            node.bbox = bbox;
            return;
        }
        let mut pts = Vec::with_capacity(n.live() as usize + extra.len());
        self.arena.collect_live(id, false, &mut pts);
        pts.extend_from_slice(extra);
        self.arena.free_below(id);
        let r = self.arena.build(&mut pts);
        self.arena.nodes[id as usize] = self.arena.nodes[r as usize];
        self.arena.free_nodes.push(r);
    }

    fn launch_background(&mut self, id: u32, ancestors: &[u32], live: usize) {
        let mut pts = Vec::with_capacity(live);
        self.arena.collect_live(id, false, &mut pts);
        let spawned = std::thread::Builder::new().name(REBUILD_THREAD.into()).spawn(move || {
            let mut arena = Arena::default();
            let root = arena.build(&mut pts);
            (arena, root)
        });
        match spawned {
            Ok(handle) => {
                self.arena.nodes[id as usize].flags |= F_BG_ROOT;
                for &a in ancestors {
                    self.arena.nodes[a as usize].flags |= F_BG_ANC;
                }
                self.bg = Some(BgJob {
                    root: id,
                    ancestors: ancestors.to_vec(),
                    log: Vec::new(),
                    handle,
                });
            }
            Err(_) => {
                // No thread to be had: do the work here.
                self.rebuild_with(id, &[]);
                self.stats.rebuilds_in_place += 1;
            }
        }
    }

    /// Appends a write to the background rebuild's log.
    pub(crate) fn log(&mut self, op: LogOp) {
        if let Some(bg) = &mut self.bg {
            bg.log.push(op);
        }
    }

    /// Swaps in a finished background rebuild (waiting for it when `block`): replays the log onto the new
    /// subtree, moves it into the old root's slot, frees the old subtree, refreshes the ancestors and
    /// re-checks the criteria along them.
    pub(crate) fn poll_background(&mut self, block: bool) {
        let ready = match &self.bg {
            None => return,
            Some(bg) => block || bg.handle.is_finished(),
        };
        if !ready {
            return;
        }
        let Some(bg) = self.bg.take() else { return };
        self.arena.nodes[bg.root as usize].flags &= !F_BG_ROOT;
        for &a in &bg.ancestors {
            self.arena.nodes[a as usize].flags &= !F_BG_ANC;
        }
        match bg.handle.join() {
            Ok((arena, root)) => {
                let params = IkdParams {
                    background_rebuild_min: usize::MAX,
                    ..self.params
                };
                let mut sub = IkdTree {
                    params,
                    arena,
                    root,
                    bg: None,
                    stats: Default::default(),
                };
                let n_ops = bg.log.len() as u64;
                let mut deletes = Vec::new();
                for op in bg.log {
                    match op {
                        LogOp::Insert(mut v) => {
                            sub.delete_regions(&deletes);
                            deletes.clear();
                            sub.insert_points(&mut v);
                        }
                        LogOp::Delete(region) => deletes.push(region),
                    }
                }
                sub.delete_regions(&deletes);
                self.arena.free_below(bg.root);
                let new = self.arena.import(&sub.arena, sub.root);
                self.arena.nodes[bg.root as usize] = self.arena.nodes[new as usize];
                self.arena.free_nodes.push(new);
                self.stats.rebuilds_background += 1;
                self.stats.replayed_ops += n_ops;
            }
            Err(_) => {
                // The thread panicked: the old subtree is intact and current, so rebuild it here.
                self.rebuild_with(bg.root, &[]);
                self.stats.rebuilds_in_place += 1;
            }
        }
        for &a in bg.ancestors.iter().rev() {
            self.arena.pull_up(a);
        }
        let mut chain = bg.ancestors;
        chain.push(bg.root);
        if let Some(i) = chain.iter().position(|&id| self.violates(id)) {
            self.rebuild(chain[i], &chain[..i]);
        }
    }

    /// End of every public write: swap in a finished background rebuild, and compact the arena once a third
    /// of it is free (free slots exceed half the used ones). Amortised O(1) per freed slot.
    pub(crate) fn finish_write(&mut self) {
        self.poll_background(false);
        if self.bg.is_some() || self.root == NIL {
            return;
        }
        let a = &self.arena;
        let nodes_wasted = a.free_nodes.len() > (a.used_nodes() / 2).max(1024);
        let leaves_wasted = a.free_leaves.len() > (a.used_leaves() / 2).max(256);
        if nodes_wasted || leaves_wasted {
            let mut fresh = Arena::with_capacity(a.used_nodes(), a.used_leaves());
            self.root = fresh.import(&self.arena, self.root);
            self.arena = fresh;
            self.stats.compactions += 1;
        }
    }
}
