//! A window-sized cache of the obstacles for the optimiser: the live points near the window copied out of
//! the site's tree once into buckets, so the many nearest-obstacle queries of an optimisation scan a few
//! buckets instead of descending a tree of the whole site.
//!
//! Exact where it answers: for a query inside the cached region (shrunk by the query radius) it returns the
//! nearest obstacle point whenever one lies within `radius` metres (static sites through the distance field,
//! live points from the buckets), and `None` when none does; outside that region it asks the [`World`].

use crate::geom::Point2;
use crate::map::ikd_tree::{Aabb, Point3};

use super::cost::Obstacles;
use super::world::World;

/// Live points of a box in buckets, with the world as fallback.
pub(crate) struct LocalObstacles<'a, 'w> {
    world: &'a World<'w>,
    /// Queries within [lo, hi] are answered from the buckets.
    lo: Point2,
    hi: Point2,
    origin: Point2,
    bucket: f64,
    nx: usize,
    ny: usize,
    /// Bucket b holds `pts[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    pts: Vec<Point2>,
    /// Coarse cells of four buckets a side: whether any point lies in them (a query far from every point
    /// checks 3 × 3 of these and stops).
    coarse: Vec<bool>,
    cnx: usize,
    cny: usize,
    radius: f64,
    band: f64,
}

impl<'a, 'w> LocalObstacles<'a, 'w> {
    /// The cache for queries in the box `[lo, hi]` (map frame, metres) that need obstacles within `radius`.
    pub(crate) fn new(world: &'a World<'w>, lo: Point2, hi: Point2, radius: f64) -> Self {
        let bucket = (0.25 * radius).max(world.resolution());
        let origin = Point2::new(lo.x - radius, lo.y - radius);
        let top = Point2::new(hi.x + radius, hi.y + radius);
        let nx = (((top.x - origin.x) / bucket).ceil() as usize).clamp(1, 4096);
        let ny = (((top.y - origin.y) / bucket).ceil() as usize).clamp(1, 4096);
        let mut raw: Vec<Point2> = Vec::new();
        if let Some(tree) = world.live {
            let b = Aabb::new(
                Point3::new(origin.x as f32, origin.y as f32, f32::NEG_INFINITY),
                Point3::new(top.x as f32, top.y as f32, f32::INFINITY),
            );
            raw = tree
                .within_box(&b)
                .into_iter()
                .map(|q| Point2::new(f64::from(q.x), f64::from(q.y)))
                .collect();
        }
        let key = |q: &Point2| -> usize {
            let bx = (((q.x - origin.x) / bucket).floor().max(0.0) as usize).min(nx - 1);
            let by = (((q.y - origin.y) / bucket).floor().max(0.0) as usize).min(ny - 1);
            by * nx + bx
        };
        let mut count = vec![0u32; nx * ny + 1];
        for q in &raw {
            count[key(q) + 1] += 1;
        }
        for b in 1..count.len() {
            count[b] += count[b - 1];
        }
        let (cnx, cny) = (nx.div_ceil(4), ny.div_ceil(4));
        let mut coarse = vec![false; cnx * cny];
        for by in 0..ny {
            for bx in 0..nx {
                if count[by * nx + bx + 1] > count[by * nx + bx] {
                    coarse[(by / 4) * cnx + bx / 4] = true;
                }
            }
        }
        let mut fill = count.clone();
        let mut pts = vec![Point2::origin(); raw.len()];
        for q in raw {
            let b = key(&q);
            pts[fill[b] as usize] = q;
            fill[b] += 1;
        }
        // Clamping in `key` only moves points that lie outside the box into edge buckets; queries stay a
        // radius inside it, so every point they need is in a bucket the scan visits.
        let ok = lo.x.is_finite() && lo.y.is_finite() && hi.x.is_finite() && hi.y.is_finite();
        Self {
            world,
            lo: if ok {
                lo
            } else {
                Point2::new(f64::INFINITY, f64::INFINITY)
            },
            hi: if ok {
                hi
            } else {
                Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY)
            },
            origin,
            bucket,
            nx,
            ny,
            start: count,
            pts,
            coarse,
            cnx,
            cny,
            radius,
            band: std::f64::consts::SQRT_2 * world.resolution(),
        }
    }

    /// Bucket coordinate of `v` metres from the origin (clamped to the grid).
    #[inline]
    fn coord(&self, v: f64, n: usize) -> usize {
        let q = v / self.bucket;
        // floor without a libm call (baseline x86-64 has no rounding instruction).
        let t = q as i64;
        let f = if (t as f64) > q { t - 1 } else { t };
        f.clamp(0, n as i64 - 1) as usize
    }

    /// The nearest live point within the radius: buckets in rings of growing Chebyshev distance around the
    /// query's own, stopping when a ring cannot hold anything nearer than the best so far (every bucket of
    /// ring k is at least (k − 1) bucket sides from the query).
    fn live_within(&self, p: Point2) -> Option<(Point2, f64)> {
        let b = self.bucket;
        let cx = self.coord(p.x - self.origin.x, self.nx) as isize;
        let cy = self.coord(p.y - self.origin.y, self.ny) as isize;
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        // Every point within the radius (≤ 4 buckets) lies in the 3 × 3 coarse cells around the query's.
        let (ccx, ccy) = (cx / 4, cy / 4);
        let (cnx, cny) = (self.cnx as isize, self.cny as isize);
        let mut any = false;
        for y in (ccy - 1).max(0)..=(ccy + 1).min(cny - 1) {
            for x in (ccx - 1).max(0)..=(ccx + 1).min(cnx - 1) {
                any |= self.coarse[(y * cnx + x) as usize];
            }
        }
        if !any {
            return None;
        }
        let rings = (self.radius / b).ceil() as isize + 1;
        let mut best = (Point2::origin(), self.radius * self.radius);
        let mut found = false;
        let (ox, oy) = (self.origin.x, self.origin.y);
        let mut visit = |bx: isize, by: isize, best: &mut (Point2, f64)| {
            if bx < 0 || bx >= nx {
                return;
            }
            // Skip a bucket that cannot hold anything nearer than the best so far.
            let (xlo, ylo) = (ox + bx as f64 * b, oy + by as f64 * b);
            let dx = (xlo - p.x).max(p.x - xlo - b).max(0.0);
            let dy = (ylo - p.y).max(p.y - ylo - b).max(0.0);
            if dx * dx + dy * dy >= best.1 {
                return;
            }
            let cell = (by * nx + bx) as usize;
            let (s, e) = (self.start[cell] as usize, self.start[cell + 1] as usize);
            for q in &self.pts[s..e] {
                let d2 = (q - p).norm_squared();
                if d2 < best.1 {
                    *best = (*q, d2);
                    found = true;
                }
            }
        };
        for k in 0..=rings {
            if k >= 2 {
                let gap = (k - 1) as f64 * b;
                if gap * gap >= best.1 {
                    break;
                }
            }
            for dy in -k..=k {
                let by = cy + dy;
                if by < 0 || by >= ny {
                    continue;
                }
                if dy.abs() == k {
                    for dx in -k..=k {
                        visit(cx + dx, by, &mut best);
                    }
                } else {
                    visit(cx - k, by, &mut best);
                    visit(cx + k, by, &mut best);
                }
            }
        }
        found.then(|| (best.0, best.1.sqrt()))
    }
}

