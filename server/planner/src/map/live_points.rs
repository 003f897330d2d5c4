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

use super::ikd_tree::{Aabb, IkdTree, Point3};
use crate::geom::Point2;

/// Read access to live obstacle points: the tree and the map-frame position of its local origin.
#[derive(Debug, Clone, Copy)]
pub struct LivePoints<'a> {
    /// Points at `(x − origin.x, y − origin.y, 0)`.
    pub tree: &'a IkdTree,
    /// Map-frame position of the tree's (0, 0), metres.
    pub origin: Point2,
}

impl<'a> LivePoints<'a> {
    /// Points of `tree` stored relative to `origin`.
    pub fn new(tree: &'a IkdTree, origin: Point2) -> Self {
        Self { tree, origin }
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

    /// The point nearest to `p` (map frame) with its distance, metres; `None` when empty or `p` is not finite.
    #[inline]
    pub fn nearest(&self, p: Point2) -> Option<(Point2, f64)> {
        let (q, _) = self.tree.nearest_point(&Self::to_local(self.origin, p))?;
        let q = self.to_map(&q);
        Some((q, (q - p).norm()))
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
}
