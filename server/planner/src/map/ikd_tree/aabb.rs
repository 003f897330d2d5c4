//! Points and axis-aligned boxes: the two geometric types of the ikd-tree's API.
//!
//! Coordinates are `f32` metres in whatever frame the caller's points are in (the map frame for the live
//! map). Squared distances are `f32` square metres.

/// A 3-D point in metres, in the frame of the tree that holds it (the map frame for a site's live map).
///
/// A plain `Copy` struct of three `f32` (12 bytes); converts to and from `[f32; 3]` and
/// `nalgebra::Point3<f32>`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Point3 {
    /// x in metres.
    pub x: f32,
    /// y in metres.
    pub y: f32,
    /// z in metres.
    pub z: f32,
}

impl Point3 {
    /// A point from its coordinates in metres.
    #[inline]
    pub const fn new(x: f32, y: f32, z: f32) -> Self {
        Self { x, y, z }
    }

    /// Coordinate along `axis` (0 = x, 1 = y, anything else = z), metres.
    #[inline(always)]
    pub fn get(&self, axis: usize) -> f32 {
        match axis {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }

    /// Squared Euclidean distance to `other`, square metres.
    #[inline(always)]
    pub fn dist2(&self, other: &Point3) -> f32 {
        let dx = self.x - other.x;
        let dy = self.y - other.y;
        let dz = self.z - other.z;
        dx * dx + dy * dy + dz * dz
    }

    /// True when all three coordinates are finite (neither NaN nor infinite). The tree stores only such
    /// points.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
}

impl From<[f32; 3]> for Point3 {
    fn from(c: [f32; 3]) -> Self {
        Self::new(c[0], c[1], c[2])
    }
}

impl From<Point3> for [f32; 3] {
    fn from(p: Point3) -> Self {
        [p.x, p.y, p.z]
    }
}

impl From<nalgebra::Point3<f32>> for Point3 {
    fn from(p: nalgebra::Point3<f32>) -> Self {
        Self::new(p.x, p.y, p.z)
    }
}

impl From<Point3> for nalgebra::Point3<f32> {
    fn from(p: Point3) -> Self {
        nalgebra::Point3::new(p.x, p.y, p.z)
    }
}

/// A closed axis-aligned box in metres, in the tree's frame: a point `p` is inside when
/// `min.a <= p.a <= max.a` on every axis `a`.
///
/// A box whose `min` exceeds its `max` on some axis, or that has a NaN bound, holds no point; the tree's
/// box operations treat it as empty (they delete, restore or return nothing). Infinite bounds are allowed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner, metres.
    pub min: Point3,
    /// Upper corner, metres.
    pub max: Point3,
}

impl Aabb {
    /// The box with corners `min` and `max` (not reordered: see the type's note on empty boxes).
    #[inline]
    pub const fn new(min: Point3, max: Point3) -> Self {
        Self { min, max }
    }

    /// The cube of half-side `half_m` metres centred on `centre`.
    pub fn around(centre: Point3, half_m: f32) -> Self {
        Self {
            min: Point3::new(centre.x - half_m, centre.y - half_m, centre.z - half_m),
            max: Point3::new(centre.x + half_m, centre.y + half_m, centre.z + half_m),
        }
    }

    /// The empty box (min = +inf, max = -inf): the identity of [`Aabb::union`].
    #[inline]
    pub const fn empty() -> Self {
        Self {
            min: Point3::new(f32::INFINITY, f32::INFINITY, f32::INFINITY),
            max: Point3::new(f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY),
        }
    }

    /// True when the box holds at least one point: no NaN bound and `min <= max` on every axis.
    #[inline]
    pub fn is_valid(&self) -> bool {
        self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z
    }

    /// True when `p` lies inside the closed box.
    #[inline(always)]
    pub fn contains(&self, p: &Point3) -> bool {
        p.x >= self.min.x
            && p.x <= self.max.x
            && p.y >= self.min.y
            && p.y <= self.max.y
            && p.z >= self.min.z
            && p.z <= self.max.z
    }

