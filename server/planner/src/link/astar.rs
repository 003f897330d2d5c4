//! A* on the reachable cells with the potential-field cost, and the pieces every link search shares: the
//! move rule ([`Graph`]), the per-cell search state ([`Frontier`]) and the cost model ([`Search`]).
//!
//! The cost of the move u→v is `step · (1 + α·(Ψ(u) + Ψ(v)) / 2)` with `step` the octile step length
//! (resolution or √2 · resolution) and Ψ = 1 / (clearance + ε). It is symmetric and at least
//! `m · step`, where `m = 1 + α / (max clearance + ε)`; the heuristic is `m` times the octile distance to
//! the goal (minus the goal set's extent), which is admissible and consistent, so a cell is final when it
//! is first popped and the first goal pop bounds the answer. The octile distance dominates the Euclidean
//! one, so this expands fewer cells than a Euclidean heuristic while staying exact.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::geom::Point2;
use crate::space::CoverageSpace;

/// Cell offsets of the 8 moves: E, N, W, S, NE, NW, SW, SE. `d ^ 2` is the opposite of `d`.
pub(crate) const DIRS: [(isize, isize); 8] = [(1, 0), (0, 1), (-1, 0), (0, -1), (1, 1), (-1, 1), (-1, -1), (1, -1)];

/// Step length of each move in cells.
pub(crate) const STEP_CELLS: [f64; 8] = [
    1.0,
    1.0,
    1.0,
    1.0,
    std::f64::consts::SQRT_2,
    std::f64::consts::SQRT_2,
    std::f64::consts::SQRT_2,
    std::f64::consts::SQRT_2,
];

/// Parent marker of a search root (a cell joined directly to `a` or `b`).
pub(crate) const ROOT: u8 = u8::MAX;

/// The move rule on the reachable cells of a space (see the module docs of `link`).
#[derive(Debug)]
pub(crate) struct Graph<'s> {
    pub(crate) space: &'s CoverageSpace,
    pub(crate) width: usize,
    pub(crate) height: usize,
    pub(crate) resolution: f64,
}

impl<'s> Graph<'s> {
    pub(crate) fn new(space: &'s CoverageSpace) -> Self {
        let g = space.geometry();
        Self {
            space,
            width: g.width,
            height: g.height,
            resolution: g.resolution,
        }
    }

    /// Number of cells.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.width * self.height
    }

    /// The cell reached from cell `i` = (`x`, `y`) by move `d`, when that move is allowed.
    #[inline(always)]
    pub(crate) fn step(&self, i: usize, x: usize, y: usize, d: usize) -> Option<usize> {
        let (dx, dy) = DIRS[d];
        let nx = x.checked_add_signed(dx)?;
        let ny = y.checked_add_signed(dy)?;
        if nx >= self.width || ny >= self.height {
            return None;
        }
        let reach = &self.space.reachable;
        let j = ny * self.width + nx;
        if !reach[j] {
            return None;
        }
        if d < 4 {
            return Some(j);
        }
        let side_x = reach[y * self.width + nx];
        let side_y = reach[ny * self.width + x];
        if side_x && side_y {
            return Some(j);
        }
        if side_x || side_y {
            // One side blocked: the two orthogonal moves through the other side connect the same cells.
            return None;
        }
        self.pinch_ok(i, j).then_some(j)
    }

    /// A diagonal step between two cells whose shared neighbours are both unreachable: allowed when the
    /// straight segment is `segment_ok` in both directions (so the rule is symmetric).
    #[cold]
    fn pinch_ok(&self, i: usize, j: usize) -> bool {
        let g = self.space.geometry();
        let (p, q) = (g.center_of(i), g.center_of(j));
        self.space.segment_ok(p, q) && self.space.segment_ok(q, p)
    }

    /// Calls `f(j, d, jx, jy)` for every allowed move `d` from cell `i` to cell `j` = (`jx`, `jy`).
    #[inline(always)]
    pub(crate) fn for_each_move(&self, i: usize, mut f: impl FnMut(usize, usize, usize, usize)) {
        let (x, y) = (i % self.width, i / self.width);
        for (d, &(dx, dy)) in DIRS.iter().enumerate() {
            if let Some(j) = self.step(i, x, y, d) {
                f(j, d, x.wrapping_add_signed(dx), y.wrapping_add_signed(dy));
            }
        }
    }

    /// The cell one move `d` back from `j` (the cell `j` was reached from).
    #[inline]
    pub(crate) fn back(&self, j: usize, d: u8) -> usize {
        let (dx, dy) = DIRS[usize::from(d)];
        let (x, y) = (j % self.width, j / self.width);
        // Moves recorded by a search were on the grid, so this stays on it.
        let px = x.wrapping_add_signed(-dx);
        let py = y.wrapping_add_signed(-dy);
        py * self.width + px
    }

    /// Octile distance between two cells, metres.
    #[inline]
    pub(crate) fn octile(&self, i: usize, j: usize) -> f64 {
        self.octile_xy((i % self.width, i / self.width), (j % self.width, j / self.width))
    }

    /// Octile distance between cells given by coordinates, metres.
    #[inline]
    pub(crate) fn octile_xy(&self, (xi, yi): (usize, usize), (xj, yj): (usize, usize)) -> f64 {
        let dx = xi.abs_diff(xj) as f64;
        let dy = yi.abs_diff(yj) as f64;
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        (hi - lo + std::f64::consts::SQRT_2 * lo) * self.resolution
    }

    /// Coordinates of cell `i`.
    #[inline]
    pub(crate) fn xy(&self, i: usize) -> (usize, usize) {
        (i % self.width, i / self.width)
    }
}

