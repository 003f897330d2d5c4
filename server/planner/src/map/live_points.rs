//! A site's live obstacle points as the planner reads them: an ikd-tree of points in the ground plane (z = 0),
//! stored relative to a local origin.
//!
//! Why an origin: the tree holds `f32` coordinates, which keep about 7 significant digits. A georeferenced site
//! (UTM northings near 5 · 10⁶ m, a LiDAR tile in state-plane feet) would lose 0.06–0.5 m to rounding, more than
//! a robot's clearance margin. Relative to the site's corner, points keep sub-millimetre precision over any
//! site up to tens of kilometres, and every query here takes and returns map-frame `f64` coordinates.
//!
//! Why z = 0: obstacle points are 2-D for coverage and corrections (a robot's disc or footprint in the ground
//! plane), and a 3-D nearest-point query from the ground would rank a point 1.5 m up and 0.1 m away behind one
//! on the floor 1 m away. The live map applies the height band before projecting (see `shift_engine::live_map`).
//!
//! Why voxels ([`LivePoints::voxels`]): the live map keeps one point per voxel (the return nearest the voxel's
//! centre), so the returns it folded into that point lie anywhere in the voxel, up to a voxel diagonal nearer a
//! path than the point kept. Read as voxels, a kept point stands for its whole voxel square and distances are
//! measured to the square: never more than the distance to any return the voxel took in, so a path that keeps
//! the radius from the squares keeps it from every return the robots saw (7 cm of slack at 5 cm voxels, which
//! the point reading would give away). [`LivePoints::new`] reads the points as points (trees that are not
//! downsampled, tests).

use super::ikd_tree::{Aabb, IkdTree, Point3};
use crate::geom::Point2;

/// Read access to live obstacle points: the tree and the map-frame position of its local origin.
#[derive(Debug, Clone, Copy)]
pub struct LivePoints<'a> {
    /// Points at `(x − origin.x, y − origin.y, 0)`.
    pub tree: &'a IkdTree,
    /// Map-frame position of the tree's (0, 0), metres.
    pub origin: Point2,
    /// Side of the voxel square each point stands for, metres; 0 reads points as points.
    pub voxel_m: f64,
}

impl<'a> LivePoints<'a> {
    /// Points of `tree` stored relative to `origin`.
    pub fn new(tree: &'a IkdTree, origin: Point2) -> Self {
        Self {
            tree,
            origin,
            voxel_m: 0.0,
        }
    }

    /// Points of a downsampled `tree` stored relative to `origin`, each standing for its voxel's square (the
    /// tree's `voxel_size`; see the module docs).
    pub fn voxels(tree: &'a IkdTree, origin: Point2) -> Self {
        Self {
            tree,
            origin,
            voxel_m: f64::from(tree.params().voxel_size),
        }
    }

    /// A map-frame point in the tree's frame (z = 0).
    #[inline]
    pub fn to_local(origin: Point2, p: Point2) -> Point3 {
        Point3::new((p.x - origin.x) as f32, (p.y - origin.y) as f32, 0.0)
    }

    /// A tree point in the map frame.
    #[inline]
    pub fn to_map(&self, q: &Point3) -> Point2 {
        Point2::new(self.origin.x + f64::from(q.x), self.origin.y + f64::from(q.y))
    }

    /// The obstacle point nearest to `p` (map frame) with its distance, metres; `None` when empty or `p` is not
    /// finite. Read as voxels, the nearest point of the nearest voxel square (`p` itself, at distance 0, inside
    /// one).
    #[inline]
    pub fn nearest(&self, p: Point2) -> Option<(Point2, f64)> {
        self.nearest_upto(p, f64::INFINITY)
    }

