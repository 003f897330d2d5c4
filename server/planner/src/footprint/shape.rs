//! The footprint itself: a convex polygon in the robot frame (Nav2's `footprint` convention: x forward, y to
//! the left, metres, the origin at the robot's centre of rotation), validated once, with the two radii every
//! check leans on.
//!
//! parry2d 0.31 is f32 on glam (ECOSYSTEM.md); [`Footprint::parry_polygon`] and [`parry_vector`] are the one
//! place the planner's f64 nalgebra meets it.

use parry2d::math::Vector;
use parry2d::shape::ConvexPolygon;

use crate::error::{PlannerError, Result};
use crate::geom::{Point2, Vector2};

/// The name a footprint is refused under (the request field it comes from).
pub const FOOTPRINT_FIELD: &str = "robot.footprint";

/// Most vertices a footprint may have (a robot outline, not a survey: every check walks them).
pub const MAX_VERTICES: usize = 64;

/// Least distance from the origin to every edge, metres: the centre of rotation must lie inside the body.
pub const MIN_ORIGIN_INSET_M: f64 = 1e-3;

/// Vertices closer than this (metres) are one vertex; turns with a cross product under `EPS_M²` are straight.
const EPS_M: f64 = 1e-9;

/// A convex robot footprint in the robot frame, metres, counter-clockwise.
#[derive(Clone)]
pub struct Footprint {
    vertices: Vec<Point2>,
    inscribed_m: f64,
    circumscribed_m: f64,
    polygon: ConvexPolygon,
}

impl std::fmt::Debug for Footprint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Footprint")
            .field("vertices", &self.vertices)
            .field("inscribed_m", &self.inscribed_m)
            .field("circumscribed_m", &self.circumscribed_m)
            .finish_non_exhaustive()
    }
}

impl PartialEq for Footprint {
    fn eq(&self, other: &Self) -> bool {
        self.vertices == other.vertices
    }
}

fn refuse(reason: String) -> PlannerError {
    PlannerError::InvalidParam {
        name: FOOTPRINT_FIELD,
        reason,
    }
}