/// An open-list entry: a cell and its priority, ordered so that `BinaryHeap` pops the smallest key.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    pub(crate) key: f64,
    pub(crate) cell: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other.key.total_cmp(&self.key).then_with(|| other.cell.cmp(&self.cell))
    }
}

/// Per-cell search state in one flat array of `(g, mark, parent)`, reused between searches:
/// - `g`: best cost found so far (valid when `mark` is of this generation);
/// - `mark`: `2·generation` = seen in this search, `2·generation + 1` = closed in this search;
/// - `parent`: the move that reached the cell (`ROOT` for roots).
///
/// The three live together so that touching a cell touches one cache line, and the all-zero initial state
/// lets a fresh array come from zeroed pages that are only faulted in where a search goes (a short link on a
/// big map does not pay for the whole map). A generation stamp says which entries belong to the current
/// search, so nothing is cleared between calls.
#[derive(Debug, Default)]
pub(crate) struct Frontier {
    nodes: Vec<(f64, u32, u8)>,
    pub(crate) heap: BinaryHeap<Entry>,
    generation: u32,
    /// Cells closed in this search.
    pub(crate) expanded: usize,
}

impl Frontier {
    /// Starts a new search over `n` cells.
    pub(crate) fn reset(&mut self, n: usize) {
        if self.nodes.len() != n {
            self.nodes = vec![(0.0, 0, 0); n];
            self.generation = 0;
        }
        if self.generation >= u32::MAX / 2 - 1 {
            self.nodes.fill((0.0, 0, 0));
            self.generation = 0;
        }
        self.generation += 1;
        self.heap.clear();
        self.expanded = 0;
    }

    /// Cost so far of cell `i` (infinite when not seen in this search).
    #[inline]
    pub(crate) fn g(&self, i: usize) -> f64 {
        let (g, mark, _) = self.nodes[i];
        if mark >> 1 == self.generation { g } else { f64::INFINITY }
    }

    #[inline]
    pub(crate) fn is_closed(&self, i: usize) -> bool {
        self.nodes[i].1 == 2 * self.generation + 1
    }

    /// Records cost `g` for cell `i`, reached by move `parent`.
    #[inline]
    pub(crate) fn set(&mut self, i: usize, g: f64, parent: u8) {
        let generation = self.generation;
        let n = &mut self.nodes[i];
        n.0 = g;
        n.2 = parent;
        if n.1 >> 1 != generation {
            n.1 = 2 * generation;
        }
    }

    #[inline]
    pub(crate) fn close(&mut self, i: usize) {
        self.nodes[i].1 = 2 * self.generation + 1;
        self.expanded += 1;
    }

    #[inline]
    pub(crate) fn parent(&self, i: usize) -> u8 {
        self.nodes[i].2
    }

    /// Drops closed entries from the top of the heap and returns the smallest key left (∞ when empty).
    pub(crate) fn top_key(&mut self) -> f64 {
        while let Some(e) = self.heap.peek() {
            if self.is_closed(e.cell as usize) {
                self.heap.pop();
            } else {
                return e.key;
            }
        }
        f64::INFINITY
    }

    /// Pops the open cell with the smallest key, skipping closed (stale) entries.
    pub(crate) fn pop_open(&mut self) -> Option<Entry> {
        while let Some(e) = self.heap.pop() {
            if !self.is_closed(e.cell as usize) {
                return Some(e);
            }
        }
        None
    }
}

