//! Property tests of the speed profile: bounds, the acceleration limit and monotonicity in A.

use proptest::prelude::*;

use super::time_param::{limit_acceleration, times};
use super::{AttributeBlob, AttributeMap, DwellLaw, SpeedLimits, SpeedParams, metric_attribute_floor, profile_path};
use crate::geom::Point2;
use crate::map::{CellState, GridGeometry, OccupancyGrid};
use crate::metrics::dwell::evaluate_dwell;
use crate::pipeline::{Waypoint, WaypointKind};
use crate::space::{CoverageSpace, RobotShape};

fn accel_ok(v: &[f64], seg: &[f64], a_max: f64) -> bool {
    v.windows(2)
        .zip(seg)
        .all(|(w, s)| (w[1] * w[1] - w[0] * w[0]).abs() <= 2.0 * a_max * s * 1.000_001 + 1e-12)
}

fn room() -> CoverageSpace {
    let g = GridGeometry::new(120, 40, 0.1, Point2::origin()).expect("valid");
    let robot = RobotShape {
        radius_m: 0.2,
        tool_width_m: 0.4,
    };
    CoverageSpace::new(OccupancyGrid::filled(g, CellState::Free), robot, Point2::new(0.5, 2.0)).expect("space")
}

/// A straight cover line along the room's middle, metres in the map frame.
fn line() -> Vec<Waypoint> {
    [0.3, 11.7]
        .iter()
        .map(|&x| Waypoint {
            position: Point2::new(x, 2.0),
            kind: WaypointKind::Cover,
            region: Some(0),
        })
        .collect()
}