    /// [`Self::nearest`] where the distance is below `upto`; otherwise a distance that is at least `upto` and
    /// never above the true one (read as voxels, the nearest point's distance less a voxel diagonal, with that
    /// point's square's nearest point), which spares the search of the squares round it.
    #[inline]
    pub fn nearest_upto(&self, p: Point2, upto: f64) -> Option<(Point2, f64)> {
        let local = Self::to_local(self.origin, p);
        let (q, _) = self.tree.nearest_point(&local)?;
        if self.voxel_m <= 0.0 {
            let q = self.to_map(&q);
            return Some((q, (q - p).norm()));
        }
        let first = self.nearest_on(&q, p);
        let bound = (self.to_map(&q) - p).norm() - self.reach_m();
        if bound >= upto {
            return Some((first, bound));
        }
        let d0 = (first - p).norm();
        // A square nearer than d0 holds its point, so that point is within d0 + a diagonal of `p`.
        let reach = (d0 + self.reach_m()) as f32 + 1e-4;
        let bx = Aabb::new(
            Point3::new(local.x - reach, local.y - reach, f32::NEG_INFINITY),
            Point3::new(local.x + reach, local.y + reach, f32::INFINITY),
        );
        let best = self
            .tree
            .within_box(&bx)
            .iter()
            .map(|q| {
                let on = self.nearest_on(q, p);
                (on, (on - p).norm())
            })
            .fold((first, d0), |a, b| if b.1 < a.1 { b } else { a });
        Some(best)
    }

    /// The point nearest to `p` (map frame) of the area the tree point `q` stands for: `q` itself, or read as
    /// voxels the nearest point of its voxel square (`p` when inside).
    #[inline]
    pub fn nearest_on(&self, q: &Point3, p: Point2) -> Point2 {
        if self.voxel_m <= 0.0 {
            return self.to_map(q);
        }
        let (c, v) = (self.voxel_corner(q), self.voxel_m);
        Point2::new(p.x.clamp(c.x, c.x + v), p.y.clamp(c.y, c.y + v))
    }

    /// Lower corner (map frame) of the voxel square of tree point `q` (`q` itself when points are points).
    #[inline]
    pub fn voxel_corner(&self, q: &Point3) -> Point2 {
        let v = self.voxel_m;
        if v <= 0.0 {
            return self.to_map(q);
        }
        // The tree's key: floor(c / voxel_size) on its own (local, f32) coordinates.
        let lo = |c: f32, o: f64| o + (f64::from(c) / v).floor() * v;
        Point2::new(lo(q.x, self.origin.x), lo(q.y, self.origin.y))
    }

    /// [`Self::voxel_corner`] of a map-frame point that [`Self::within`] returned.
    #[inline]
    pub fn voxel_corner_map(&self, q: Point2) -> Point2 {
        // Back to the tree's f32: the map-frame f64 is origin + f32, so the cast recovers the stored value.
        self.voxel_corner(&Self::to_local(self.origin, q))
    }

    /// How much nearer than its point the area a point stands for can come, metres: a voxel's diagonal, or 0.
    #[inline]
    pub fn reach_m(&self) -> f64 {
        std::f64::consts::SQRT_2 * self.voxel_m.max(0.0)
    }

    /// Every point in the map-frame box `[lo, hi]` (closed), in the map frame. The box is grown by a
    /// millimetre before the `f32` query so rounding never cuts off a point of the `f64` box; callers that need
    /// the exact box filter again.
    pub fn within(&self, lo: Point2, hi: Point2) -> Vec<Point2> {
        const GROW: f64 = 1e-3;
        let a = Self::to_local(self.origin, Point2::new(lo.x - GROW, lo.y - GROW));
        let b = Self::to_local(self.origin, Point2::new(hi.x + GROW, hi.y + GROW));
        let bx = Aabb::new(
            Point3::new(a.x, a.y, f32::NEG_INFINITY),
            Point3::new(b.x, b.y, f32::INFINITY),
        );
        self.tree.within_box(&bx).iter().map(|q| self.to_map(q)).collect()
    }

