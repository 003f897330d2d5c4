//! Circular Judgment and Assessment (seed 000 §IV.D, Alg. 1): the stretches of the plan ahead of the robot,
//! inside a circle around it, whose cost J exceeds J_th.
//!
//! # The cost J
//!
//! The judged part of the path is sampled at a step `h ≤ min(resolution / 2, robot_radius / 2)` along its
//! segments (not only at waypoints: lanes are long straight segments). Each sample `i` gets
//!
//! - a clearance term `e_i = (max(0, d_safe − c_live, r − slack − c_static) / margin)²`, with `c_live` the
//!   distance to the nearest live obstacle point, `c_static` the exact distance to the static map (DESIGN §6
//!   metric; both 0 off the map), `d_safe = robot_radius + margin` and `slack` =
//!   [`super::world::STATIC_SLACK_M`]: the plan was made on the static map and may run at exactly the radius
//!   from its walls, so only new obstacles must keep the margin; `e_i = 1` where the robot just touches a live
//!   obstacle;
//! - at waypoints, when `max_curvature_per_m` is finite, a curvature term `(κ / κ_max − 1)²` for
//!   `κ > κ_max`, with `κ` the turning angle over the mean of the two adjacent segment lengths.
//!
//! A sample is *non-compliant* when its term is positive. J of a maximal run of non-compliant samples is
//! `Σ h_i · e_i` (metres: the length of path at zero margin it is equivalent to). The run is a [`Breach`]
//! when `J > J_th` (`j_threshold`, default 0.02 m), or whenever a sample is closer than the robot radius
//! (a collision is never tolerated, however short).

use crate::geom::{Point2, heading_change};

use super::params::CorrectParams;
use super::path::PathPos;
use super::world::{STATIC_SLACK_M, World};

/// A maximal non-compliant stretch of the path ahead of the robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Breach {
    /// First non-compliant sample.
    pub start: PathPos,
    /// Last non-compliant sample.
    pub end: PathPos,
    /// J of the stretch, metres (see the [module docs](self)).
    pub cost: f64,
    /// Smallest clearance along the stretch, metres (0 off the map).
    pub min_clearance_m: f64,
    /// Where judging started: the robot's projection on segment `ahead_from`. A repair never moves the path
    /// before this point.
    pub earliest: PathPos,
}

/// Sample step along the path for judging and verification, metres: `min(resolution / 2, radius / 2)`.
pub(crate) fn sample_step(world: &World<'_>, robot_radius_m: f64) -> f64 {
    (0.5 * world.resolution()).min(0.5 * robot_radius_m)
}

/// Projection of `p` on the segment `a`–`b`, as a fraction in [0, 1].
pub(crate) fn project_t(p: Point2, a: Point2, b: Point2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 <= f64::EPSILON || !len2.is_finite() {
        return 0.0;
    }
    ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
}

/// Curvature of the path at waypoint `k` (1 ≤ k ≤ len − 2), 1/m: turning angle over the mean adjacent
/// segment length. 0 at the ends and where a neighbour coincides.
pub(crate) fn waypoint_curvature(path: &[Point2], k: usize) -> f64 {
    if k == 0 || k + 1 >= path.len() {
        return 0.0;
    }
    let (a, b) = (path[k] - path[k - 1], path[k + 1] - path[k]);
    let (la, lb) = (a.norm(), b.norm());
    if la <= 1e-12 || lb <= 1e-12 {
        return 0.0;
    }
    heading_change(a, b) / (0.5 * (la + lb))
}

/// Circular Judgment and Assessment (Alg. 1). Looks at the path from the robot's projection on segment
/// `ahead_from` onwards, as long as it stays within `p.window_radius_m` of `robot` (map frame, metres; the
/// first sample outside the circle ends the judged part), and returns its maximal non-compliant stretches
/// whose cost exceeds `p.j_threshold` or that come closer than the robot radius, in path order. Returns
/// nothing for invalid `p` (see [`CorrectParams::validate`]), an inconsistent world ([`World::check`]), a
/// path of fewer than two points,
/// `ahead_from` past the last segment, or a non-finite `robot`.
pub fn judge(path: &[Point2], ahead_from: usize, robot: Point2, world: &World<'_>, p: &CorrectParams) -> Vec<Breach> {
    let mut out = Vec::new();
    if p.validate().is_err() || world.check().is_err() || path.len() < 2 || ahead_from + 1 >= path.len() {
        return out;
    }
    if !(robot.x.is_finite() && robot.y.is_finite()) {
        return out;
    }
    let h = sample_step(world, p.robot_radius_m);
    let d_safe = p.d_safe();
    let r2 = p.window_radius_m * p.window_radius_m;
    let t0 = project_t(robot, path[ahead_from], path[ahead_from + 1]);
    let earliest = PathPos::new(ahead_from, t0);
    let mut run: Option<Breach> = None;
    let close = |run: &mut Option<Breach>, out: &mut Vec<Breach>| {
        if let Some(b) = run.take()
            && (b.cost > p.j_threshold || b.min_clearance_m < p.static_radius_m)
        {
            out.push(b);
        }
    };
    'walk: for k in ahead_from..path.len() - 1 {
        let (a, b) = (path[k], path[k + 1]);
        if !(a.x.is_finite() && a.y.is_finite() && b.x.is_finite() && b.y.is_finite()) {
            break;
        }
        let t_start = if k == ahead_from { t0 } else { 0.0 };
        let len = (b - a).norm() * (1.0 - t_start);
        let n = ((len / h).ceil() as usize).max(1);
        let last_seg = k + 2 == path.len();
        let dt = (1.0 - t_start) / n as f64;
        let ds = len / n as f64;
        let kappa_term = if t_start == 0.0 && p.max_curvature_per_m.is_finite() {
            let kappa = waypoint_curvature(path, k);
            if kappa > p.max_curvature_per_m {
                (kappa / p.max_curvature_per_m - 1.0).powi(2)
            } else {
                0.0
            }
        } else {
            0.0
        };
        for j in 0..=n {
            if j == n && !last_seg {
                break;
            }
            let t = t_start + dt * j as f64;
            let q = a + (b - a) * t;
            if (q - robot).norm_squared() > r2 {
                break 'walk;
            }
            // The plan was made on the static map: its own distance to walls (often exactly the radius) is
            // no breach; only new (live) obstacles must keep d_safe, and the static map only the clearance
            // the plan keeps from it (the radius; a footprint's inscribed radius).
            let (c_live, c_static) = if world.inside(q) {
                (
                    world.live_clearance_upto(q, d_safe),
                    world.static_clearance_upto(q, d_safe),
                )
            } else {
                (0.0, 0.0)
            };
            let c = c_live.min(c_static);
            let static_short = p.static_radius_m - STATIC_SLACK_M - c_static;
            let deficit = ((d_safe - c_live).max(static_short).max(0.0) / p.margin_m).powi(2);
            let e = deficit + if j == 0 { kappa_term } else { 0.0 };
            let pos = PathPos::new(k, t.min(1.0));
            if e > 0.0 {
                let w = if ds > 0.0 { ds } else { h };
                let entry = run.get_or_insert(Breach {
                    start: pos,
                    end: pos,
                    cost: 0.0,
                    min_clearance_m: f64::INFINITY,
                    earliest,
                });
                entry.end = pos;
                entry.cost += w * e;
                entry.min_clearance_m = entry.min_clearance_m.min(c);
            } else {
                close(&mut run, &mut out);
            }
        }
    }
    close(&mut run, &mut out);
    out
}
