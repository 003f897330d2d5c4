//! A window-sized cache of the obstacles for the optimiser: the live points near the window copied out of
//! the site's tree once, sorted into a uniform grid of buckets (row-major, a quarter of the query radius a
//! side), so the many nearest-obstacle queries of an optimisation scan a few contiguous runs of points
//! instead of descending a tree of the whole site.
//!
//! Exact where it answers: for a query inside the cached region (shrunk by the query radius) it returns the
//! nearest obstacle point whenever one lies within `radius` metres (static sites through the distance field,
//! live points from the buckets), and `None` when none does; outside that region it asks the [`World`].
//!
//! A live query first asks a summed-area table of the bucket counts whether the square of side 2·radius
//! around it holds any point (most queries of a window lie far from every point and stop there). Otherwise
//! it scans the query's own bucket, then the bucket rows outward from its own, each row over the buckets
//! that the circle of the best distance so far spans: points sorted row-major make that span one contiguous
//! slice. A row whose band lies at least the best distance away ends the scan in its direction.
//!
//! Live points read as voxels ([`crate::map::LivePoints::voxels`]) are held as their squares' lower corners,
//! and distances go to the squares; every bound above is widened by the square's diagonal.

use crate::geom::Point2;

use super::cost::Obstacles;
use super::world::World;

/// Most buckets a side, and in all, of one cache (bounded memory whatever the box; larger boxes get larger
/// buckets).
const MAX_SIDE: f64 = 4096.0;
const MAX_BUCKETS: f64 = (1u32 << 20) as f64;

/// Widening of every bucket range a query computes, metres: covers the rounding of the key arithmetic, so a
/// point nearer than the best distance is never left out of a scanned range.
const SLACK_M: f64 = 1e-6;

/// Live points of a box in buckets, with the world as fallback.
pub(crate) struct LocalObstacles<'a, 'w> {
    world: &'a World<'w>,
    /// Queries within [lo, hi] are answered from the buckets.
    lo: Point2,
    hi: Point2,
    /// Lower corner of bucket (0, 0); the buckets cover [lo − radius, hi + radius].
    origin: Point2,
    bucket: f64,
    nx: usize,
    ny: usize,
    /// Bucket b = y·nx + x holds `pts[start[b]..start[b + 1]]`, so buckets x0..=x1 of row y hold
    /// `pts[start[y·nx + x0]..start[y·nx + x1 + 1]]`.
    start: Vec<u32>,
    pts: Vec<Point2>,
    /// Side of the square each of `pts` is the lower corner of, metres (0: points).
    voxel: f64,
    /// How much nearer than its corner a square can come: its diagonal.
    reach: f64,
    /// Summed-area table of the bucket counts: `sat[y·(nx+1) + x]` points lie in buckets [0, x) × [0, y).
    sat: Vec<u32>,
    radius: f64,
    band: f64,
}

