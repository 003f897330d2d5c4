//! The fallbacks when the optimiser cannot clear a window: a local potential-field A* detour from anchor
//! to anchor, and the skip to a later reachable point of the plan.
//!
//! Both search a [`LocalGrid`]: a box of cells aligned with the map's (coarsened by an integer factor when
//! the box is large) where a cell is blocked when its centre is closer than the robot radius to the static
//! map (DESIGN §6) or to a live point, or lies off the map. Clearance comes from an exact distance
//! transform of the box's obstacle cells (static non-free cells and cells holding live points); it is within
//! half a cell diagonal of the true clearance, so cells in that band are decided by the exact
//! [`World::clear_of`]. The box is padded by the radius so that obstacles just outside it are seen.
//! Moves are 8-connected without corner cutting and cost `step · (1 + α·(Ψ(u) + Ψ(v))/2)` with
//! Ψ = 1/(clearance + ε), as in `link` (seed 000 eqs. 15-16), so paths keep off obstacles; then a
//! line-of-sight shortcut keeps only segments that pass [`segment_clear`].

use std::cmp::Ordering;
use std::collections::{BinaryHeap, VecDeque};

use crate::geom::{Point2, simplify_polyline};
use crate::map::{DistanceField, GridGeometry};

use super::verify::segment_clear;
use super::world::World;

/// Potential-field weight α (as `link`'s default).
const ALPHA: f64 = 0.2;
/// Potential-field ε, metres.
const EPSILON_M: f64 = 0.05;

/// Cells of a local search box and which of them the robot's centre may occupy.
#[derive(Debug)]
pub(crate) struct LocalGrid {
    pub(crate) geo: GridGeometry,
    pub(crate) blocked: Vec<bool>,
    /// Approximate clearance of each cell centre, metres (for the potential).
    clearance: Vec<f32>,
}