    /// Every point, in the map frame.
    pub fn all(&self) -> Vec<Point2> {
        self.tree.flatten().iter().map(|q| self.to_map(q)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::IkdParams;

    /// At UTM magnitudes an f32 map-frame coordinate is off by up to 0.25 m; relative to the site's corner the
    /// tree keeps the points to well under a millimetre, and queries answer in the map frame.
    #[test]
    fn utm_sized_coordinates_keep_millimetres() {
        let origin = Point2::new(512_300.0, 5_123_400.0);
        let pts: Vec<Point2> = (0..50)
            .map(|i| Point2::new(origin.x + 37.123 + 0.05 * f64::from(i), origin.y + 81.457))
            .collect();
        assert!(
            ((pts[0].y as f32) as f64 - pts[0].y).abs() > 0.01,
            "f32 alone loses the centimetres"
        );
        let mut tree = IkdTree::new(IkdParams::default()).expect("params");
        let local: Vec<Point3> = pts.iter().map(|&p| LivePoints::to_local(origin, p)).collect();
        tree.add_points(&local, false);
        let live = LivePoints::new(&tree, origin);
        let q = Point2::new(pts[7].x + 0.001, pts[7].y - 0.3);
        let (near, d) = live.nearest(q).expect("a point");
        assert!((near - pts[7]).norm() < 1e-3, "{near:?} for {:?}", pts[7]);
        assert!((d - (q - pts[7]).norm()).abs() < 1e-3);
        // The box is in the map frame, and brute force over the input agrees.
        let (lo, hi) = (
            Point2::new(pts[10].x, pts[0].y - 1.0),
            Point2::new(pts[20].x, pts[0].y + 1.0),
        );
        let mut got: Vec<Point2> = live
            .within(lo, hi)
            .into_iter()
            .filter(|p| p.x >= lo.x - 1e-4 && p.x <= hi.x + 1e-4)
            .collect();
        got.sort_by(|a, b| a.x.total_cmp(&b.x));
        let want: Vec<Point2> = pts
            .iter()
            .copied()
            .filter(|p| p.x >= lo.x - 1e-4 && p.x <= hi.x + 1e-4)
            .collect();
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(&want) {
            assert!((*g - *w).norm() < 1e-3);
        }
        assert_eq!(live.all().len(), 50);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// Read as voxels at a UTM-sized origin, the nearest distance is the brute-force nearest voxel square of
        /// the points kept, and never above the distance to any return the downsampled tree took in.
        #[test]
        fn read_as_voxels_never_farther_than_a_return(
            returns in proptest::collection::vec((0.0f64..4.0, 0.0f64..3.0), 1..120),
            queries in proptest::collection::vec((-1.0f64..5.0, -1.0f64..4.0), 1..40),
        ) {
            let origin = Point2::new(512_300.0, 5_123_400.0);
            let vs = 0.05f32;
            let mut tree = IkdTree::new(IkdParams { voxel_size: vs, ..IkdParams::default() }).expect("params");
            let raw: Vec<Point2> = returns.iter().map(|&(x, y)| Point2::new(origin.x + x, origin.y + y)).collect();
            let local: Vec<Point3> = raw.iter().map(|&p| LivePoints::to_local(origin, p)).collect();
            tree.add_points(&local, true);
            let live = LivePoints::voxels(&tree, origin);
            let v = f64::from(vs);
            let squares: Vec<Point2> = tree
                .flatten()
                .iter()
                .map(|q| {
                    let c = |a: f32, o: f64| o + (f64::from(a) / v).floor() * v;
                    Point2::new(c(q.x, origin.x), c(q.y, origin.y))
                })
                .collect();
            for &(x, y) in &queries {
                let p = Point2::new(origin.x + x, origin.y + y);
                let (on, d) = live.nearest(p).expect("points");
                let want = squares
                    .iter()
                    .map(|c| (Point2::new(p.x.clamp(c.x, c.x + v), p.y.clamp(c.y, c.y + v)) - p).norm())
                    .fold(f64::INFINITY, f64::min);
                proptest::prop_assert!((d - want).abs() < 1e-6, "at {:?}: {} against brute {}", p, d, want);
                proptest::prop_assert!(((on - p).norm() - d).abs() < 1e-9);
                // f32 storage rounds a return by up to ~0.1 mm at these magnitudes' local offsets.
                let nearest_return = raw.iter().map(|r| (r - p).norm()).fold(f64::INFINITY, f64::min);
                proptest::prop_assert!(d <= nearest_return + 1e-5, "{} above a return at {}", d, nearest_return);
                // Capped: exact below the cap, else at least the cap and never above the truth.
                for upto in [0.0, 0.05, 0.3, 1.0] {
                    let (_, c) = live.nearest_upto(p, upto).expect("points");
                    if want < upto - 1e-6 {
                        proptest::prop_assert!((c - want).abs() < 1e-6, "capped at {}: {} against {}", upto, c, want);
                    } else {
                        proptest::prop_assert!(c >= upto - 1e-6 && c <= want + 1e-6, "capped at {}: {} against {}", upto, c, want);
                    }
                }
            }
        }
    }
}