impl<'a, 'w> LocalObstacles<'a, 'w> {
    /// The cache for queries in the box `[lo, hi]` (map frame, metres) that need obstacles within `radius`.
    pub(crate) fn new(world: &'a World<'w>, lo: Point2, hi: Point2, radius: f64) -> Self {
        let ok = lo.x.is_finite()
            && lo.y.is_finite()
            && hi.x.is_finite()
            && hi.y.is_finite()
            && radius.is_finite()
            && lo.x <= hi.x
            && lo.y <= hi.y;
        let origin = Point2::new(lo.x - radius, lo.y - radius);
        let top = Point2::new(hi.x + radius, hi.y + radius);
        let (ex, ey) = if ok {
            (top.x - origin.x, top.y - origin.y)
        } else {
            (0.0, 0.0)
        };
        let bucket = (0.25 * radius)
            .max(world.resolution())
            .max(ex / MAX_SIDE)
            .max(ey / MAX_SIDE)
            .max((ex * ey / MAX_BUCKETS).sqrt());
        let nx = ((ex / bucket).ceil() as usize).max(1);
        let ny = ((ey / bucket).ceil() as usize).max(1);
        let mut raw: Vec<Point2> = Vec::new();
        let (voxel, reach) = world.live.map_or((0.0, 0.0), |l| (l.voxel_m.max(0.0), l.reach_m()));
        if ok && let Some(live) = world.live {
            // Areas outside the buckets' extent are at least `radius` from every query the buckets answer,
            // and the clamping of `key` puts them in an edge bucket.
            let grow = Point2::new(reach, reach);
            raw = live.within(origin - grow.coords, top + grow.coords);
            for q in &mut raw {
                *q = live.voxel_corner_map(*q);
            }
        }
        let mut me = Self {
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
            start: Vec::new(),
            pts: Vec::new(),
            sat: Vec::new(),
            voxel,
            reach,
            radius,
            band: std::f64::consts::SQRT_2 * world.resolution(),
        };
        // Counting sort by bucket.
        let keys: Vec<u32> = raw.iter().map(|q| (me.row(q.y) * nx + me.col(q.x)) as u32).collect();
        let mut start = vec![0u32; nx * ny + 1];
        for &k in &keys {
            start[k as usize + 1] += 1;
        }
        for b in 1..start.len() {
            start[b] += start[b - 1];
        }
        let mut fill = start.clone();
        let mut pts = vec![Point2::origin(); raw.len()];
        for (q, &k) in raw.iter().zip(&keys) {
            pts[fill[k as usize] as usize] = *q;
            fill[k as usize] += 1;
        }
        let w = nx + 1;
        let mut sat = vec![0u32; w * (ny + 1)];
        for y in 0..ny {
            let mut row_sum = 0u32;
            for x in 0..nx {
                let b = y * nx + x;
                row_sum += start[b + 1] - start[b];
                sat[(y + 1) * w + x + 1] = sat[y * w + x + 1] + row_sum;
            }
        }
        me.start = start;
        me.pts = pts;
        me.sat = sat;
        me
    }

    /// Bucket column of map-frame x, clamped to the grid. Truncation is the floor here: a negative quotient
    /// clamps to 0 either way (and NaN gives 0).
    #[inline]
    fn col(&self, x: f64) -> usize {
        (((x - self.origin.x) / self.bucket) as i64).clamp(0, self.nx as i64 - 1) as usize
    }

    /// Bucket row of map-frame y, clamped to the grid.
    #[inline]
    fn row(&self, y: f64) -> usize {
        (((y - self.origin.y) / self.bucket) as i64).clamp(0, self.ny as i64 - 1) as usize
    }

    /// Points in buckets [x0, x1] × [y0, y1] (inclusive).
    #[inline]
    fn count(&self, x0: usize, x1: usize, y0: usize, y1: usize) -> u32 {
        let w = self.nx + 1;
        self.sat[(y1 + 1) * w + x1 + 1] + self.sat[y0 * w + x0]
            - self.sat[y0 * w + x1 + 1]
            - self.sat[(y1 + 1) * w + x0]
    }

    /// Scans buckets x0..=x1 of row y for a point nearer to `p` than `best` (squared distance).
    #[inline]
    fn scan(&self, y: usize, x0: usize, x1: usize, p: Point2, best: &mut (Point2, f64), found: &mut bool) {
        let row = y * self.nx;
        let (s, e) = (self.start[row + x0] as usize, self.start[row + x1 + 1] as usize);
        let v = self.voxel;
        for q in &self.pts[s..e] {
            let on = Point2::new(p.x.clamp(q.x, q.x + v), p.y.clamp(q.y, q.y + v));
            let d2 = (on - p).norm_squared();
            if d2 < best.1 {
                *best = (on, d2);
                *found = true;
            }
        }
    }