impl Footprint {
    /// Validates `vertices` (`[[x, y], …]` in the robot frame, metres, implicitly closed, either winding):
    /// at least 3 and at most [`MAX_VERTICES`] vertices, all finite, no repeated vertex, convex, a non-zero
    /// area, and the origin inside, at least [`MIN_ORIGIN_INSET_M`] from every edge. Vertices on a straight
    /// edge are dropped; the polygon is kept counter-clockwise.
    pub fn new(vertices: &[[f64; 2]]) -> Result<Self> {
        let n = vertices.len();
        if n < 3 {
            return Err(refuse(format!("needs at least 3 vertices, got {n}")));
        }
        if n > MAX_VERTICES {
            return Err(refuse(format!("has {n} vertices; at most {MAX_VERTICES} are accepted")));
        }
        if let Some((i, v)) = vertices
            .iter()
            .enumerate()
            .find(|(_, v)| !(v[0].is_finite() && v[1].is_finite()))
        {
            return Err(refuse(format!("vertex {i} ({}, {}) is not finite", v[0], v[1])));
        }
        let mut pts: Vec<Point2> = vertices.iter().map(|v| Point2::new(v[0], v[1])).collect();
        for i in 0..n {
            if (pts[(i + 1) % n] - pts[i]).norm() <= EPS_M {
                return Err(refuse(format!("vertex {} repeats vertex {i}", (i + 1) % n)));
            }
        }
        let area2: f64 = (0..n)
            .map(|i| {
                let (a, b) = (pts[i], pts[(i + 1) % n]);
                a.x * b.y - b.x * a.y
            })
            .sum();
        if area2.abs() <= EPS_M {
            return Err(refuse("has no area (its vertices lie on a line)".into()));
        }
        if area2 < 0.0 {
            pts.reverse();
        }
        // Convex and simple: every turn to the left (straight vertices dropped) and one turn round in all.
        let turn = |p: &[Point2], i: usize| -> f64 {
            let m = p.len();
            let (a, b, c) = (p[(i + m - 1) % m], p[i], p[(i + 1) % m]);
            (b - a).perp(&(c - b))
        };
        let mut kept: Vec<Point2> = Vec::with_capacity(n);
        for i in 0..n {
            let t = turn(&pts, i);
            if t < -EPS_M * EPS_M {
                return Err(refuse(format!("is not convex (it turns right at vertex {i})")));
            }
            if t > EPS_M * EPS_M {
                kept.push(pts[i]);
            }
        }
        if kept.len() < 3 {
            return Err(refuse("has no area (its vertices lie on a line)".into()));
        }
        let winding: f64 = (0..kept.len())
            .map(|i| {
                let m = kept.len();
                let (a, b, c) = (kept[(i + m - 1) % m], kept[i], kept[(i + 1) % m]);
                let (u, v) = (b - a, c - b);
                u.perp(&v).atan2(u.dot(&v))
            })
            .sum();
        if (winding - std::f64::consts::TAU).abs() > 1e-6 {
            return Err(refuse(format!(
                "is not convex (its edges wind {:.0}° round instead of 360°)",
                winding.to_degrees()
            )));
        }
        let m = kept.len();
        // Signed distance from the origin to each edge's line, positive inside (counter-clockwise).
        let inscribed_m = (0..m)
            .map(|i| {
                let (a, b) = (kept[i], kept[(i + 1) % m]);
                let d = b - a;
                d.perp(&(Point2::origin() - a)) / d.norm()
            })
            .fold(f64::INFINITY, f64::min);
        if inscribed_m < MIN_ORIGIN_INSET_M {
            return Err(refuse(format!(
                "must hold the origin (the robot's centre) at least {MIN_ORIGIN_INSET_M} m inside every edge; \
                 it is {inscribed_m:.4} m"
            )));
        }
        let circumscribed_m = kept.iter().map(|p| p.coords.norm()).fold(0.0, f64::max);
        // Validated convex, counter-clockwise and with no straight vertex: the unmodified constructor keeps
        // exactly these vertices.
        let polygon =
            ConvexPolygon::from_convex_polyline_unmodified(kept.iter().map(|p| parry_vector(p.coords)).collect())
                .ok_or_else(|| refuse("is too small to be a shape in single precision".into()))?;
        Ok(Self {
            vertices: kept,
            inscribed_m,
            circumscribed_m,
            polygon,
        })
    }

