//! Geodesic (shortest collision-free) travel lengths between many points at once.
//!
//! The grid distance between two points is the length of the shortest walk over the link moves (octile
//! steps between reachable cells, see `link`) between their cells, plus the straight connections from each
//! point to its cell's centre; two points in the same cell are their straight-line distance apart. No
//! potential term: this is travel length, metres. [`geodesic_distance`] computes it exactly for one pair.
//!
//! [`geodesic_matrix`] avoids one grid search per pair:
//! 1. one multi-source Dijkstra over the whole grid labels every cell with its nearest point (a discrete
//!    geodesic Voronoi diagram), the distance to it and the move it was reached by (a shortest-path tree per
//!    point). Every step is at least one resolution long, so a bucket queue with buckets one resolution wide
//!    is exact (a cell can only be improved from earlier buckets) at O(1) per cell;
//! 2. where two regions touch, the touching cell pair `(u, v)` with the smallest `d(u) + step + d(v)` is a
//!    *portal* between the two points (the saddle of their Voronoi boundary); the walk from one point to
//!    `u`, the step, and the walk from `v` to the other point is a real path between them;
//! 3. a sparse graph on the portals: two portals of the same region are joined by a short real walk between
//!    their cells — the straight octile (Bresenham) walk when all its moves are allowed (then no walk is
//!    shorter), otherwise the best of the walk along the region's shortest-path tree (through the cells'
//!    lowest common ancestor) and of straight walks to ancestors 1, 2, 4, … steps up the other cell's tree
//!    path;
//! 4. from every point, Dijkstra on the portal graph (seeded with its own portals at `d(u)`), and each other
//!    point's distance is the best of its portals plus its `d(v)`.
//!
//! Every edge is the length of a real walk, so the entries are **upper bounds** of the grid distance (never
//! below it, except that a point sharing its cell with another may gain the straight distance inside the
//! cell: at most one cell diagonal). They are exact for neighbouring points whose shortest path crosses
//! their common boundary, and near-exact otherwise: unlike a graph on the points themselves (where every
//! path must visit the intermediate points: ~14 % mean excess on cluttered maps), paths only pass the
//! saddles between regions. What remains comes from crossing each boundary at its saddle rather than where
//! the true path crosses it, and from the approximate walks inside regions: on seeded cluttered random maps
//! the mean excess is ~5 % and the 95th percentile ~14 % (see the tests). Cost: one grid sweep plus n
//! Dijkstra runs on a graph of ~3n portals and ~15n edges.

use super::astar::{DIRS, Frontier, Graph, ROOT, STEP_CELLS, Search};
use crate::geom::Point2;
use crate::space::CoverageSpace;

/// No label.
const NONE: u32 = u32::MAX;

/// Grid distance between `a` and `b` (map frame, metres): the shortest octile walk over the link moves
/// between their cells plus the straight connections to the cell centres (straight-line distance when they
/// share a cell). `None` when either point is not on a reachable cell or they are not connected. Exact
/// (A* with the octile heuristic); use [`geodesic_matrix`] for many pairs.
pub fn geodesic_distance(space: &CoverageSpace, a: Point2, b: Point2) -> Option<f64> {
    let g = space.geometry();
    let ca = g.index(g.locate(a)?);
    let cb = g.index(g.locate(b)?);
    if !space.reachable[ca] || !space.reachable[cb] {
        return None;
    }
    if ca == cb {
        return Some((b - a).norm());
    }
    let graph = Graph::new(space);
    let search = Search {
        graph: &graph,
        alpha: 0.0,
        epsilon_m: 1.0,
        heuristic_scale: 1.0,
        max_cost: f64::INFINITY,
    };
    let mut frontier = Frontier::default();
    let roots = [(ca, (g.center_of(ca) - a).norm())];
    let goals = [(cb, (g.center_of(cb) - b).norm())];
    super::astar::search(&search, &mut frontier, &roots, &goals).map(|f| f.cost)
}

