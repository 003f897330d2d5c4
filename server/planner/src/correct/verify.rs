//! The last word on a candidate patch: every segment, sampled at most `min(resolution, radius) / 2` apart,
//! keeps the robot radius from the static map (DESIGN §6 metric: distance to the nearest non-free cell
//! centre) and from every live obstacle point, and stays on the map.
//!
//! Sampling is made exact for the continuous segment: between two samples δ apart that are both at least
//! ρ from an obstacle point, the segment stays at least √(ρ² − δ²/4) from it, so each sample must keep
//! √(r² + δ²/4) (a fraction of a millimetre more than r at the usual δ). Where a cheap lower bound of the
//! clearance ([`World::clearance_lower_bound`]) exceeds r + δ, the samples jump ahead by that excess
//! (sphere tracing: clearance is 1-Lipschitz, so every point skipped is clear). The map is a rectangle, so
//! both ends on the map mean the whole segment is.

use crate::geom::Point2;

use super::judge::sample_step;
use super::world::World;

/// True when the straight segment `a`–`b` (map frame, metres) keeps at least `robot_radius_m` from every
/// obstacle of `world` and lies on the map.
pub fn segment_clear(a: Point2, b: Point2, world: &World<'_>, robot_radius_m: f64) -> bool {
    if !(a.x.is_finite() && a.y.is_finite() && b.x.is_finite() && b.y.is_finite()) {
        return false;
    }
    let len = (b - a).norm();
    let delta = sample_step(world, robot_radius_m);
    // 1 µm more covers the f32 rounding of live points and queries.
    let need = (robot_radius_m * robot_radius_m + 0.25 * delta * delta).sqrt() + 1e-6;
    if !(world.inside(a) && world.inside(b)) {
        return false;
    }
    let dir = if len > 0.0 { (b - a) / len } else { (b - a) * 0.0 };
    let mut s = 0.0;
    loop {
        let q = a + dir * s;
        // Far from everything: every point within (lower bound − r) of q is clear (clearance is
        // 1-Lipschitz), so jump; near obstacles, step δ and demand the chord-sag clearance.
        let jump = world.clearance_lower_bound(q) - robot_radius_m - 1e-6;
        let advance = if jump > delta {
            jump
        } else if world.clear_of(q, need) {
            delta
        } else {
            return false;
        };
        if s >= len {
            return true;
        }
        s = (s + advance).min(len);
    }
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

/// Smallest clearance (live and static, capped at `upto`) along the polyline `points`, sampled every 2 cm,
/// metres (`upto` for fewer than two points).
pub fn min_clearance(points: &[Point2], world: &World<'_>, upto: f64) -> f64 {
    let mut best = upto;
    for w in points.windows(2) {
        let n = ((w[1] - w[0]).norm() / 0.02).ceil().max(1.0) as usize;
        for k in 0..=n {
            let q = w[0] + (w[1] - w[0]) * (k as f64 / n as f64);
            best = best.min(world.clearance_upto(q, upto));
        }
    }
    best
}