    /// Scans row y over the buckets within the best distance of `p`, the row's band lying `gap` metres
    /// from `p` (0 for the query's own row).
    #[inline]
    fn scan_row(&self, y: usize, gap: f64, p: Point2, best: &mut (Point2, f64), found: &mut bool) {
        // Every corner of the row whose square is nearer than the best has |x − p.x| < √(best − gap²) + reach
        // (the callers' gap is already less the reach).
        let half = (best.1 - gap * gap).max(0.0).sqrt() + SLACK_M + self.reach;
        self.scan(y, self.col(p.x - half), self.col(p.x + half), p, best, found);
    }

    /// The nearest live point within the radius (see the module docs), with its distance.
    fn live_within(&self, p: Point2) -> Option<(Point2, f64)> {
        let r = self.radius + SLACK_M + self.reach;
        let (x0, x1) = (self.col(p.x - r), self.col(p.x + r));
        let (y0, y1) = (self.row(p.y - r), self.row(p.y + r));
        if self.count(x0, x1, y0, y1) == 0 {
            return None;
        }
        let mut best = (Point2::origin(), self.radius * self.radius);
        let mut found = false;
        let (cx, cy) = (self.col(p.x), self.row(p.y));
        // The own bucket first: inside a cluster it holds a near point, which narrows every row after it.
        self.scan(cy, cx, cx, p, &mut best, &mut found);
        self.scan_row(cy, 0.0, p, &mut best, &mut found);
        let (b, oy) = (self.bucket, self.origin.y);
        let (mut down, mut up) = (cy > y0, cy < y1);
        let mut k = 1;
        while down || up {
            if up {
                let y = cy + k;
                // The band of row y starts at oy + y·b, above p.
                let gap = (oy + y as f64 * b - p.y - SLACK_M - self.reach).max(0.0);
                if y > y1 || gap * gap >= best.1 {
                    up = false;
                } else {
                    self.scan_row(y, gap, p, &mut best, &mut found);
                }
            }
            if down {
                if k > cy {
                    down = false;
                } else {
                    let y = cy - k;
                    // The band of row y ends at oy + (y + 1)·b, below p.
                    let gap = (p.y - (oy + (y + 1) as f64 * b) - SLACK_M - self.reach).max(0.0);
                    if y < y0 || gap * gap >= best.1 {
                        down = false;
                    } else {
                        self.scan_row(y, gap, p, &mut best, &mut found);
                    }
                }
            }
            k += 1;
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
    use crate::map::ikd_tree::{Aabb, Point3};

    /// The nearest live point of `p` by brute force over the tree's points, with its distance.
    fn brute(site: &Site, p: Point2) -> Option<f64> {
        site.tree
            .within_box(&Aabb::new(
                Point3::new(f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY),
                Point3::new(f32::INFINITY, f32::INFINITY, f32::INFINITY),
            ))
            .into_iter()
            .map(|q| (Point2::new(f64::from(q.x), f64::from(q.y)) - p).norm())
            .min_by(f64::total_cmp)
    }

    /// Checks the cache against the world and brute force at a lattice of queries over [a, b].
    fn check(site: &Site, lo: Point2, hi: Point2, radius: f64, a: Point2, b: Point2) -> usize {
        let world = site.world();
        let local = LocalObstacles::new(&world, lo, hi, radius);
        let mut near = 0;
        for k in 0..6400 {
            let p = Point2::new(
                a.x + (b.x - a.x) * f64::from(k % 80) / 79.0 + 1e-4 * f64::from(k % 7),
                a.y + (b.y - a.y) * f64::from(k / 80) / 79.0,
            );
            let want = world.nearest_obstacle(p);
            let got = local.nearest(p);
            match (want, got) {
                (Some((_, dw)), Some((q, dg))) => {
                    assert!(
                        (dw - dg).abs() < 1e-12 || (dw >= radius && dg >= radius),
                        "at {p:?}: world {dw}, cache {dg}"
                    );
                    assert!(
                        ((q - p).norm() - dg).abs() < 1e-12,
                        "the point returned lies at its distance"
                    );
                }
                (Some((_, dw)), None) => assert!(dw >= radius - 1e-12, "missed an obstacle at {dw} from {p:?}"),
                (None, Some(_)) => panic!("invented an obstacle"),
                (None, None) => {}
            }
            // The live part is the exact nearest of all points whenever within the radius.
            let inside = p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y;
            if inside && let Some(d) = brute(site, p).filter(|&d| d < radius) {
                near += 1;
                let (_, dl) = local.live_within(p).expect("a live point within the radius");
                assert_eq!(dl, d, "live nearest at {p:?}");
            } else if inside {
                assert!(
                    local.live_within(p).is_none(),
                    "a live point beyond the radius at {p:?}"
                );
            }
        }
        near
    }

    #[test]
    fn agrees_with_the_world_within_the_radius() {
        let mut grid = walled(8.0, 6.0);
        grid.fill_disk(Point2::new(5.0, 3.0), 0.3, crate::map::CellState::Occupied);
        let mut live = blob(Point2::new(3.0, 3.0), 0.4, 0.05);
        live.extend(blob(Point2::new(6.2, 1.6), 0.15, 0.02));
        live.push(Point2::new(0.5, 0.5));
        live.push(Point2::new(1.05, 4.95));
        let site = Site::new(grid, live);
        let (lo, hi) = (Point2::new(1.0, 1.0), Point2::new(7.0, 5.0));
        // Over the whole map (queries outside [lo, hi] go to the world) and zoomed on the dense blob.
        let near = check(&site, lo, hi, 0.4, Point2::new(0.2, 0.2), Point2::new(7.8, 5.8));
        assert!(near > 300, "only {near} queries had a live point near");
        check(&site, lo, hi, 0.4, Point2::new(2.4, 2.4), Point2::new(3.6, 3.6));
        // A tiny cache (one bucket) and a thin one.
        check(
            &site,
            Point2::new(2.9, 2.9),
            Point2::new(3.0, 3.0),
            0.1,
            Point2::new(2.7, 2.7),
            Point2::new(3.2, 3.2),
        );
        check(
            &site,
            Point2::new(1.0, 3.0),
            Point2::new(7.0, 3.0),
            0.35,
            Point2::new(0.8, 2.6),
            Point2::new(7.2, 3.4),
        );
    }

    /// Seeded clusters of live points on a 10 × 8 m site: `clusters` of them, each of `points` points spread
    /// over a random disc.
    fn clusters(
        rng: &mut rand_chacha::ChaCha8Rng,
        clusters: std::ops::Range<i32>,
        points: std::ops::Range<i32>,
    ) -> Vec<Point2> {
        use rand::Rng;
        let mut live = Vec::new();
        for _ in 0..rng.random_range(clusters) {
            let c = Point2::new(rng.random_range(1.0..9.0), rng.random_range(1.0..7.0));
            let spread = rng.random_range(0.01..1.0);
            for _ in 0..rng.random_range(points.clone()) {
                let (a, r) = (
                    rng.random_range(0.0..std::f64::consts::TAU),
                    spread * rng.random::<f64>().sqrt(),
                );
                live.push(c + nalgebra::Vector2::new(r * a.cos(), r * a.sin()));
            }
        }
        live
    }

    /// A seeded query box `[lo, hi]` and radius for a cache on that site.
    fn query_box(rng: &mut rand_chacha::ChaCha8Rng) -> (Point2, Point2, f64) {
        use rand::Rng;
        let lo = Point2::new(rng.random_range(0.5..4.0), rng.random_range(0.5..3.0));
        let hi = lo + nalgebra::Vector2::new(rng.random_range(0.0..5.0), rng.random_range(0.0..4.0));
        (lo, hi, rng.random_range(0.05..0.8))
    }

    #[test]
    fn matches_brute_force_on_seeded_random_clouds() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x10ca1);
        for _ in 0..12 {
            let site = Site::new(walled(10.0, 8.0), clusters(&mut rng, 1..5, 1..400));
            let world = site.world();
            let (lo, hi, radius) = query_box(&mut rng);
            let local = LocalObstacles::new(&world, lo, hi, radius);
            for _ in 0..1500 {
                let p = Point2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
                let want = brute(&site, p).filter(|&d| d < radius);
                assert_eq!(local.live_within(p).map(|(_, d)| d), want, "at {p:?}, radius {radius}");
            }
        }
    }