/// The cost model of one link search.
#[derive(Debug)]
pub(crate) struct Search<'g, 's> {
    pub(crate) graph: &'g Graph<'s>,
    pub(crate) alpha: f64,
    pub(crate) epsilon_m: f64,
    /// Lower bound of the per-metre cost multiplier (scales the heuristic).
    pub(crate) heuristic_scale: f64,
    /// The search gives up (no path) once every open path would cost more than this.
    pub(crate) max_cost: f64,
}

/// A goal set as the heuristic sees it: a centre cell's coordinates and the set's extent (largest octile
/// distance of a goal cell from the centre, metres).
#[derive(Debug, Clone, Copy)]
pub(crate) struct GoalFrame {
    pub(crate) centre: (usize, usize),
    pub(crate) extent_m: f64,
}

/// A search root or goal: a cell, and the cost of the straight connection between it and the point.
pub(crate) type Attachment = (usize, f64);

/// What a grid search found.
#[derive(Debug)]
pub(crate) struct Found {
    /// Cells from the one joined to `a` to the one joined to `b`.
    pub(crate) cells: Vec<usize>,
    /// Total cost including both straight connections.
    pub(crate) cost: f64,
    /// Cells closed (both directions for the bidirectional search).
    pub(crate) expanded: usize,
}

impl Search<'_, '_> {
    /// Ψ at clearance `d` metres.
    #[inline]
    pub(crate) fn psi(&self, d: f64) -> f64 {
        1.0 / (d + self.epsilon_m)
    }

    /// Ψ of cell `i`.
    #[inline]
    pub(crate) fn psi_cell(&self, i: usize) -> f64 {
        self.psi(self.graph.space.clearance.at(i))
    }

    /// Cost of a move of `length_m` metres between points with potentials `psi_u` and `psi_v`.
    #[inline]
    pub(crate) fn edge(&self, length_m: f64, psi_u: f64, psi_v: f64) -> f64 {
        length_m * (1.0 + self.alpha * 0.5 * (psi_u + psi_v))
    }

    /// The cells around `p` (its own and the 8 around it) that are reachable and joined to `p` by a
    /// `segment_ok` straight segment (checked both ways, so roots and goals agree), with the connection
    /// cost. Empty when `p` is not a valid robot position.
    pub(crate) fn attach(&self, p: Point2) -> Vec<Attachment> {
        let space = self.graph.space;
        let g = space.geometry();
        let Some(c) = g.locate(p) else {
            return Vec::new();
        };
        if !space.point_ok(p) {
            return Vec::new();
        }
        let psi_p = self.psi(space.clearance_at(p));
        let mut out = Vec::with_capacity(9);
        // The point's own cell first: it is the centre of the goal frame when attached.
        const AROUND: [(isize, isize); 9] = [
            (0, 0),
            (1, 0),
            (0, 1),
            (-1, 0),
            (0, -1),
            (1, 1),
            (-1, 1),
            (-1, -1),
            (1, -1),
        ];
        for (dx, dy) in AROUND {
            let Some(n) = g.offset(c, dx, dy) else {
                continue;
            };
            let i = g.index(n);
            if !space.reachable[i] {
                continue;
            }
            let q = g.center(n);
            if space.segment_ok(p, q) && space.segment_ok(q, p) {
                out.push((i, self.edge((q - p).norm(), psi_p, self.psi_cell(i))));
            }
        }
        out
    }

    /// Admissible, consistent estimate of the cost from the cell at `xy` to a goal set.
    #[inline]
    pub(crate) fn heuristic(&self, xy: (usize, usize), goal: &GoalFrame) -> f64 {
        self.heuristic_scale * (self.graph.octile_xy(xy, goal.centre) - goal.extent_m).max(0.0)
    }

    /// The frame of a goal set (the first attachment is the point's own cell when that one is attached;
    /// any cell of the set works as centre).
    pub(crate) fn goal_frame(&self, goals: &[Attachment]) -> GoalFrame {
        let centre = goals[0].0;
        let extent = goals
            .iter()
            .map(|&(i, _)| self.graph.octile(i, centre))
            .fold(0.0, f64::max);
        GoalFrame {
            centre: self.graph.xy(centre),
            extent_m: extent * (1.0 + 1e-12),
        }
    }

