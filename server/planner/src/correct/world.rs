//! The obstacles a correction must keep clear of: the site's static occupancy map (through its exact distance
//! field) and, when present, the live obstacle points ([`LivePoints`]: ground plane, map-frame queries).
//!
//! Two kinds of query:
//! - fast ones for the optimiser ([`World::nearest_obstacle`], [`World::clearance_fast`]): the static part is
//!   the distance field's [`DistanceField::at_point`] (distance to a real non-free cell centre, so never
//!   below the true distance, and in practice equal to it);
//! - exact ones for judging and verification ([`World::clearance`], [`World::clear_of`]): the static part is
//!   the distance from the point to the nearest non-free cell centre, the DESIGN §6 collision metric. The
//!   field's answer is within √2 · resolution of the true distance (the nearest site of the point's own cell
//!   is at most one half-diagonal further than from the cell centre, twice), so only when it lands in that
//!   band above the distance of interest are the cells around the point scanned.

use crate::geom::Point2;
use crate::map::{DistanceField, LivePoints, OccupancyGrid};

use super::error::CorrectError;

/// How far under a requested clearance a point may be from the *static* map and still count as clear,
/// metres. Plans hug walls at exactly the robot radius (lanes and edge passes are placed on cell centres at
/// that distance), so a patch that starts and ends on such a lane must be allowed the same distance; the
/// chord-sag allowance [`super::verify`] adds between samples (half a millimetre at the usual step) would
/// otherwise reject the plan's own wall-side stretches. One millimetre is far below any occupancy map's
/// accuracy; live obstacle points get no slack.
pub const STATIC_SLACK_M: f64 = 1e-3;

/// The obstacles of one site as a correction sees them. Map frame, metres.
#[derive(Debug, Clone, Copy)]
pub struct World<'a> {
    /// The static occupancy map; non-free cells (occupied or unknown) are obstacles.
    pub grid: &'a OccupancyGrid,
    /// Exact distance field of `grid` to its non-free cells (same geometry), optionally with the map border
    /// as sites.
    pub field: &'a DistanceField,
    /// Live obstacle points, if the site has any.
    pub live: Option<LivePoints<'a>>,
}

impl<'a> World<'a> {
    /// A world after checking that `grid` and `field` share one geometry.
    pub fn new(
        grid: &'a OccupancyGrid,
        field: &'a DistanceField,
        live: Option<LivePoints<'a>>,
    ) -> Result<Self, CorrectError> {
        let w = Self { grid, field, live };
        w.check()?;
        Ok(w)
    }

    /// Checks that the grid and the field describe the same raster.
    pub fn check(&self) -> Result<(), CorrectError> {
        if *self.field.geometry() != self.grid.geometry {
            return Err(CorrectError::BadWorld(format!(
                "grid geometry {:?} differs from distance field geometry {:?}",
                self.grid.geometry,
                self.field.geometry()
            )));
        }
        Ok(())
    }

    /// Map resolution, metres per cell.
    #[inline]
    pub fn resolution(&self) -> f64 {
        self.grid.geometry.resolution
    }

    /// True when `p` lies on the map (inside a cell of the grid).
    #[inline]
    pub fn inside(&self, p: Point2) -> bool {
        self.grid.geometry.locate(p).is_some()
    }

    /// Distance from `p` to the nearest live obstacle point (metres, ground plane), with that point;
    /// `None` without a live tree, with an empty one, or for a non-finite `p`.
    #[inline]
    pub fn nearest_live(&self, p: Point2) -> Option<(Point2, f64)> {
        self.live?.nearest(p)
    }

    /// Distance from `p` to the nearest live obstacle point, metres (∞ when there is none).
    #[inline]
    pub fn live_clearance(&self, p: Point2) -> f64 {
        self.nearest_live(p).map_or(f64::INFINITY, |(_, d)| d)
    }