    /// The nearest voxel square of `p` by brute force (squares of the tree's voxel size on its points).
    fn brute_squares(site: &Site, p: Point2) -> Option<f64> {
        let v = f64::from(site.tree.params().voxel_size);
        site.live
            .iter()
            .map(|q| {
                let (x0, y0) = ((q.x / v).floor() * v, (q.y / v).floor() * v);
                (Point2::new(p.x.clamp(x0, x0 + v), p.y.clamp(y0, y0 + v)) - p).norm()
            })
            .min_by(f64::total_cmp)
    }

    /// Read as voxels, the cache measures to the squares: equal to brute force within the radius, never above
    /// the distance to the point itself, and the same answer as the world's tree query.
    #[test]
    fn read_as_voxels_matches_brute_force_over_the_squares() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x5a1e);
        for _ in 0..10 {
            let site = Site::new(walled(10.0, 8.0), clusters(&mut rng, 1..4, 1..200));
            let world = site.world_as_voxels();
            let (lo, hi, radius) = query_box(&mut rng);
            let local = LocalObstacles::new(&world, lo, hi, radius);
            for _ in 0..1000 {
                let p = Point2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
                let want = brute_squares(&site, p);
                let got = local.live_within(p);
                match (want.filter(|&d| d < radius), got) {
                    (Some(w), Some((q, d))) => {
                        assert!((w - d).abs() < 1e-9, "at {p:?}: brute {w}, cache {d}");
                        assert!(((q - p).norm() - d).abs() < 1e-12);
                    }
                    (None, None) => {}
                    (w, g) => panic!("at {p:?}, radius {radius}: brute {w:?}, cache {g:?}"),
                }
                let tree = world.nearest_live(p).map(|(_, d)| d);
                assert!(
                    (tree.expect("points") - want.expect("points")).abs() < 1e-9,
                    "tree query at {p:?}"
                );
                let points = brute(&site, p).expect("points");
                assert!(want.expect("points") <= points + 1e-12);
            }
        }
    }

    #[test]
    fn a_huge_box_gets_larger_buckets_and_stays_exact() {
        let grid = walled(8.0, 6.0);
        let site = Site::new(grid, blob(Point2::new(3.0, 3.0), 0.4, 0.05));
        let world = site.world();
        let local = LocalObstacles::new(&world, Point2::new(-5e3, -5e3), Point2::new(5e3, 5e3), 0.4);
        assert!(local.nx as f64 <= MAX_SIDE + 1.0 && (local.nx * local.ny) as f64 <= 1.01 * MAX_BUCKETS);
        for p in [
            Point2::new(3.0, 3.5),
            Point2::new(3.3, 3.3),
            Point2::new(2.0, 3.0),
            Point2::new(3.0, 3.0),
        ] {
            let want = brute(&site, p).filter(|&d| d < 0.4);
            assert_eq!(local.live_within(p).map(|(_, d)| d), want, "at {p:?}");
        }
        // A non-finite box answers everything from the world.
        let local = LocalObstacles::new(&world, Point2::new(f64::NAN, 0.0), Point2::new(1.0, 1.0), 0.4);
        let p = Point2::new(3.0, 3.5);
        assert_eq!(local.nearest(p), world.nearest_obstacle(p));
    }
}