    /// A rectangle `length_m` along x by `width_m` along y, centred on the origin.
    pub fn rectangle(length_m: f64, width_m: f64) -> Result<Self> {
        let (hx, hy) = (length_m / 2.0, width_m / 2.0);
        Self::new(&[[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    }

    /// The vertices, counter-clockwise, robot frame, metres.
    pub fn vertices(&self) -> &[Point2] {
        &self.vertices
    }

    /// Radius of the largest disc about the origin inside the footprint (least distance from the origin to
    /// an edge), metres: wherever this disc collides, every heading does.
    pub fn inscribed_radius_m(&self) -> f64 {
        self.inscribed_m
    }

    /// Radius of the smallest disc about the origin holding the footprint (farthest vertex), metres:
    /// wherever this disc is clear, every heading is.
    pub fn circumscribed_radius_m(&self) -> f64 {
        self.circumscribed_m
    }

    /// The radius a [`crate::space::CoverageSpace`] is built with for this footprint on a grid of
    /// `resolution_m`: the inscribed radius plus half a cell's diagonal, so that a robot centre the space
    /// accepts keeps its inscribed disc off every blocked cell's square (the space measures to cell centres).
    pub fn planning_radius_m(&self, resolution_m: f64) -> f64 {
        self.inscribed_m + resolution_m * std::f64::consts::FRAC_1_SQRT_2
    }

    /// The vertices at pose (`x`, `y`, `yaw_rad`) in the map frame, metres.
    pub fn at_pose(&self, x: f64, y: f64, yaw_rad: f64) -> Vec<Point2> {
        let (s, c) = yaw_rad.sin_cos();
        self.vertices
            .iter()
            .map(|p| Point2::new(x + c * p.x - s * p.y, y + s * p.x + c * p.y))
            .collect()
    }

    /// The footprint as a parry2d shape in the robot frame.
    pub fn parry_polygon(&self) -> &ConvexPolygon {
        &self.polygon
    }
}

/// A planner vector as parry's (f32).
pub fn parry_vector(v: Vector2) -> Vector {
    Vector::new(v.x as f32, v.y as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rectangle_has_its_radii() {
        let f = Footprint::rectangle(1.2, 0.8).expect("valid");
        assert!((f.inscribed_radius_m() - 0.4).abs() < 1e-12);
        assert!((f.circumscribed_radius_m() - 0.6f64.hypot(0.4)).abs() < 1e-12);
        assert!((f.planning_radius_m(0.05) - (0.4 + 0.05 / 2f64.sqrt())).abs() < 1e-12);
        assert_eq!(f.parry_polygon().points().len(), 4);
        let at = f.at_pose(1.0, 2.0, std::f64::consts::FRAC_PI_2);
        assert!((at[0] - Point2::new(0.6, 2.6)).norm() < 1e-12, "{at:?}");
    }

    #[test]
    fn either_winding_is_kept_counter_clockwise_and_straight_vertices_go() {
        let cw = Footprint::new(&[[0.5, 0.3], [0.5, 0.0], [0.5, -0.3], [-0.5, -0.3], [-0.5, 0.3]]).expect("valid");
        assert_eq!(cw.vertices().len(), 4);
        let v = cw.vertices();
        let area2: f64 = (0..4).map(|i| v[i].coords.perp(&v[(i + 1) % 4].coords)).sum();
        assert!(area2 > 0.0);
    }

    #[test]
    fn bad_footprints_are_refused_naming_the_field() {
        let cases: [(&[[f64; 2]], &str); 8] = [
            (&[[0.5, 0.5], [-0.5, 0.5]], "at least 3"),
            (&[[0.5, 0.5], [-0.5, 0.5], [f64::NAN, 0.0]], "not finite"),
            (&[[0.5, 0.5], [0.5, 0.5], [-0.5, -0.5]], "repeats"),
            (&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]], "no area"),
            (
                &[[1.0, 1.0], [-1.0, 1.0], [0.0, 0.1], [-1.0, -1.0], [1.0, -1.0]],
                "not convex",
            ),
            (&[[1.0, 0.1], [2.0, 0.1], [2.0, 1.0], [1.0, 1.0]], "origin"),
            (&[[0.5, 0.0], [0.5, 0.5], [-0.5, 0.5], [-0.5, 0.0]], "origin"),
            // A pentagram turns left at every vertex but winds twice.
            (
                &[
                    [1.0, 0.0],
                    [-0.809, 0.588],
                    [0.309, -0.951],
                    [0.309, 0.951],
                    [-0.809, -0.588],
                ],
                "not convex",
            ),
        ];
        for (vertices, want) in cases {
            let e = Footprint::new(vertices).expect_err(want);
            let msg = e.to_string();
            assert!(
                msg.contains(FOOTPRINT_FIELD) && msg.contains(want),
                "{vertices:?}: {msg}"
            );
        }
        let many: Vec<[f64; 2]> = (0..MAX_VERTICES + 1)
            .map(|i| {
                let a = i as f64 / (MAX_VERTICES + 1) as f64 * std::f64::consts::TAU;
                [a.cos(), a.sin()]
            })
            .collect();
        assert!(Footprint::new(&many).is_err());
    }
}
