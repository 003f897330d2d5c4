//! Is the footprint clear at a pose? The distance field decides most poses at once — clear when the
//! circumscribed disc is, blocked when the inscribed disc is not — and parry2d decides the band between
//! exactly: the polygon at its heading against the square of each blocked cell near it.
//!
//! Cells are squares of the map's resolution; blocked means occupied, unknown, or off the map (the map's edge
//! is a wall, as in [`crate::space`]). A check may carry a margin: every blocked square grows by it, so a
//! pose clear with margin `m` stays clear when every point of the polygon moves by less than `m`. The planner
//! checks with a margin of an eighth of a cell and samples poses a quarter of a cell apart (the circumscribed
//! radius moving a quarter of a cell per turn step), so the continuous motion between its samples is clear
//! too; DESIGN §6's `collisions` ([`FootprintCheck::count_collisions`]) counts without a margin.

use std::ops::ControlFlow;

use parry2d::math::Pose;
use parry2d::query::intersection_test;
use parry2d::shape::Cuboid;

use super::poses::visit_poses;
use super::shape::{Footprint, parry_vector};
use crate::error::{PlannerError, Result};
use crate::geom::{Point2, Vector2};
use crate::map::{DistanceField, OccupancyGrid};

/// Footprint collision checks on one grid.
#[derive(Debug, Clone)]
pub struct FootprintCheck<'a> {
    grid: &'a OccupancyGrid,
    clearance: &'a DistanceField,
    footprint: &'a Footprint,
    margin_m: f64,
    cell: Cuboid,
}

impl<'a> FootprintCheck<'a> {
    /// Checks on `grid` with `clearance`, the distance from every cell centre to the nearest blocked cell
    /// centre with the map's edge as a wall (what [`crate::space::CoverageSpace::clearance`] holds). No margin.
    pub fn new(grid: &'a OccupancyGrid, clearance: &'a DistanceField, footprint: &'a Footprint) -> Result<Self> {
        if clearance.geometry() != &grid.geometry || !clearance.border_is_site() {
            return Err(PlannerError::InvalidParam {
                name: "clearance",
                reason: "must be the grid's distance field to its blocked cells, with the map's edge as a wall".into(),
            });
        }
        let h = grid.geometry.resolution / 2.0;
        Ok(Self {
            grid,
            clearance,
            footprint,
            margin_m: 0.0,
            cell: Cuboid::new(parry_vector(Vector2::new(h, h))),
        })
    }

    /// The same checks with every blocked square grown by `margin_m` metres (≥ 0).
    pub fn with_margin(mut self, margin_m: f64) -> Self {
        self.margin_m = margin_m.max(0.0);
        let h = self.grid.geometry.resolution / 2.0 + self.margin_m;
        self.cell = Cuboid::new(parry_vector(Vector2::new(h, h)));
        self
    }

    /// The margin the planner checks with on a grid of `resolution_m`: an eighth of a cell.
    pub fn planning_margin_m(resolution_m: f64) -> f64 {
        resolution_m / 8.0
    }

    /// The footprint.
    pub fn footprint(&self) -> &Footprint {
        self.footprint
    }

    /// The grid.
    pub fn grid(&self) -> &OccupancyGrid {
        self.grid
    }

    /// The distance field the fast paths read.
    pub fn clearance_field(&self) -> &DistanceField {
        self.clearance
    }

    /// The margin, metres.
    pub fn margin_m(&self) -> f64 {
        self.margin_m
    }

    /// Poses along a straight move are sampled this far apart: a quarter of a cell, metres.
    pub fn sample_spacing_m(&self) -> f64 {
        self.grid.geometry.resolution / 4.0
    }

    /// Headings of a turn in place are sampled this far apart, radians: the circumscribed radius moves a
    /// quarter of a cell per step.
    pub fn rotation_step_rad(&self) -> f64 {
        (self.sample_spacing_m() / self.footprint.circumscribed_radius_m()).min(0.25)
    }

    /// A lower bound of the distance from `p` to the nearest blocked cell centre, metres (`-∞` off the map).
    #[inline]
    pub fn clearance_lower_bound(&self, p: Point2) -> f64 {
        let g = &self.grid.geometry;
        g.locate(p).map_or(f64::NEG_INFINITY, |c| {
            let i = g.index(c);
            self.clearance.at(i) * (1.0 - 1e-6) - (p - g.center_of(i)).norm() - 1e-9
        })
    }

