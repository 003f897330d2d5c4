//! The last word on a candidate patch: every segment, sampled at most `min(resolution, radius) / 2` apart,
//! keeps the robot radius from the static map (DESIGN §6 metric: distance to the nearest non-free cell
//! centre) and from every live obstacle point, and stays on the map.
//!
//! Sampling is made exact for the continuous segment: between two samples δ apart that are both at least
//! ρ from an obstacle point, the segment stays at least √(ρ² − δ²/4) from it, so each sample must keep
//! √(r² + δ²/4) (a fraction of a millimetre more than r at the usual δ). The map is a rectangle, so samples
//! on the map mean the whole segment is.

use crate::geom::Point2;

use super::judge::sample_step;
use super::world::World;

/// The samples of segment `a`–`b` (both ends included) at most `step` apart, and their spacing.
fn samples(a: Point2, b: Point2, step: f64) -> (usize, f64) {
    let len = (b - a).norm();
    let n = ((len / step).ceil() as usize).max(1);
    (n, len / n as f64)
}

/// True when the straight segment `a`–`b` (map frame, metres) keeps at least `robot_radius_m` from every
/// obstacle of `world` and lies on the map.
pub fn segment_clear(a: Point2, b: Point2, world: &World<'_>, robot_radius_m: f64) -> bool {
    if !(a.x.is_finite() && a.y.is_finite() && b.x.is_finite() && b.y.is_finite()) {
        return false;
    }
    let (n, delta) = samples(a, b, sample_step(world, robot_radius_m));
    // 1 µm more covers the f32 rounding of live points and queries.
    let need = (robot_radius_m * robot_radius_m + 0.25 * delta * delta).sqrt() + 1e-6;
    (0..=n).all(|j| world.clear_of(a + (b - a) * (j as f64 / n as f64), need))
}

/// True when every segment of the polyline `points` passes [`segment_clear`] (a single point must be clear
/// itself; an empty polyline is trivially clear).
pub fn verify(points: &[Point2], world: &World<'_>, robot_radius_m: f64) -> bool {
    match points {
        [] => true,
        [p] => world.clear_of(*p, robot_radius_m),
        _ => points
            .windows(2)
            .all(|w| segment_clear(w[0], w[1], world, robot_radius_m)),
    }
}
