//! Speeds and times for a patch: the replaced stretch's speeds carried over (they hold the RFICP dwell
//! intent), capped by curvature, acceleration-limited, and times that continue the plan's clock.

use crate::geom::Point2;
use crate::speed::SpeedLimits;
use crate::speed::samples::curvature_cap;
use crate::speed::time_param::{limit_acceleration, segment_duration};

use super::error::CorrectError;
use super::judge::waypoint_curvature;

/// A waypoint of a timed plan: position (map frame, metres), speed (m/s) and time from the plan's start
/// (seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimedWaypoint {
    /// Position, map frame, metres.
    pub position: Point2,
    /// Speed at the waypoint, m/s.
    pub v_mps: f64,
    /// Time at the waypoint from the plan's start, seconds.
    pub t_s: f64,
}

/// Speeds and times of a patch's waypoints.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Retimed {
    /// Speed at each patch waypoint, m/s.
    pub v_mps: Vec<f64>,
    /// Time at each patch waypoint from the plan's start, seconds.
    pub t_s: Vec<f64>,
    /// How much later (seconds, negative: earlier) the waypoint after the patch (`path[to]`) and every one
    /// after it is now reached; 0 when nothing follows the patch.
    pub dt_after_s: f64,
}

/// Retimes `patch` (the waypoints of a [`super::Repair`], map frame, metres).
///
/// - `before`: the kept waypoint just before the patch (`path[from − 1]`), whose speed is the entry speed
///   and whose time the patch's clock continues from; `None` when the patch starts the plan.
/// - `replaced`: the original timed waypoints `path[from..to)`; each patch waypoint takes the speed of the
///   nearest of them (or of `before`/`after` when none was replaced).
/// - `after`: the kept waypoint just after the patch (`path[to]`); its speed is the exit speed the patch
///   must be able to meet; `None` when the patch ends the plan.
///
/// Speeds are capped by curvature (√(a_lat / κ), [`curvature_cap`]) and clamped to [v_min, v_max], then
/// acceleration-limited forward and backward ([`limit_acceleration`]) with the entry speed held.
pub fn retime(
    before: Option<&TimedWaypoint>,
    replaced: &[TimedWaypoint],
    after: Option<&TimedWaypoint>,
    patch: &[Point2],
    limits: &SpeedLimits,
) -> Result<Retimed, CorrectError> {
    limits.validate().map_err(|e| CorrectError::InvalidParam {
        name: "speed limits",
        reason: e.to_string(),
    })?;
    let finite = |w: &TimedWaypoint| {
        w.position.x.is_finite() && w.position.y.is_finite() && w.v_mps.is_finite() && w.t_s.is_finite()
    };
    if before.is_some_and(|w| !finite(w))
        || after.is_some_and(|w| !finite(w))
        || replaced.iter().any(|w| !finite(w))
        || patch.iter().any(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(CorrectError::BadPath(
            "a timed waypoint or patch point is not finite".into(),
        ));
    }
    if patch.is_empty() {
        return Ok(Retimed {
            dt_after_s: match (before, after) {
                (Some(b), Some(a)) => {
                    let v0 = b.v_mps.max(limits.v_min_mps);
                    let v1 = a.v_mps.max(limits.v_min_mps);
                    b.t_s + segment_duration((a.position - b.position).norm(), v0, v1) - a.t_s
                }
                _ => 0.0,
            },
            ..Retimed::default()
        });
    }
    let clamp = |v: f64| v.clamp(limits.v_min_mps, limits.v_max_mps);
    // The full chain: before, patch..., after.
    let mut pts: Vec<Point2> = Vec::with_capacity(patch.len() + 2);
    pts.extend(before.map(|w| w.position));
    pts.extend_from_slice(patch);
    pts.extend(after.map(|w| w.position));
    let off = usize::from(before.is_some());
    let mut caps = Vec::with_capacity(pts.len());
    if let Some(b) = before {
        caps.push(clamp(b.v_mps));
    }
    for (i, q) in patch.iter().enumerate() {
        let nearest = replaced.iter().chain(before).chain(after).min_by(|a, b| {
            (a.position - q)
                .norm_squared()
                .total_cmp(&(b.position - q).norm_squared())
        });
        let v = nearest.map_or(limits.v_max_mps, |w| w.v_mps);
        let kappa = waypoint_curvature(&pts, i + off);
        caps.push(clamp(v).min(curvature_cap(kappa, limits)));
    }
    if let Some(a) = after {
        caps.push(clamp(a.v_mps));
    }
    let seg: Vec<f64> = pts.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    let mut v = limit_acceleration(&caps, &seg, limits.a_max_mps2);
    if let (Some(b), Some(first)) = (before, v.first_mut()) {
        // The robot is already there at this speed.
        *first = clamp(b.v_mps);
    }
    let t_start = before.map_or_else(|| replaced.first().map_or(0.0, |w| w.t_s), |w| w.t_s);
    let mut t = Vec::with_capacity(pts.len());
    let mut now = t_start;
    t.push(now);
    for i in 0..seg.len() {
        now += segment_duration(seg[i], v[i], v[i + 1]);
        t.push(now);
    }
    let dt_after_s = after.map_or(0.0, |a| t[t.len() - 1] - a.t_s);
    let range = off..off + patch.len();
    Ok(Retimed {
        v_mps: v[range.clone()].to_vec(),
        t_s: t[range].to_vec(),
        dt_after_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tw(x: f64, y: f64, v: f64, t: f64) -> TimedWaypoint {
        TimedWaypoint {
            position: Point2::new(x, y),
            v_mps: v,
            t_s: t,
        }
    }

    #[test]
    fn carries_speeds_and_shifts_later_times() {
        let limits = SpeedLimits::new(0.1, 1.0, 0.5);
        let before = tw(0.0, 0.0, 0.5, 10.0);
        let replaced = [tw(1.0, 0.0, 0.5, 12.0), tw(2.0, 0.0, 0.5, 14.0)];
        let after = tw(3.0, 0.0, 0.5, 16.0);
        // The same straight line: nothing changes.
        let same = [Point2::new(1.0, 0.0), Point2::new(2.0, 0.0)];
        let r = retime(Some(&before), &replaced, Some(&after), &same, &limits).expect("ok");
        assert!(r.v_mps.iter().all(|v| (v - 0.5).abs() < 1e-12));
        assert!((r.t_s[0] - 12.0).abs() < 1e-9 && (r.t_s[1] - 14.0).abs() < 1e-9);
        assert!(r.dt_after_s.abs() < 1e-9);
        // A detour is longer: later waypoints shift, the corner slows the robot.
        let limits = SpeedLimits {
            a_lat_mps2: 0.2,
            ..limits
        };
        let detour = [Point2::new(1.0, 0.0), Point2::new(1.5, 1.0), Point2::new(2.0, 0.0)];
        let r = retime(Some(&before), &replaced, Some(&after), &detour, &limits).expect("ok");
        assert_eq!(r.v_mps.len(), 3);
        assert!(r.dt_after_s > 0.0);
        assert!(r.t_s.windows(2).all(|w| w[1] > w[0]));
        assert!(r.v_mps.iter().all(|&v| (0.1..=1.0).contains(&v)));
        assert!(r.v_mps[1] < 0.5);
        // Nothing after: no shift; nothing before: the clock starts at the first replaced waypoint.
        let r = retime(None, &replaced, None, &same, &limits).expect("ok");
        assert_eq!(r.dt_after_s, 0.0);
        assert!((r.t_s[0] - 12.0).abs() < 1e-12);
        assert!(retime(None, &replaced, None, &[Point2::new(f64::NAN, 0.0)], &limits).is_err());
    }
}