    /// Clearance (from a pose's centre to the nearest blocked cell centre) beyond which no blocked square,
    /// grown by the margin, can touch the footprint at any heading: the circumscribed radius plus half the
    /// grown square's diagonal, metres.
    pub fn turning_clearance_m(&self) -> f64 {
        self.footprint.circumscribed_radius_m()
            + (self.grid.geometry.resolution / 2.0 + self.margin_m) * std::f64::consts::SQRT_2
    }

    /// True when the robot may stand at `p` at any heading and turn there freely (its circumscribed disc is
    /// clear of every blocked square).
    #[inline]
    pub fn turns_freely(&self, p: Point2) -> bool {
        self.spare_m(p) >= 0.0
    }

    /// How far the robot may move from `p` and still turn freely there, metres (negative where it cannot
    /// turn freely at `p`): clearance changes by at most the distance moved.
    #[inline]
    pub fn spare_m(&self, p: Point2) -> f64 {
        self.clearance_lower_bound(p) - self.turning_clearance_m()
    }

    /// True when the footprint at pose (`x`, `y`, `yaw_rad`) (map frame) overlaps no blocked cell.
    pub fn pose_free(&self, x: f64, y: f64, yaw_rad: f64) -> bool {
        let p = Point2::new(x, y);
        if !(x.is_finite() && y.is_finite() && yaw_rad.is_finite()) {
            return false;
        }
        if self.turns_freely(p) {
            return true;
        }
        // A blocked cell centre inside the inscribed disc is inside the polygon (the distance is to a real
        // blocked centre, so it bounds the nearest from above).
        if self.clearance.at_point(p) < self.footprint.inscribed_radius_m() {
            return false;
        }
        self.exact_free(p, yaw_rad)
    }