    /// Seeds `frontier` with the roots, keyed with the heuristic towards `goal`.
    pub(crate) fn seed(&self, frontier: &mut Frontier, roots: &[Attachment], goal: &GoalFrame) {
        frontier.reset(self.graph.len());
        for &(i, cost) in roots {
            if cost < frontier.g(i) {
                frontier.set(i, cost, ROOT);
                frontier.heap.push(Entry {
                    key: cost + self.heuristic(self.graph.xy(i), goal),
                    cell: i as u32,
                });
            }
        }
    }

    /// The chain of cells from a root of `frontier` to `end` (inclusive), root first.
    pub(crate) fn trace(&self, frontier: &Frontier, end: usize) -> Vec<usize> {
        let mut cells = vec![end];
        let mut i = end;
        loop {
            let d = frontier.parent(i);
            if d == ROOT {
                break;
            }
            i = self.graph.back(i, d);
            cells.push(i);
        }
        cells.reverse();
        cells
    }
}

/// Cost of the goal connection of cell `i`, if `i` is a goal.
#[inline]
pub(crate) fn goal_cost(goals: &[Attachment], i: usize) -> Option<f64> {
    goals.iter().find(|&&(g, _)| g == i).map(|&(_, c)| c)
}

/// Forward A* from the `roots` to the `goals`; optimal under the potential-field cost.
pub(crate) fn search(
    s: &Search<'_, '_>,
    fwd: &mut Frontier,
    roots: &[Attachment],
    goals: &[Attachment],
) -> Option<Found> {
    let goal = s.goal_frame(goals);
    s.seed(fwd, roots, &goal);
    let res = s.graph.resolution;
    let mut best = f64::INFINITY;
    let mut best_cell = None;
    while let Some(e) = fwd.pop_open() {
        if e.key >= best || e.key > s.max_cost {
            break;
        }
        let u = e.cell as usize;
        let gu = fwd.g(u);
        fwd.close(u);
        if let Some(c) = goal_cost(goals, u)
            && gu + c < best
        {
            best = gu + c;
            best_cell = Some(u);
        }
        let psi_u = s.psi_cell(u);
        s.graph.for_each_move(u, |v, d, vx, vy| {
            if fwd.is_closed(v) {
                return;
            }
            let gv = gu + s.edge(STEP_CELLS[d] * res, psi_u, s.psi_cell(v));
            if gv < fwd.g(v) {
                fwd.set(v, gv, d as u8);
                fwd.heap.push(Entry {
                    key: gv + s.heuristic((vx, vy), &goal),
                    cell: v as u32,
                });
            }
        });
    }
    let end = best_cell?;
    Some(Found {
        cells: s.trace(fwd, end),
        cost: best,
        expanded: fwd.expanded,
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::random_space;
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

        /// Every allowed move is a collision-free straight step (both ways), moves are symmetric, and moves
        /// past exactly one blocked corner cell are refused.
        #[test]
        fn moves_are_collision_free_and_symmetric(
            seed in any::<u64>(), w in 8usize..40, h in 8usize..40, obstacles in 0usize..20, radius in 0.05f64..0.3,
        ) {
            let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
            let graph = Graph::new(&s);
            let g = s.geometry();
            for i in (0..g.len()).filter(|&i| s.reachable[i]) {
                let (x, y) = graph.xy(i);
                for d in 0..8 {
                    let Some(j) = graph.step(i, x, y, d) else { continue };
                    prop_assert!(s.segment_ok(g.center_of(i), g.center_of(j)));
                    prop_assert!(s.segment_ok(g.center_of(j), g.center_of(i)));
                    let (jx, jy) = graph.xy(j);
                    prop_assert_eq!(graph.step(j, jx, jy, d ^ 2), Some(i));
                    prop_assert_eq!(graph.back(j, d as u8), i);
                    if d >= 4 {
                        let sides = [y * g.width + jx, jy * g.width + x];
                        prop_assert!(s.reachable[sides[0]] == s.reachable[sides[1]]);
                    }
                }
            }
        }
    }

    #[test]
    fn heap_pops_smallest_key_first() {
        let mut heap = BinaryHeap::new();
        for (k, c) in [(3.0, 1), (0.5, 2), (7.0, 3), (0.5, 4), (f64::INFINITY, 5)] {
            heap.push(Entry { key: k, cell: c });
        }
        let order: Vec<u32> = std::iter::from_fn(|| heap.pop()).map(|e| e.cell).collect();
        assert_eq!(order, vec![2, 4, 1, 3, 5]);
    }
}