/// The cell a point starts from: its own, or — for a point on a cell edge or corner, which the floor puts in
/// an unreachable cell beside it — the nearest reachable cell around it.
fn home_cell(space: &CoverageSpace, p: Point2) -> Option<usize> {
    let geometry = space.geometry();
    let c = geometry.locate(p)?;
    let i = geometry.index(c);
    if space.reachable[i] {
        return Some(i);
    }
    [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, 1), (1, -1), (-1, -1)]
        .into_iter()
        .filter_map(|(dx, dy)| geometry.offset(c, dx, dy))
        .map(|n| geometry.index(n))
        .filter(|&j| space.reachable[j] && space.segment_ok(p, geometry.center_of(j)))
        .min_by(|&a, &b| {
            (geometry.center_of(a) - p)
                .norm()
                .total_cmp(&(geometry.center_of(b) - p).norm())
        })
}

/// Grid distances from one point to every reachable cell: the sweep of [`geodesic_matrix`] with one
/// seed. For a few distances from one point on a large map (the dock's transits to a single region) it
/// costs one pass over the grid, which can run while other work is being done.
#[derive(Debug, Clone)]
pub struct DistancesFrom {
    from: Point2,
    dist: Vec<f64>,
}

impl DistancesFrom {
    /// The distances from `from` (a point on the reachable set; from nowhere, everything is unreachable).
    pub fn new(space: &CoverageSpace, from: Point2) -> Self {
        let graph = Graph::new(space);
        let g = space.geometry();
        let seeds: Vec<(usize, f64, u32)> = home_cell(space, from)
            .map(|i| (i, (g.center_of(i) - from).norm(), 0))
            .into_iter()
            .collect();
        Self {
            from,
            dist: sweep(&graph, &seeds).iter().map(|c| c.dist).collect(),
        }
    }

    /// The grid distance to `p` (as [`geodesic_distance`] measures it); `None` when `p` is not on a
    /// reachable cell connected to the start point.
    pub fn to(&self, space: &CoverageSpace, p: Point2) -> Option<f64> {
        let g = space.geometry();
        let i = home_cell(space, p)?;
        if g.locate(self.from).is_some_and(|c| g.index(c) == i) {
            return Some((p - self.from).norm());
        }
        let d = self.dist.get(i).copied()?;
        d.is_finite().then(|| d + (g.center_of(i) - p).norm())
    }
}

/// Sweep state of one cell (kept together: one cache line per touched cell).
#[derive(Debug, Clone, Copy)]
struct SweepCell {
    /// Distance to the nearest point, metres.
    dist: f64,
    /// That point's index (`NONE` when unreached).
    label: u32,
    /// Move that reached the cell (`ROOT` at a point's own cell).
    parent: u8,
    /// Settled.
    done: bool,
}

const UNREACHED: SweepCell = SweepCell {
    dist: f64::INFINITY,
    label: NONE,
    parent: ROOT,
    done: false,
};

/// The cheapest crossing between two touching regions.
#[derive(Debug, Clone, Copy)]
struct Portal {
    /// The two points, and the crossing's cell on each one's side.
    sites: [u32; 2],
    cells: [u32; 2],
    /// Length of the move between the two cells, metres.
    step_m: f64,
    /// Walk from each point to the middle of the crossing: its cell's distance plus half the step, metres.
    reach_m: [f64; 2],
}