proptest! {
    #[test]
    fn forward_backward_respects_caps_and_acceleration(
        caps in prop::collection::vec(0.1f64..1.0, 2..200),
        seg_seed in prop::collection::vec(0.0f64..0.5, 199),
        a_max in 0.05f64..2.0,
    ) {
        let seg = &seg_seed[..caps.len() - 1];
        let v = limit_acceleration(&caps, seg, a_max);
        prop_assert!(v.iter().zip(&caps).all(|(v, c)| *v <= *c + 1e-12 && *v >= 0.1 - 1e-12));
        prop_assert!(accel_ok(&v, seg, a_max));
        let t = times(&v, seg);
        prop_assert!(t.windows(2).all(|w| w[1] >= w[0]));
    }

    #[test]
    fn law_speed_is_bounded_and_falls_as_a_grows(lo in 0.0f64..1.0, span in 0.0f64..1.0, a in 0.0f64..1.0, b in 0.0f64..1.0) {
        let limits = SpeedLimits::default();
        let law = DwellLaw::for_range(lo, (lo + span).min(1.0), 0.4, &limits);
        let (va, vb) = (law.speed(a), law.speed(b));
        prop_assert!((0.1..=1.0).contains(&va) && (0.1..=1.0).contains(&vb));
        if a <= b {
            prop_assert!(va >= vb);
        }
    }

    #[test]
    fn straight_line_speed_is_monotone_in_a(lo in 0.0f64..0.9, rise in 0.05f64..1.0, v_min in 0.05f64..0.5, a_max in 0.1f64..2.0) {
        // A grows along the line; the open-loop profile rises from v_min at the start to the law's speed and
        // then never rises again: slower where A is higher.
        let space = room();
        let g = *space.geometry();
        let values = (0..g.len()).map(|i| (lo + rise * g.center_of(i).x / 12.0).min(1.0)).collect();
        let attr = AttributeMap::from_values(g, values).expect("attr");
        let limits = SpeedLimits::new(v_min, 1.0, a_max);
        let params = SpeedParams { refine_iterations: 0, smooth: None, ..SpeedParams::new(limits, 0.4) };
        let p = profile_path(&space, &line(), Some(&attr), &params).expect("profile");
        let v: Vec<f64> = p.waypoints.iter().map(|w| w.speed_mps).collect();
        let peak = v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map_or(0, |(i, _)| i);
        prop_assert!(v[..=peak].windows(2).all(|w| w[1] >= w[0] - 1e-12));
        prop_assert!(v[peak..].windows(2).all(|w| w[1] <= w[0] + 1e-12), "{v:?}");
        prop_assert!(p.waypoints.iter().all(|w| w.speed_mps <= p.law.speed(attr.at_point(w.waypoint.position)) + 1e-9));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn refined_profiles_keep_bounds_and_acceleration(
        bx in 1.0f64..11.0, by in 0.5f64..3.5, sigma in 0.3f64..3.0, amp in 0.1f64..1.5,
        v_min in 0.05f64..0.4, v_max in 0.5f64..2.0, a_max in 0.1f64..1.5,
    ) {
        let space = room();
        let attr = AttributeMap::from_blobs(*space.geometry(), &[AttributeBlob { centre: Point2::new(bx, by), sigma_m: sigma, amplitude: amp }]).expect("attr");
        // Boustrophedon over the room.
        let mut path = Vec::new();
        for k in 0..9 {
            let y = 0.2 + 0.4 * f64::from(k);
            let xs = if k % 2 == 0 { [0.2, 11.8] } else { [11.8, 0.2] };
            for x in xs {
                path.push(Waypoint { position: Point2::new(x, y.min(3.8)), kind: WaypointKind::Cover, region: Some(0) });
            }
        }
        let limits = SpeedLimits::new(v_min, v_max, a_max);
        let params = SpeedParams::new(limits, 0.4);
        let p = profile_path(&space, &path, Some(&attr), &params).expect("profile");
        let v: Vec<f64> = p.waypoints.iter().map(|w| w.speed_mps).collect();
        let seg: Vec<f64> = p.waypoints.windows(2).map(|w| w[1].arc_m - w[0].arc_m).collect();
        prop_assert!(v.iter().all(|v| *v >= v_min - 1e-9 && *v <= v_max + 1e-9));
        prop_assert!(accel_ok(&v, &seg, a_max));
        prop_assert_eq!(p.metrics.collisions, 0);
        prop_assert!(p.dwell.dwell_cv <= p.open_loop_dwell_cv + 1e-12);
        // Time is the objective: the refinement adds at most `extra_time`, and nothing when the open-loop law
        // is already within the uniformity goal.
        let open = profile_path(&space, &path, Some(&attr), &SpeedParams { refine_iterations: 0, ..params })
            .expect("open loop");
        let (t, t0) = (p.dwell.duration_s, open.dwell.duration_s);
        prop_assert!(t <= t0 * (1.0 + params.extra_time) * (1.0 + 1e-6), "{t} vs open loop {t0}");
        if p.open_loop_dwell_cv < super::refine::UNIFORMITY_GOAL * p.dwell.dwell_cv_const_speed - 1e-9 {
            prop_assert!((t - t0).abs() <= 1e-6 * t0, "{t} vs open loop {t0}");
        }
        // The figures the profile takes over from the refinement are the metric's own, recomputed from the
        // timed waypoints.
        let working: Vec<bool> = p.waypoints[1..].iter().map(|w| w.waypoint.kind == WaypointKind::Cover).collect();
        let a_hi = attr.range_over(&space.coverable).map_or(1.0, |r| r.1);
        let again = evaluate_dwell(&space, &p.points(), &v, &working, &attr, metric_attribute_floor(a_hi, &limits));
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12);
        prop_assert!(close(again.dwell_cv, p.dwell.dwell_cv), "{again:?} vs {:?}", p.dwell);
        prop_assert!(close(again.dwell_cv_const_speed, p.dwell.dwell_cv_const_speed), "{again:?} vs {:?}", p.dwell);
        prop_assert!(close(again.duration_s, p.dwell.duration_s), "{again:?} vs {:?}", p.dwell);
    }
}