    /// Bit `i` set when `pts[i]` lies inside the box (at most the first 32 points), computed without
    /// branches.
    #[inline(always)]
    pub(crate) fn inside_mask(&self, pts: &[Point3]) -> u32 {
        let mut m = 0u32;
        for (i, p) in pts.iter().take(32).enumerate() {
            let inside = (p.x >= self.min.x)
                & (p.x <= self.max.x)
                & (p.y >= self.min.y)
                & (p.y <= self.max.y)
                & (p.z >= self.min.z)
                & (p.z <= self.max.z);
            m |= (inside as u32) << i;
        }
        m
    }

    /// True when `other` lies wholly inside this box (an empty `other` is inside every box).
    #[inline(always)]
    pub fn contains_box(&self, other: &Aabb) -> bool {
        !other.is_valid()
            || (other.min.x >= self.min.x
                && other.max.x <= self.max.x
                && other.min.y >= self.min.y
                && other.max.y <= self.max.y
                && other.min.z >= self.min.z
                && other.max.z <= self.max.z)
    }

    /// True when the two closed boxes share at least one point.
    #[inline(always)]
    pub fn intersects(&self, other: &Aabb) -> bool {
        self.min.x <= other.max.x
            && self.max.x >= other.min.x
            && self.min.y <= other.max.y
            && self.max.y >= other.min.y
            && self.min.z <= other.max.z
            && self.max.z >= other.min.z
    }

    /// Squared distance in square metres from `p` to the nearest point of the box (0 inside). For the empty
    /// box the result is +inf.
    #[inline(always)]
    pub fn dist2(&self, p: &Point3) -> f32 {
        let dx = (self.min.x - p.x).max(p.x - self.max.x).max(0.0);
        let dy = (self.min.y - p.y).max(p.y - self.max.y).max(0.0);
        let dz = (self.min.z - p.z).max(p.z - self.max.z).max(0.0);
        dx * dx + dy * dy + dz * dz
    }

    /// Grows the box to hold `p`.
    #[inline(always)]
    pub fn expand(&mut self, p: &Point3) {
        self.min.x = self.min.x.min(p.x);
        self.min.y = self.min.y.min(p.y);
        self.min.z = self.min.z.min(p.z);
        self.max.x = self.max.x.max(p.x);
        self.max.y = self.max.y.max(p.y);
        self.max.z = self.max.z.max(p.z);
    }

    /// The smallest box holding both boxes.
    #[inline(always)]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: Point3::new(
                self.min.x.min(o.min.x),
                self.min.y.min(o.min.y),
                self.min.z.min(o.min.z),
            ),
            max: Point3::new(
                self.max.x.max(o.max.x),
                self.max.y.max(o.max.y),
                self.max.z.max(o.max.z),
            ),
        }
    }

    /// The smallest box holding every point of `pts` (the empty box when `pts` is empty).
    pub fn of_points(pts: &[Point3]) -> Aabb {
        let mut b = Aabb::empty();
        for p in pts {
            b.expand(p);
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_predicates() {
        let b = Aabb::new(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 2.0, 3.0));
        assert!(b.contains(&Point3::new(1.0, 2.0, 3.0)));
        assert!(!b.contains(&Point3::new(1.0, 2.0, 3.1)));
        assert_eq!(b.dist2(&Point3::new(2.0, 2.0, 4.0)), 2.0);
        assert_eq!(b.dist2(&Point3::new(0.5, 0.5, 0.5)), 0.0);
        assert!(b.contains_box(&Aabb::empty()));
        assert!(!Aabb::empty().is_valid());
        assert!(!Aabb::new(Point3::new(f32::NAN, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0)).is_valid());
        assert_eq!(Aabb::empty().dist2(&Point3::default()), f32::INFINITY);
        let u = b.union(&Aabb::around(Point3::new(5.0, 5.0, 5.0), 1.0));
        assert_eq!(u.max, Point3::new(6.0, 6.0, 6.0));
        assert_eq!(u.min, Point3::new(0.0, 0.0, 0.0));
    }
}