/// Multi-source Dijkstra over the grid from the points' cells (bucket queue, exact; see the module docs).
fn sweep(graph: &Graph<'_>, seeds: &[(usize, f64, u32)]) -> Vec<SweepCell> {
    let res = graph.resolution;
    let inv_res = 1.0 / res;
    let mut cells = vec![UNREACHED; graph.len()];
    let mut buckets: [Vec<u32>; 4] = Default::default();
    let mut pending = 0usize;
    for &(i, d, label) in seeds {
        if d < cells[i].dist {
            cells[i] = SweepCell {
                dist: d,
                label,
                parent: ROOT,
                done: false,
            };
            // Offsets to the cell centre are below one resolution: bucket 0.
            buckets[0].push(i as u32);
            pending += 1;
        }
    }
    let mut current = 0usize;
    while pending > 0 {
        let slot = current & 3;
        let mut list = std::mem::take(&mut buckets[slot]);
        pending -= list.len();
        // Cells of one bucket are independent; in memory order they share cache lines and pages.
        list.sort_unstable();
        for &u in &list {
            let u = u as usize;
            let cu = cells[u];
            if cu.done {
                continue;
            }
            cells[u].done = true;
            graph.for_each_move(u, |v, d, _, _| {
                let cv = &mut cells[v];
                if cv.done {
                    return;
                }
                let dv = cu.dist + STEP_CELLS[d] * res;
                if dv < cv.dist {
                    *cv = SweepCell {
                        dist: dv,
                        label: cu.label,
                        parent: d as u8,
                        done: false,
                    };
                    // At least the next bucket (exact arithmetic guarantees it; this guards rounding); at
                    // most two ahead since steps are below 1.5 resolutions, so four slots never collide.
                    let b = ((dv * inv_res) as usize).max(current + 1);
                    buckets[b & 3].push(v as u32);
                    pending += 1;
                }
            });
        }
        list.clear();
        if buckets[slot].is_empty() {
            buckets[slot] = list;
        }
        current += 1;
    }
    cells
}

/// Length of the walk from cell `x` to cell `y` of one region along its shortest-path tree (through their
/// lowest common ancestor).
fn tree_walk(graph: &Graph<'_>, cells: &[SweepCell], x: usize, y: usize) -> f64 {
    let (mut a, mut b) = (x, y);
    while a != b {
        // Parents are strictly closer to the root, so moving the farther one up meets at the ancestor.
        if cells[a].dist >= cells[b].dist {
            if cells[a].parent == ROOT {
                return f64::INFINITY;
            }
            a = graph.back(a, cells[a].parent);
        } else {
            if cells[b].parent == ROOT {
                return f64::INFINITY;
            }
            b = graph.back(b, cells[b].parent);
        }
    }
    cells[x].dist + cells[y].dist - 2.0 * cells[a].dist
}

/// A short real walk between cells `x` and `y` of one region: the straight octile walk when it is free (no
/// walk is shorter); otherwise the best of the tree walk and of straight walks from one cell to ancestors
/// of the other, continued down the tree.
fn region_walk(graph: &Graph<'_>, cells: &[SweepCell], x: usize, y: usize) -> f64 {
    if let Some(line) = line_walk(graph, x, y) {
        return line;
    }
    tree_walk(graph, cells, x, y)
        .min(ancestor_walk(graph, cells, x, y))
        .min(ancestor_walk(graph, cells, y, x))
}

/// Straight walks from `x` to the ancestors of `y` 1, 2, 4, … steps up `y`'s tree path, then down the tree
/// to `y`: the best of them.
fn ancestor_walk(graph: &Graph<'_>, cells: &[SweepCell], x: usize, y: usize) -> f64 {
    let mut best = f64::INFINITY;
    let (mut a, mut steps, mut next) = (y, 0usize, 1usize);
    while cells[a].parent != ROOT {
        a = graph.back(a, cells[a].parent);
        steps += 1;
        if steps == next {
            next *= 2;
            if let Some(line) = line_walk(graph, x, a) {
                best = best.min(line + cells[y].dist - cells[a].dist);
            }
        }
    }
    best
}

/// The move index of a non-zero offset (`dx`, `dy`) with components in {-1, 0, 1}.
fn dir_of(dx: isize, dy: isize) -> usize {
    // Every such offset is in DIRS; the fallback is never taken.
    DIRS.iter().position(|&o| o == (dx, dy)).unwrap_or(0)
}