    /// [`Self::live_clearance`] where it is below `upto`; otherwise some value ≥ `upto` that is never above
    /// it (see [`LivePoints::nearest_upto`]).
    #[inline]
    pub fn live_clearance_upto(&self, p: Point2, upto: f64) -> f64 {
        self.live
            .and_then(|l| l.nearest_upto(p, upto))
            .map_or(f64::INFINITY, |(_, d)| d)
    }

    /// The nearest static site (non-free cell centre, or the border ring when the field has one) as the
    /// distance field sees it, with its distance (metres). Never nearer than the true nearest site.
    #[inline]
    pub fn nearest_static_fast(&self, p: Point2) -> Option<(Point2, f64)> {
        // The field's own geometry indexes the field (so a world built without `new` cannot index out of it).
        let g = self.field.geometry();
        let (cx, cy) = g.to_cell_coords(p);
        if !(cx.is_finite() && cy.is_finite()) {
            return None;
        }
        let (w, h) = (g.width as isize, g.height as isize);
        let (ix, iy) = (cx.floor() as isize, cy.floor() as isize);
        if self.field.border_is_site() && (ix < 0 || iy < 0 || ix >= w || iy >= h) {
            // Off the map with the border as a wall: the point is inside an obstacle.
            return Some((p, 0.0));
        }
        let mut best: Option<(Point2, f64)> = None;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (x, y) = (ix + dx, iy + dy);
                if x < 0 || y < 0 || x >= w || y >= h {
                    continue;
                }
                if let Some(s) = self.field.nearest_site((y * w + x) as usize) {
                    let d = (s - p).norm();
                    if best.is_none_or(|(_, b)| d < b) {
                        best = Some((s, d));
                    }
                }
            }
        }
        best
    }

    /// The nearest obstacle (static site or live point) for the optimiser's gradient, with its distance,
    /// metres. `None` when the world has no obstacle at all.
    #[inline]
    pub fn nearest_obstacle(&self, p: Point2) -> Option<(Point2, f64)> {
        match (self.nearest_static_fast(p), self.nearest_live(p)) {
            (Some(a), Some(b)) => Some(if b.1 < a.1 { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// Clearance for the optimiser: min of the field's static distance and the live distance, metres.
    #[inline]
    pub fn clearance_fast(&self, p: Point2) -> f64 {
        self.nearest_obstacle(p).map_or(f64::INFINITY, |(_, d)| d)
    }

    /// Exact distance from `p` to the nearest non-free cell centre (and border ring cell centre when the
    /// field has the border as sites), whenever that distance is below `upto` metres; otherwise some value
    /// ≥ `upto`. Off the map with a border field: 0.
    pub fn static_clearance_upto(&self, p: Point2, upto: f64) -> f64 {
        let fast = self.nearest_static_fast(p).map_or(f64::INFINITY, |(_, d)| d);
        let band = std::f64::consts::SQRT_2 * self.resolution();
        if fast >= upto + band || fast <= 0.0 {
            return fast;
        }
        // Scan every cell centre within `fast` of p: the true nearest site is among them.
        let g = &self.grid.geometry;
        let r = g.resolution;
        let (cx, cy) = g.to_cell_coords(p);
        let reach = fast / r;
        let (x0, x1) = ((cx - reach - 0.5).floor() as isize, (cx + reach - 0.5).ceil() as isize);
        let (y0, y1) = ((cy - reach - 0.5).floor() as isize, (cy + reach - 0.5).ceil() as isize);
        let (w, h) = (g.width as isize, g.height as isize);
        let border = self.field.border_is_site();
        let mut best2 = fast * fast;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let on_map = x >= 0 && y >= 0 && x < w && y < h;
                let site = if on_map {
                    !self.grid.is_free((y * w + x) as usize)
                } else {
                    border && x >= -1 && y >= -1 && x <= w && y <= h
                };
                if !site {
                    continue;
                }
                let c = Point2::new(g.origin.x + (x as f64 + 0.5) * r, g.origin.y + (y as f64 + 0.5) * r);
                best2 = best2.min((c - p).norm_squared());
            }
        }
        best2.sqrt()
    }

    /// A guaranteed lower bound of the clearance of `p`, metres: the field's static distance less the √2 ·
    /// resolution band, and the live distance. Cheap (no scan).
    #[inline]
    pub fn clearance_lower_bound(&self, p: Point2) -> f64 {
        let fast = self.nearest_static_fast(p).map_or(f64::INFINITY, |(_, d)| d);
        let band = std::f64::consts::SQRT_2 * self.resolution();
        // Any cheap lower bound will do for the live part too.
        (fast - band).max(0.0).min(self.live_clearance_upto(p, 0.0))
    }

    /// Exact clearance of `p` (metres) whenever it is below `upto`: min of the exact static distance and the
    /// live distance. Values ≥ `upto` are only known to be ≥ `upto`.
    #[inline]
    pub fn clearance_upto(&self, p: Point2, upto: f64) -> f64 {
        self.static_clearance_upto(p, upto)
            .min(self.live_clearance_upto(p, upto))
    }

    /// True when `p` is on the map, at least `radius_m` from every live obstacle point, and at least
    /// `radius_m −` [`STATIC_SLACK_M`] from every non-free cell centre (DESIGN §6).
    #[inline]
    pub fn clear_of(&self, p: Point2, radius_m: f64) -> bool {
        self.inside(p)
            && self.live_clearance_upto(p, radius_m) >= radius_m
            && self.static_clearance_upto(p, radius_m) >= radius_m - STATIC_SLACK_M
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::ikd_tree::Point3;
    use crate::map::{CellState, GridGeometry, IkdParams, IkdTree};

    fn brute_static(grid: &OccupancyGrid, p: Point2) -> f64 {
        (0..grid.geometry.len())
            .filter(|&i| !grid.is_free(i))
            .map(|i| (grid.geometry.center_of(i) - p).norm())
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn exact_static_clearance_matches_brute_force() {
        let g = GridGeometry::new(40, 30, 0.05, Point2::new(0.3, -0.2)).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_disk(Point2::new(1.0, 0.5), 0.12, CellState::Occupied);
        grid.fill_rect(1.6, -0.2, 1.65, 0.6, CellState::Unknown);
        grid.set(crate::map::Cell::new(3, 25), CellState::Occupied);
        let field = DistanceField::compute(g, |i| !grid.is_free(i), false);
        let world = World::new(&grid, &field, None).expect("consistent");
        let mut s = 12345u64;
        for _ in 0..3000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let x = 0.3 + (s % 10_000) as f64 / 10_000.0 * 2.0;
            let y = -0.2 + ((s / 10_000) % 10_000) as f64 / 10_000.0 * 1.5;
            let p = Point2::new(x, y);
            let want = brute_static(&grid, p);
            let got = world.static_clearance_upto(p, 0.4);
            if want < 0.4 {
                assert!((got - want).abs() < 1e-12, "at {p:?}: got {got} want {want}");
            } else {
                assert!(got >= 0.4 - 1e-12);
            }
            assert!(world.clearance_fast(p) >= want - 1e-12);
        }
    }

    #[test]
    fn live_points_count() {
        let g = GridGeometry::new(40, 40, 0.05, Point2::origin()).expect("valid");
        let grid = OccupancyGrid::filled(g, CellState::Free);
        let field = DistanceField::compute(g, |i| !grid.is_free(i), false);
        let mut tree = IkdTree::new(IkdParams::default()).expect("params");
        tree.build(&[Point3::new(1.0, 1.0, 0.0)]);
        let world = World::new(&grid, &field, Some(LivePoints::new(&tree, Point2::origin()))).expect("consistent");
        let p = Point2::new(1.3, 1.4);
        assert!((world.clearance_upto(p, 1.0) - 0.5).abs() < 1e-6);
        let (q, d) = world.nearest_obstacle(p).expect("an obstacle");
        assert!((q - Point2::new(1.0, 1.0)).norm() < 1e-6 && (d - 0.5).abs() < 1e-6);
        assert!(world.clear_of(p, 0.49) && !world.clear_of(p, 0.51));
        assert!(!world.clear_of(Point2::new(-0.1, 1.0), 0.1));
    }
}