    /// The exact decision: parry2d's intersection test of the rotated polygon against every blocked square
    /// (grown by the margin) that meets the polygon's bounding box. Coordinates relative to the pose, so f32
    /// keeps sub-micrometre precision. Squares wholly outside one of the polygon's edges (a separating axis,
    /// in f64 with a micrometre to spare) never reach parry: only squares that touch or nearly touch do.
    fn exact_free(&self, p: Point2, yaw_rad: f64) -> bool {
        let g = &self.grid.geometry;
        let corners = self.footprint.at_pose(p.x, p.y, yaw_rad);
        let half = g.resolution / 2.0 + self.margin_m;
        let (mut x0, mut y0, mut x1, mut y1) = (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for c in &corners {
            x0 = x0.min(c.x - half);
            y0 = y0.min(c.y - half);
            x1 = x1.max(c.x + half);
            y1 = y1.max(c.y + half);
        }
        // Outward normal and offset of each edge, map frame: a square of half-side `half` at centre q lies
        // wholly outside edge e when n·q − c > half (|n.x| + |n.y|).
        let n = corners.len();
        let edges: Vec<(Vector2, f64, f64)> = (0..n)
            .map(|i| {
                let d = corners[(i + 1) % n] - corners[i];
                let normal = Vector2::new(d.y, -d.x) / d.norm();
                let reach = half * (normal.x.abs() + normal.y.abs()) + 1e-6;
                (normal, normal.dot(&corners[i].coords), reach)
            })
            .collect();
        let (cx0, cy0) = g.to_cell_coords(Point2::new(x0, y0));
        let (cx1, cy1) = g.to_cell_coords(Point2::new(x1, y1));
        let polygon = self.footprint.parry_polygon();
        let robot = Pose::rotation(yaw_rad as f32);
        let (w, h) = (g.width as i64, g.height as i64);
        for iy in (cy0.floor() as i64)..=(cy1.floor() as i64) {
            for ix in (cx0.floor() as i64)..=(cx1.floor() as i64) {
                let on_map = ix >= 0 && iy >= 0 && ix < w && iy < h;
                if on_map && self.grid.is_free((iy * w + ix) as usize) {
                    continue;
                }
                let centre = Point2::new(
                    g.origin.x + (ix as f64 + 0.5) * g.resolution,
                    g.origin.y + (iy as f64 + 0.5) * g.resolution,
                );
                if edges
                    .iter()
                    .any(|(normal, offset, reach)| normal.dot(&centre.coords) - offset > *reach)
                {
                    continue;
                }
                let d = centre - p;
                let at = Pose::translation(d.x as f32, d.y as f32);
                // A convex polygon and a cuboid are both support maps: the query is always supported.
                if intersection_test(&robot, polygon, &at, &self.cell).is_ok_and(|i| i.intersecting) {
                    return false;
                }
            }
        }
        true
    }

    /// True when the robot can turn in place at (`x`, `y`) from `yaw0_rad` to `yaw1_rad` the shorter way,
    /// every heading on the way sampled at [`FootprintCheck::rotation_step_rad`] (the pose at `yaw0_rad` is
    /// taken as known).
    pub fn rotation_free(&self, x: f64, y: f64, yaw0_rad: f64, yaw1_rad: f64) -> bool {
        let p = Point2::new(x, y);
        if self.turns_freely(p) {
            return true;
        }
        super::poses::turn_headings(yaw0_rad, yaw1_rad, self.rotation_step_rad()).all(|h| self.pose_free(x, y, h))
    }

    /// How far the robot at (`x`, `y`, `yaw_rad`) can turn in place counter-clockwise and clockwise before a
    /// sampled heading is blocked, radians, each at most π (the pose at `yaw_rad` is taken as known).
    pub fn free_turn_arcs(&self, x: f64, y: f64, yaw_rad: f64) -> (f64, f64) {
        let pi = std::f64::consts::PI;
        if self.turns_freely(Point2::new(x, y)) {
            return (pi, pi);
        }
        let step = self.rotation_step_rad();
        let arc = |sign: f64| {
            let mut a: f64 = 0.0;
            while a < pi {
                let next = (a + step).min(pi);
                if !self.pose_free(x, y, yaw_rad + sign * next) {
                    break;
                }
                a = next;
            }
            a
        };
        (arc(1.0), arc(-1.0))
    }

    /// True when the robot can drive straight from `a` to `b` facing `b` (the pose at `a` is taken as known),
    /// poses sampled every [`FootprintCheck::sample_spacing_m`]. Samples with clearance to spare let the
    /// check leap over the samples after them (any pose within the spare distance of a clear disc is clear).
    pub fn segment_free(&self, a: Point2, b: Point2) -> bool {
        let Some(yaw) = super::poses::segment_heading(a, b) else {
            return true;
        };
        let len = (b - a).norm();
        let m = (len / self.sample_spacing_m()).ceil().max(1.0) as usize;
        let spacing = len / m as f64;
        let needed = self.turning_clearance_m();
        let mut j = 1;
        while j <= m {
            let p = a + (b - a) * (j as f64 / m as f64);
            let slack = self.clearance_lower_bound(p) - needed;
            if slack >= 0.0 {
                j += if slack > spacing {
                    (slack / spacing).floor() as usize
                } else {
                    1
                };
                continue;
            }
            if !self.pose_free(p.x, p.y, yaw) {
                return false;
            }
            j += 1;
        }
        true
    }

    /// True when every pose of `path` is clear (the poses [`super::poses::visit_poses`] names, with the
    /// robot at `start_yaw` at the first point and turning to `end_yaw` at the last).
    pub fn path_free(&self, path: &[Point2], start_yaw: Option<f64>, end_yaw: Option<f64>) -> bool {
        visit_poses(
            path,
            start_yaw,
            end_yaw,
            self.sample_spacing_m(),
            self.rotation_step_rad(),
            &mut |p, h| {
                if self.pose_free(p.x, p.y, h) {
                    ControlFlow::Continue(())
                } else {
                    ControlFlow::Break(())
                }
            },
        )
    }

    /// DESIGN §6 `collisions` in footprint form: the robot drives `path` forward, its heading along each
    /// segment and turning in place at each vertex the shorter way (starting at the first segment's heading);
    /// poses are sampled every quarter cell along segments and every [`FootprintCheck::rotation_step_rad`]
    /// in turns, and each pose whose polygon overlaps a blocked cell counts once.
    pub fn count_collisions(&self, path: &[Point2]) -> usize {
        let mut n = 0;
        visit_poses(
            path,
            None,
            None,
            self.sample_spacing_m(),
            self.rotation_step_rad(),
            &mut |p, h| {
                if !self.pose_free(p.x, p.y, h) {
                    n += 1;
                }
                ControlFlow::Continue(())
            },
        );
        n
    }
}