/// Octile length of the Bresenham walk from cell `x` to cell `y` when every move of it is allowed.
fn line_walk(graph: &Graph<'_>, x: usize, y: usize) -> Option<f64> {
    let (x0, y0) = graph.xy(x);
    let (x1, y1) = graph.xy(y);
    let (adx, ady) = (x0.abs_diff(x1), y0.abs_diff(y1));
    let sx: isize = if x1 >= x0 { 1 } else { -1 };
    let sy: isize = if y1 >= y0 { 1 } else { -1 };
    let (major, minor, x_major) = if adx >= ady {
        (adx, ady, true)
    } else {
        (ady, adx, false)
    };
    let straight = if x_major { dir_of(sx, 0) } else { dir_of(0, sy) };
    let diagonal = dir_of(sx, sy);
    let (mut cx, mut cy, mut i) = (x0, y0, x);
    let (major_i, minor_i) = (major as i64, minor as i64);
    let mut err = 0i64;
    for _ in 0..major {
        err += minor_i;
        let d = if 2 * err >= major_i {
            err -= major_i;
            diagonal
        } else {
            straight
        };
        i = graph.step(i, cx, cy, d)?;
        (cx, cy) = graph.xy(i);
    }
    (i == y).then(|| graph.octile(x, y))
}

/// Position marker of a node not in the heap.
const ABSENT: u32 = u32::MAX;
/// Position marker of a settled node.
const SETTLED: u32 = u32::MAX - 1;

/// A 4-ary min-heap over node ids with decrease-key (each node is in the heap at most once), for Dijkstra
/// on the portal graph; reset in time proportional to the nodes touched.
#[derive(Debug)]
struct IndexedHeap {
    heap: Vec<u32>,
    pos: Vec<u32>,
    dist: Vec<f64>,
    touched: Vec<u32>,
}

impl IndexedHeap {
    fn new(n: usize) -> Self {
        Self {
            heap: Vec::new(),
            pos: vec![ABSENT; n],
            dist: vec![f64::INFINITY; n],
            touched: Vec::new(),
        }
    }

    fn reset(&mut self) {
        for &t in &self.touched {
            self.pos[t as usize] = ABSENT;
            self.dist[t as usize] = f64::INFINITY;
        }
        self.touched.clear();
        self.heap.clear();
    }

    /// Nodes given a distance since the last reset.
    fn touched(&self) -> &[u32] {
        &self.touched
    }

    fn dist(&self, v: u32) -> f64 {
        self.dist[v as usize]
    }

