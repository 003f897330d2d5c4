//! What a lazy delete removes: a box, a voxel or an exact point.

use super::VoxelShape;
use super::aabb::{Aabb, Point3};

/// What a delete removes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Region {
    /// Every valid point inside the closed box.
    Box(Aabb),
    /// Every valid point of a voxel (of side `vs` metres).
    Voxel { shape: VoxelShape, vs: f32 },
    /// Every valid point with exactly these coordinates.
    Point(Point3),
}

impl Region {
    /// A box holding every point the region can match.
    #[inline]
    pub(super) fn search_box(&self) -> Aabb {
        match self {
            Region::Box(r) => *r,
            Region::Voxel { shape, .. } => shape.outer,
            Region::Point(p) => Aabb::new(*p, *p),
        }
    }

    /// True when every point inside `b` matches (only boxes can say so).
    #[inline]
    pub(super) fn swallows(&self, b: &Aabb) -> bool {
        match self {
            Region::Box(r) => r.contains_box(b),
            _ => false,
        }
    }
}
