//! The hidden world's solids as parry2d shapes: ray casts for the laser and intersection tests for collisions.
//!
//! parry2d 0.31 works in f32 on glam vectors (ECOSYSTEM.md); this module is the boundary: everything outside it
//! is f64 nalgebra ([`Point2`]).

use parry2d::math::{Pose, Vector};
use parry2d::query::{Ray, intersection_test};
use parry2d::shape::{Ball, Cuboid, SharedShape};
use shift_planner::geom::Point2;

fn vec2(p: Point2) -> Vector {
    Vector::new(p.x as f32, p.y as f32)
}

/// A solid shape placed in the map frame.
#[derive(Clone)]
pub struct Solid {
    shape: SharedShape,
    pose: Pose,
}

impl std::fmt::Debug for Solid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Solid")
            .field("pose", &self.pose)
            .finish_non_exhaustive()
    }
}

impl Solid {
    /// An axis-aligned box between two corners.
    pub fn aabb(x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        let half = Vector::new(((x1 - x0) / 2.0) as f32, ((y1 - y0) / 2.0) as f32);
        Self {
            shape: SharedShape::new(Cuboid::new(half)),
            pose: Pose::from_translation(vec2(Point2::new((x0 + x1) / 2.0, (y0 + y1) / 2.0))),
        }
    }

    /// A disc.
    pub fn disc(centre: Point2, r: f64) -> Self {
        Self {
            shape: SharedShape::new(Ball::new(r as f32)),
            pose: Pose::from_translation(vec2(centre)),
        }
    }

    /// Moves the shape's centre to `centre`.
    pub fn move_to(&mut self, centre: Point2) {
        self.pose = Pose::from_translation(vec2(centre));
    }

    /// Distance along the unit direction `dir` from `origin` to the shape, within `max_range` (0 from inside).
    pub fn cast(&self, origin: Point2, dir: (f64, f64), max_range: f64) -> Option<f64> {
        let ray = Ray::new(vec2(origin), Vector::new(dir.0 as f32, dir.1 as f32));
        self.shape
            .cast_ray(&self.pose, &ray, max_range as f32, true)
            .map(f64::from)
    }

    /// True when a disc of radius `r` at `centre` overlaps the shape (parry's intersection test).
    pub fn overlaps_disc(&self, centre: Point2, r: f64) -> bool {
        let ball = Ball::new(r as f32);
        intersection_test(
            &Pose::from_translation(vec2(centre)),
            &ball,
            &self.pose,
            self.shape.as_ref(),
        )
        .is_ok_and(|i| i.intersecting)
    }

    /// True when `p` lies inside the shape.
    pub fn contains(&self, p: Point2) -> bool {
        self.shape.contains_point(&self.pose, vec2(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_and_discs_meet_a_box_where_geometry_says() {
        let b = Solid::aabb(1.0, -1.0, 2.0, 1.0);
        let t = b.cast(Point2::new(0.0, 0.0), (1.0, 0.0), 10.0).expect("hit");
        assert!((t - 1.0).abs() < 1e-5, "{t}");
        assert_eq!(b.cast(Point2::new(0.0, 0.0), (-1.0, 0.0), 10.0), None);
        assert_eq!(b.cast(Point2::new(0.0, 0.0), (1.0, 0.0), 0.5), None);
        assert!(b.overlaps_disc(Point2::new(0.8, 0.0), 0.25));
        assert!(!b.overlaps_disc(Point2::new(0.7, 0.0), 0.25));
        assert!(b.contains(Point2::new(1.5, 0.5)));
        assert!(!b.contains(Point2::new(2.5, 0.5)));
    }

    #[test]
    fn a_moved_disc_is_cast_at_its_new_place() {
        let mut d = Solid::disc(Point2::new(0.0, 3.0), 0.5);
        assert_eq!(d.cast(Point2::new(0.0, 0.0), (1.0, 0.0), 10.0), None);
        d.move_to(Point2::new(3.0, 0.0));
        let t = d.cast(Point2::new(0.0, 0.0), (1.0, 0.0), 10.0).expect("hit");
        assert!((t - 2.5).abs() < 1e-5, "{t}");
    }
}