impl Obstacles for LocalObstacles<'_, '_> {
    fn nearest(&self, p: Point2) -> Option<(Point2, f64)> {
        if !(p.x >= self.lo.x && p.y >= self.lo.y && p.x <= self.hi.x && p.y <= self.hi.y) {
            return self.world.nearest_obstacle(p);
        }
        // Static: one cell look-up decides whether any site can be within the radius.
        let g = self.world.field.geometry();
        let stat = match g.locate(p) {
            Some(c) if self.world.field.at(g.index(c)) >= self.radius + self.band => None,
            _ => self.world.nearest_static_fast(p),
        };
        match (stat, self.live_within(p)) {
            (Some(a), Some(b)) => Some(if b.1 < a.1 { b } else { a }),
            (a, b) => a.or(b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::correct::tests::{Site, blob, walled};

    #[test]
    fn agrees_with_the_world_within_the_radius() {
        let mut grid = walled(8.0, 6.0);
        grid.fill_disk(Point2::new(5.0, 3.0), 0.3, crate::map::CellState::Occupied);
        let mut live = blob(Point2::new(3.0, 3.0), 0.4, 0.05);
        live.push(Point2::new(0.5, 0.5));
        let site = Site::new(grid, live);
        let world = site.world();
        let radius = 0.4;
        let local = LocalObstacles::new(&world, Point2::new(1.0, 1.0), Point2::new(7.0, 5.0), radius);
        for k in 0..4000 {
            let p = Point2::new(0.2 + (k % 80) as f64 * 0.0951, 0.2 + (k / 80) as f64 * 0.1133);
            let want = world.nearest_obstacle(p);
            let got = local.nearest(p);
            match (want, got) {
                (Some((_, dw)), Some((_, dg))) => assert!((dw - dg).abs() < 1e-12 || (dw >= radius && dg >= radius)),
                (Some((_, dw)), None) => assert!(dw >= radius - 1e-12, "missed an obstacle at {dw} from {p:?}"),
                (None, Some(_)) => panic!("invented an obstacle"),
                (None, None) => {}
            }
        }
    }
}