    /// Offers distance `d` to node `v` (ignored when `v` is settled or already has a shorter one).
    #[inline]
    fn relax(&mut self, v: u32, d: f64) {
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
    fn pop(&mut self) -> Option<(u32, f64)> {
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

/// Geodesic (shortest collision-free) distances between all pairs of `points` (map frame, on reachable
/// cells), metres, as a row-major n × n `Vec<f64>`: symmetric, 0 on the diagonal, `f64::INFINITY` when
/// disconnected or when a point is not on a reachable cell. Upper bounds of [`geodesic_distance`] (travel
/// length, no potential term), exact for neighbouring points and within ~5 % on average otherwise (see the
/// module docs). One grid sweep plus n searches on a sparse graph of ~3n nodes.
pub fn geodesic_matrix(space: &CoverageSpace, points: &[Point2]) -> Vec<f64> {
    let n = points.len();
    let mut out = vec![f64::INFINITY; n * n];
    for i in 0..n {
        out[i * n + i] = 0.0;
    }
    if n < 2 {
        return out;
    }
    let geometry = space.geometry();
    let graph = Graph::new(space);
    let res = graph.resolution;

    // Each point's cell, when valid; the point of each cell nearest its centre owns it (the "winner").
    let home: Vec<Option<usize>> = points.iter().map(|&p| home_cell(space, p)).collect();
    let seeds: Vec<(usize, f64, u32)> = home
        .iter()
        .enumerate()
        .filter_map(|(k, h)| h.map(|i| (i, (geometry.center_of(i) - points[k]).norm(), k as u32)))
        .collect();

    // 1. The sweep.
    let cells = sweep(&graph, &seeds);

    // 2. Portals: the cheapest touching cell pair per pair of regions.
    let mut portals: Vec<Portal> = Vec::new();
    let mut weight: Vec<f64> = Vec::new();
    // Per point: (the other point, the portal between them).
    let mut of_site: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
    for u in 0..cells.len() {
        let lu = cells[u].label;
        if lu == NONE {
            continue;
        }
        let (x, y) = graph.xy(u);
        // E, N, NE, NW: each unordered pair of neighbouring cells once.
        for d in [0, 1, 4, 5] {
            let Some(v) = graph.step(u, x, y, d) else {
                continue;
            };
            let lv = cells[v].label;
            if lv == NONE || lv == lu {
                continue;
            }
            let step_m = STEP_CELLS[d] * res;
            let w = cells[u].dist + step_m + cells[v].dist;
            let (site_u, site_v) = (lu as usize, lv as usize);
            let half = 0.5 * step_m;
            let portal = Portal {
                sites: [lu, lv],
                cells: [u as u32, v as u32],
                step_m,
                reach_m: [cells[u].dist + half, cells[v].dist + half],
            };
            match of_site[site_u].iter().find(|e| e.0 == lv) {
                Some(&(_, id)) => {
                    let id = id as usize;
                    if w < weight[id] {
                        weight[id] = w;
                        let p = &mut portals[id];
                        // Keep the portal's orientation: cells[k] lies in sites[k]'s region.
                        *p = if p.sites[0] == lu {
                            portal
                        } else {
                            Portal {
                                sites: [lv, lu],
                                cells: [v as u32, u as u32],
                                step_m,
                                reach_m: [portal.reach_m[1], portal.reach_m[0]],
                            }
                        };
                    }
                }
                None => {
                    let id = portals.len() as u32;
                    portals.push(portal);
                    weight.push(w);
                    of_site[site_u].push((lv, id));
                    of_site[site_v].push((lu, id));
                }
            }
        }
    }
    let side = |p: &Portal, site: u32| -> usize { usize::from(p.sites[1] == site) };

    // 3. Portal graph (CSR): portals of one region joined by the shorter real walk between their cells.
    let np = portals.len();
    let mut edges: Vec<(u32, u32, f64)> = Vec::new();
    for (site, list) in of_site.iter().enumerate() {
        let site = site as u32;
        for (k, &(_, p)) in list.iter().enumerate() {
            let pp = &portals[p as usize];
            let x = pp.cells[side(pp, site)] as usize;
            for &(_, q) in &list[k + 1..] {
                let qp = &portals[q as usize];
                let y = qp.cells[side(qp, site)] as usize;
                let walk = region_walk(&graph, &cells, x, y);
                if walk.is_finite() {
                    let w = 0.5 * pp.step_m + walk + 0.5 * qp.step_m;
                    edges.push((p, q, w));
                    edges.push((q, p, w));
                }
            }
        }
    }
    let mut start = vec![0usize; np + 1];
    for &(a, _, _) in &edges {
        start[a as usize + 1] += 1;
    }
    for i in 0..np {
        start[i + 1] += start[i];
    }
    let mut adj = vec![(0u32, 0.0f64); edges.len()];
    let mut fill = start.clone();
    for &(a, b, w) in &edges {
        adj[fill[a as usize]] = (b, w);
        fill[a as usize] += 1;
    }
    drop(edges);

    // 4. From every region's point: Dijkstra over the portals, then each other point's best portal.
    let winners: Vec<usize> = seeds
        .iter()
        .map(|&(i, _, k)| (i, k as usize))
        .filter(|&(i, k)| cells[i].label as usize == k)
        .map(|(_, k)| k)
        .collect();
    let mut queue = IndexedHeap::new(np);
    let mut row = vec![f64::INFINITY; n];
    for &src in &winners {
        queue.reset();
        let src_label = src as u32;
        for &(_, p) in &of_site[src] {
            let pp = &portals[p as usize];
            queue.relax(p, pp.reach_m[side(pp, src_label)]);
        }
        while let Some((u, du)) = queue.pop() {
            let u = u as usize;
            for &(v, w) in &adj[start[u]..start[u + 1]] {
                queue.relax(v, du + w);
            }
        }
        row.fill(f64::INFINITY);
        for &p in queue.touched() {
            let pp = &portals[p as usize];
            let dp = queue.dist(p);
            for (site, reach) in pp.sites.iter().zip(pp.reach_m) {
                let site = *site as usize;
                row[site] = row[site].min(dp + reach);
            }
        }
        row[src] = 0.0;
        for &dst in &winners {
            let (a, b) = (src * n + dst, dst * n + src);
            let d = out[a].min(row[dst]);
            out[a] = d;
            out[b] = d;
        }
    }

    // Points whose cell another point owns: straight to that owner, then the owner's distances.
    let owner = |k: usize| home[k].map(|i| cells[i].label as usize);
    for q in 0..n {
        let Some(w) = owner(q) else { continue };
        if w == q {
            continue;
        }
        let to_w = (points[q] - points[w]).norm();
        for j in 0..n {
            if j == q {
                continue;
            }
            let d = match owner(j) {
                Some(wj) if wj == w => (points[q] - points[j]).norm(),
                Some(wj) if wj == j => to_w + out[w * n + j],
                // j's cell is owned by another point too: through both owners.
                Some(wj) => to_w + out[w * n + wj] + (points[j] - points[wj]).norm(),
                None => f64::INFINITY,
            };
            out[q * n + j] = d;
            out[j * n + q] = d;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{Rng, random_points, random_space};
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::space::RobotShape;
    use proptest::prelude::*;

    #[test]
    fn corridor_distances_are_exact_along_a_line() {
        // An empty 10 m × 1 m strip: points on its centre line; geodesics are the straight distances.
        let g = GridGeometry::new(100, 10, 0.1, Point2::origin()).expect("valid");
        let grid = OccupancyGrid::filled(g, CellState::Free);
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 0.5)).expect("space");
        let pts: Vec<Point2> = [0.55, 2.05, 4.95, 9.05, 9.08]
            .iter()
            .map(|&x| Point2::new(x, 0.55))
            .collect();
        let m = geodesic_matrix(&s, &pts);
        for i in 0..pts.len() {
            for j in 0..pts.len() {
                assert!(
                    (m[i * 5 + j] - (pts[i] - pts[j]).norm()).abs() < 1e-9,
                    "{i} {j}: {}",
                    m[i * 5 + j]
                );
            }
        }
    }

    #[test]
    fn walls_lengthen_and_separate() {
        // Wall at x = 3 m with a door at the top; a third point boxed in.
        let g = GridGeometry::new(60, 30, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(2.95, 0.0, 3.05, 1.95, CellState::Occupied);
        let robot = RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        };
        let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space");
        let pts = [Point2::new(2.55, 0.55), Point2::new(3.45, 0.55), Point2::new(-5.0, 0.0)];
        let m = geodesic_matrix(&s, &pts);
        let exact = geodesic_distance(&s, pts[0], pts[1]).expect("connected");
        // Around the wall: up ~1.6 m, over, down again.
        assert!(exact > 3.0, "{exact}");
        assert!(m[1] >= exact - 1e-9 && m[1] <= exact * 1.02, "{} vs {exact}", m[1]);
        assert_eq!(m[1], m[3]);
        assert_eq!(m[2], f64::INFINITY);
        assert_eq!(m[8], 0.0);
        assert!(geodesic_matrix(&s, &[]).is_empty());
        assert_eq!(geodesic_matrix(&s, &pts[..1]), vec![0.0]);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

        #[test]
        fn matrix_matches_per_pair_search(
            seed in any::<u64>(), w in 16usize..60, h in 16usize..60, obstacles in 0usize..16,
            radius in 0.08f64..0.22, npts in 2usize..24,
        ) {
            let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
            let mut rng = Rng::new(seed ^ 0x77);
            let pts = random_points(&s, &mut rng, npts);
            let m = geodesic_matrix(&s, &pts);
            let diag = 0.1 * std::f64::consts::SQRT_2;
            for i in 0..npts {
                prop_assert_eq!(m[i * npts + i], 0.0);
                for j in 0..npts {
                    let v = m[i * npts + j];
                    prop_assert_eq!(v, m[j * npts + i]);
                    prop_assert!(v >= (pts[i] - pts[j]).norm() - 1e-9);
                    if i < j {
                        match geodesic_distance(&s, pts[i], pts[j]) {
                            // An upper bound (up to a cell diagonal for points sharing a cell), and not a
                            // wild one.
                            Some(exact) => {
                                prop_assert!(v >= exact - diag - 1e-9, "{} < {}", v, exact);
                                prop_assert!(v <= 2.0 * exact + diag, "{} vs {}", v, exact);
                            }
                            None => prop_assert!(v.is_infinite()),
                        }
                    }
                }
            }
        }

        /// Distances from one point over the whole grid equal the per-pair search.
        #[test]
        fn distances_from_one_point_match_per_pair_search(
            seed in any::<u64>(), w in 16usize..60, h in 16usize..60, obstacles in 0usize..16,
            radius in 0.08f64..0.22, npts in 2usize..12,
        ) {
            let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
            let mut rng = Rng::new(seed ^ 0x55);
            let pts = random_points(&s, &mut rng, npts);
            let from = DistancesFrom::new(&s, pts[0]);
            for &p in &pts[1..] {
                match (from.to(&s, p), geodesic_distance(&s, pts[0], p)) {
                    (Some(d), Some(exact)) => prop_assert!((d - exact).abs() < 1e-9, "{} vs {}", d, exact),
                    (d, exact) => prop_assert_eq!(d, exact),
                }
            }
        }
    }

    /// Relative excess of the matrix over the exact per-pair distance on seeded cluttered maps.
    fn excess_stats(size: usize, obstacles: usize, npts: usize, seeds: std::ops::Range<u64>) -> (f64, f64, usize) {
        let mut all = Vec::new();
        for seed in seeds {
            let Some(s) = random_space(seed, size, size, obstacles, 0.15) else {
                continue;
            };
            let mut rng = Rng::new(seed);
            let pts = random_points(&s, &mut rng, npts);
            let m = geodesic_matrix(&s, &pts);
            for i in 0..npts {
                for j in i + 1..npts {
                    if let Some(exact) = geodesic_distance(&s, pts[i], pts[j]) {
                        all.push((m[i * npts + j] - exact) / exact.max(0.3));
                    }
                }
            }
        }
        all.sort_by(f64::total_cmp);
        let mean = all.iter().sum::<f64>() / all.len() as f64;
        (mean, all[all.len() * 95 / 100], all.len())
    }

    #[test]
    fn close_to_exact_on_cluttered_maps() {
        // 10 m × 10 m, 40 obstacles, 25 points, 4 maps: measured mean excess ≈ 5 %, p95 ≈ 17 %.
        let (mean, p95, pairs) = excess_stats(100, 40, 25, 0..4);
        assert!(pairs > 500, "{pairs}");
        assert!(mean <= 0.08, "mean relative excess {mean}");
        assert!(p95 <= 0.25, "p95 relative excess {p95}");
    }

    /// The same on bigger maps (slow: per-pair A* for every pair).
    #[test]
    #[ignore]
    fn close_to_exact_on_big_cluttered_maps() {
        for (size, obstacles, npts) in [(150, 60, 50), (300, 200, 60)] {
            let (mean, p95, pairs) = excess_stats(size, obstacles, npts, 0..6);
            println!(
                "{size}² cells, {obstacles} obstacles, {npts} points: {pairs} pairs, mean {mean:.4}, p95 {p95:.4}"
            );
            assert!(mean <= 0.08 && p95 <= 0.25);
        }
    }
}