impl LocalGrid {
    /// The box `[lo, hi]` (map frame, metres) padded by the radius, at the map's resolution coarsened so
    /// that it has at most about `max_cells` cells. `None` for an empty or non-finite box.
    pub(crate) fn build(world: &World<'_>, lo: Point2, hi: Point2, radius_m: f64, max_cells: usize) -> Option<Self> {
        let mg = &world.grid.geometry;
        let res = mg.resolution;
        if !(lo.x.is_finite() && lo.y.is_finite() && hi.x.is_finite() && hi.y.is_finite()) {
            return None;
        }
        // Map cell range (may extend past the map).
        let pad = radius_m + 2.0 * res;
        let fx0 = ((lo.x - pad - mg.origin.x) / res).floor();
        let fy0 = ((lo.y - pad - mg.origin.y) / res).floor();
        let fx1 = ((hi.x + pad - mg.origin.x) / res).ceil();
        let fy1 = ((hi.y + pad - mg.origin.y) / res).ceil();
        let (nx, ny) = (fx1 - fx0, fy1 - fy0);
        if !(nx >= 1.0 && ny >= 1.0) || nx * ny > 1e9 {
            return None;
        }
        let k = ((nx * ny / max_cells.max(1) as f64).sqrt().ceil() as usize).max(1);
        // Pad with the radius again at the coarse size, so a ring of cells holds obstacles just outside.
        let c = res * k as f64;
        let ring = (radius_m / c).ceil() as isize + 1;
        let (ix0, iy0) = (fx0 as isize - ring * k as isize, fy0 as isize - ring * k as isize);
        let width = (nx as usize).div_ceil(k) + 2 * ring as usize;
        let height = (ny as usize).div_ceil(k) + 2 * ring as usize;
        let origin = Point2::new(mg.origin.x + ix0 as f64 * res, mg.origin.y + iy0 as f64 * res);
        let geo = GridGeometry::new(width, height, c, origin).ok()?;
        let mut site = vec![false; geo.len()];
        let (mw, mh) = (mg.width as isize, mg.height as isize);
        let border = world.field.border_is_site();
        for ly in 0..height {
            for lx in 0..width {
                let mut s = false;
                'cells: for dy in 0..k as isize {
                    for dx in 0..k as isize {
                        let (x, y) = (ix0 + (lx * k) as isize + dx, iy0 + (ly * k) as isize + dy);
                        let on = x >= 0 && y >= 0 && x < mw && y < mh;
                        if (on && !world.grid.is_free((y * mw + x) as usize)) || (!on && border) {
                            s = true;
                            break 'cells;
                        }
                    }
                }
                site[ly * width + lx] = s;
            }
        }
        if let Some(live) = world.live {
            let top = Point2::new(origin.x + width as f64 * c, origin.y + height as f64 * c);
            for q in live.within(origin, top) {
                if let Some(cell) = geo.locate(q) {
                    site[geo.index(cell)] = true;
                }
            }
        }
        let field = DistanceField::compute(geo, |i| site[i], false);
        let band = c * std::f64::consts::FRAC_1_SQRT_2 + 1e-9;
        let ring = ring as usize;
        let mut blocked = vec![true; geo.len()];
        for (i, b) in blocked.iter_mut().enumerate() {
            let cell = geo.cell(i);
            if cell.x < ring || cell.y < ring || cell.x >= width - ring || cell.y >= height - ring {
                continue;
            }
            let p = geo.center_of(i);
            let d = field.at(i);
            *b = if !world.inside(p) || d < radius_m - band {
                true
            } else if d < radius_m + band {
                !world.clear_of(p, radius_m)
            } else {
                false
            };
        }
        let clearance = field.values().to_vec();
        Some(Self {
            geo,
            blocked,
            clearance,
        })
    }

    /// The unblocked cell holding `p`, if any.
    pub(crate) fn free_cell(&self, p: Point2) -> Option<usize> {
        let i = self.geo.index(self.geo.locate(p)?);
        (!self.blocked[i]).then_some(i)
    }

    fn psi(&self, i: usize) -> f64 {
        1.0 / (f64::from(self.clearance[i]).min(1e6) + EPSILON_M)
    }

    /// Calls `f(j, step_m)` for each allowed move from cell `i`.
    fn moves(&self, i: usize, mut f: impl FnMut(usize, f64)) {
        const D: [(isize, isize); 8] = [(1, 0), (0, 1), (-1, 0), (0, -1), (1, 1), (-1, 1), (-1, -1), (1, -1)];
        let (w, h) = (self.geo.width as isize, self.geo.height as isize);
        let (x, y) = ((i % self.geo.width) as isize, (i / self.geo.width) as isize);
        let ok = |x: isize, y: isize| x >= 0 && y >= 0 && x < w && y < h && !self.blocked[(y * w + x) as usize];
        for (d, &(dx, dy)) in D.iter().enumerate() {
            let (nx, ny) = (x + dx, y + dy);
            if !ok(nx, ny) || (d >= 4 && !(ok(nx, y) && ok(x, ny))) {
                continue;
            }
            let step = if d >= 4 { std::f64::consts::SQRT_2 } else { 1.0 } * self.geo.resolution;
            f((ny * w + nx) as usize, step);
        }
    }

    /// Cells reachable from `start`.
    pub(crate) fn reachable(&self, start: usize) -> Vec<bool> {
        let mut seen = vec![false; self.geo.len()];
        let mut queue = VecDeque::from([start]);
        seen[start] = true;
        while let Some(i) = queue.pop_front() {
            self.moves(i, |j, _| {
                if !seen[j] {
                    seen[j] = true;
                    queue.push_back(j);
                }
            });
        }
        seen
    }

    /// Potential-field A* from cell `start` to cell `goal`: the cell centres of the path, or `None`.
    pub(crate) fn astar(&self, start: usize, goal: usize) -> Option<Vec<Point2>> {
        let n = self.geo.len();
        let mut g = vec![f64::INFINITY; n];
        let mut parent = vec![usize::MAX; n];
        let mut closed = vec![false; n];
        let mut heap = BinaryHeap::new();
        let gc = self.geo.cell(goal);
        let hfn = |i: usize| {
            let c = self.geo.cell(i);
            let (dx, dy) = (c.x.abs_diff(gc.x) as f64, c.y.abs_diff(gc.y) as f64);
            let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
            (hi - lo + std::f64::consts::SQRT_2 * lo) * self.geo.resolution
        };
        g[start] = 0.0;
        heap.push(Open(hfn(start), start));
        while let Some(Open(_, i)) = heap.pop() {
            if closed[i] {
                continue;
            }
            closed[i] = true;
            if i == goal {
                let mut cells = vec![goal];
                let mut c = goal;
                while c != start {
                    c = parent[c];
                    cells.push(c);
                }
                cells.reverse();
                return Some(cells.into_iter().map(|c| self.geo.center_of(c)).collect());
            }
            let psi_i = self.psi(i);
            self.moves(i, |j, step| {
                if closed[j] {
                    return;
                }
                let cand = g[i] + step * (1.0 + ALPHA * 0.5 * (psi_i + self.psi(j)));
                if cand < g[j] {
                    g[j] = cand;
                    parent[j] = i;
                    heap.push(Open(cand + hfn(j), j));
                }
            });
        }
        None
    }
}

/// Min-heap entry (priority, cell).
#[derive(Debug, PartialEq)]
struct Open(f64, usize);

impl Eq for Open {}

impl PartialOrd for Open {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Open {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then_with(|| other.1.cmp(&self.1))
    }
}

/// `head ++ cells ++ tail` with the middle shortcut by line of sight (segments that pass
/// [`segment_clear`]); the first and last point of `head` and `tail` are kept.
pub(crate) fn shortcut_chain(
    head: &[Point2],
    cells: &[Point2],
    tail: &[Point2],
    world: &World<'_>,
    radius_m: f64,
) -> Vec<Point2> {
    let mut mid: Vec<Point2> = Vec::with_capacity(cells.len() + 2);
    mid.extend(head.last());
    mid.extend_from_slice(cells);
    mid.extend(tail.first());
    let keep = |a: Point2, b: Point2| segment_clear(a, b, world, radius_m);
    let short = simplify_polyline(&mid, f64::INFINITY, &keep);
    let mut out = Vec::with_capacity(short.len() + head.len() + tail.len());
    out.extend_from_slice(&head[..head.len().saturating_sub(1)]);
    out.extend(short);
    out.extend_from_slice(tail.get(1..).unwrap_or(&[]));
    out.dedup_by(|a, b| (*a - *b).norm() < 1e-12);
    out
}
