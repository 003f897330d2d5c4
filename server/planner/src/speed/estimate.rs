//! How long a path takes to drive, before it is final: the time objective's estimate (DESIGN §6
//! `duration_s` without an attribute map). Every corner is rounded as smoothing would round it
//! ([`crate::smooth::corners::round_every_corner`]: leg up to the smoothing's `max_leg_m`, reversals sharp),
//! each sample gets the speed its curvature allows under the lateral bound, the acceleration bound is applied
//! forwards and backwards, and the times are summed — the same steps as [`super::profile_path`] without the
//! checks against the map and without an attribute to follow. On a path that smoothing rounds fully, it is
//! the profile's duration.

use crate::pipeline::Waypoint;
use crate::smooth::SmoothParams;
use crate::smooth::corners::round_every_corner;

use super::SpeedLimits;
use super::samples::resample;
use super::time_param::{limit_acceleration, times};

/// Seconds to drive `path` (map frame, metres) at the fastest speeds `limits` allow, with its corners
/// rounded by `smooth` and samples at most `spacing_m` apart (the profile's spacing is a quarter of the
/// tool width). A path of fewer than two distinct points takes no time.
pub fn drive_time(path: &[Waypoint], limits: &SpeedLimits, smooth: &SmoothParams, spacing_m: f64) -> f64 {
    drive_timeline(path, limits, smooth, spacing_m)
        .last()
        .map_or(0.0, |&(_, t)| t)
}

/// [`drive_time`] sample by sample: (arc length along the rounded path, metres; seconds from its start), from
/// (0, 0) to the whole path's length and time. Empty for a path of fewer than two distinct points.
pub fn drive_timeline(
    path: &[Waypoint],
    limits: &SpeedLimits,
    smooth: &SmoothParams,
    spacing_m: f64,
) -> Vec<(f64, f64)> {
    let rounded = round_every_corner(path, smooth);
    if rounded.waypoints.len() < 2 || !(spacing_m.is_finite() && spacing_m > 0.0) {
        return Vec::new();
    }
    let samples = resample(&rounded, spacing_m, limits);
    let v = limit_acceleration(&samples.caps, &samples.seg, limits.a_max_mps2);
    let t = times(&v, &samples.seg);
    let mut arc = 0.0;
    (t.iter().enumerate())
        .map(|(i, &t)| {
            if i > 0 {
                arc += samples.seg[i - 1];
            }
            (arc, t)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;
    use crate::pipeline::WaypointKind;

    fn path(points: &[(f64, f64)]) -> Vec<Waypoint> {
        points
            .iter()
            .map(|&(x, y)| Waypoint {
                position: Point2::new(x, y),
                kind: WaypointKind::Cover,
                region: Some(0),
            })
            .collect()
    }

    /// Analytic time of a straight run of `s` metres from v_min to v_min under v_max and a_max.
    fn straight(s: f64, l: &SpeedLimits) -> f64 {
        let (v0, vm, a) = (l.v_min_mps, l.v_max_mps, l.a_max_mps2);
        let ramp = (vm * vm - v0 * v0) / (2.0 * a);
        if 2.0 * ramp <= s {
            2.0 * (vm - v0) / a + (s - 2.0 * ramp) / vm
        } else {
            let peak = (a * s + v0 * v0).sqrt();
            2.0 * (peak - v0) / a
        }
    }

    #[test]
    fn a_straight_run_takes_the_trapezoid_time() {
        let l = SpeedLimits::default();
        let smooth = SmoothParams::for_tool(0.5);
        for s in [0.3, 1.0, 2.5, 10.0, 100.0] {
            let t = drive_time(&path(&[(0.0, 0.0), (s, 0.0)]), &l, &smooth, 0.05);
            let want = straight(s, &l);
            assert!((t - want).abs() < 0.02 * want + 0.05, "{s} m: {t} s, want {want} s");
        }
    }

    #[test]
    fn turns_cost_time() {
        let l = SpeedLimits::default();
        let smooth = SmoothParams::for_tool(0.5);
        let t = |pts: &[(f64, f64)]| drive_time(&path(pts), &l, &smooth, 0.1);
        let straight = t(&[(0.0, 0.0), (20.0, 0.0)]);
        // The same length with one right angle in the middle, with a U-turn on a 0.5 m step (two right
        // angles, rounded with half-step legs: tighter), and with a reversal (sharp: v_min at one point).
        let corner = t(&[(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)]);
        let lanes = t(&[(0.0, 0.0), (9.75, 0.0), (9.75, 0.5), (0.0, 0.5)]);
        let spike = t(&[(0.0, 0.0), (10.0, 0.0), (0.0, 0.0)]);
        assert!(straight < corner, "{straight} < {corner}");
        assert!(corner < lanes, "{corner} < {lanes}");
        assert!(straight < spike, "{straight} < {spike}");
        // A right angle rounded with a 0.5 m leg allows about √(a_lat · r): far above v_min.
        assert!(
            corner - straight < 3.0,
            "one rounded corner costs {} s",
            corner - straight
        );
    }

    #[test]
    fn degenerate_paths_take_no_time() {
        let l = SpeedLimits::default();
        let smooth = SmoothParams::for_tool(0.5);
        assert_eq!(drive_time(&path(&[]), &l, &smooth, 0.1), 0.0);
        assert_eq!(drive_time(&path(&[(1.0, 1.0), (1.0, 1.0)]), &l, &smooth, 0.1), 0.0);
        assert_eq!(drive_time(&path(&[(0.0, 0.0), (1.0, 0.0)]), &l, &smooth, f64::NAN), 0.0);
    }
}
