//! The indexed 4-ary heap of the Dijkstra runs on the portal graph (step 4 of
//! [`geodesic_matrix`](super::geodesic_matrix)).

/// Position marker of a node not in the heap.
const ABSENT: u32 = u32::MAX;
/// Position marker of a settled node.
const SETTLED: u32 = u32::MAX - 1;

/// A 4-ary min-heap over node ids with decrease-key (each node is in the heap at most once), for Dijkstra
/// on the portal graph; reset in time proportional to the nodes touched.
#[derive(Debug)]
pub(super) struct IndexedHeap {
    heap: Vec<u32>,
    pos: Vec<u32>,
    dist: Vec<f64>,
    touched: Vec<u32>,
}

impl IndexedHeap {
    pub(super) fn new(n: usize) -> Self {
        Self {
            heap: Vec::new(),
            pos: vec![ABSENT; n],
            dist: vec![f64::INFINITY; n],
            touched: Vec::new(),
        }
    }

    pub(super) fn reset(&mut self) {
        for &t in &self.touched {
            self.pos[t as usize] = ABSENT;
            self.dist[t as usize] = f64::INFINITY;
        }
        self.touched.clear();
        self.heap.clear();
    }

    /// Nodes given a distance since the last reset.
    pub(super) fn touched(&self) -> &[u32] {
        &self.touched
    }

    pub(super) fn dist(&self, v: u32) -> f64 {
        self.dist[v as usize]
    }

    /// Offers distance `d` to node `v` (ignored when `v` is settled or already has a shorter one).
    #[inline]
    pub(super) fn relax(&mut self, v: u32, d: f64) {
        let vi = v as usize;
        if d >= self.dist[vi] {
            return;
        }
        match self.pos[vi] {
            SETTLED => return,
            ABSENT => {
                self.touched.push(v);
                self.heap.push(v);
                self.pos[vi] = (self.heap.len() - 1) as u32;
            }
            _ => {}
        }
        self.dist[vi] = d;
        self.sift_up(self.pos[vi] as usize);
    }

    /// Removes and settles the node with the smallest distance.
    pub(super) fn pop(&mut self) -> Option<(u32, f64)> {
        let top = *self.heap.first()?;
        let last = self.heap.pop()?;
        self.pos[top as usize] = SETTLED;
        if !self.heap.is_empty() {
            self.heap[0] = last;
            self.pos[last as usize] = 0;
            self.sift_down(0);
        }
        Some((top, self.dist[top as usize]))
    }

    fn sift_up(&mut self, mut i: usize) {
        let v = self.heap[i];
        let d = self.dist[v as usize];
        while i > 0 {
            let parent = (i - 1) / 4;
            let p = self.heap[parent];
            if self.dist[p as usize] <= d {
                break;
            }
            self.heap[i] = p;
            self.pos[p as usize] = i as u32;
            i = parent;
        }
        self.heap[i] = v;
        self.pos[v as usize] = i as u32;
    }

    fn sift_down(&mut self, mut i: usize) {
        let v = self.heap[i];
        let d = self.dist[v as usize];
        let len = self.heap.len();
        loop {
            let first = 4 * i + 1;
            if first >= len {
                break;
            }
            let mut best = first;
            let mut best_d = self.dist[self.heap[first] as usize];
            for c in first + 1..(first + 4).min(len) {
                let dc = self.dist[self.heap[c] as usize];
                if dc < best_d {
                    best = c;
                    best_d = dc;
                }
            }
            if best_d >= d {
                break;
            }
            let b = self.heap[best];
            self.heap[i] = b;
            self.pos[b as usize] = i as u32;
            i = best;
        }
        self.heap[i] = v;
        self.pos[v as usize] = i as u32;
    }
}
