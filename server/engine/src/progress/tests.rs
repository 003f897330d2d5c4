use shift_proto::{PlanMetricsDoc, WaypointDoc, WaypointKindDoc};

use super::*;

pub(crate) fn doc(points: &[(f64, f64)]) -> Arc<PlanDocument> {
    Arc::new(PlanDocument {
        plan_id: "p-1".into(),
        version: 1,
        frame: "map".into(),
        waypoints: points
            .iter()
            .map(|&(x, y)| WaypointDoc {
                x,
                y,
                z: 0.0,
                v: 0.5,
                t: 0.0,
                kind: WaypointKindDoc::Cover,
                region: None,
            })
            .collect(),
        regions: vec![],
        metrics: PlanMetricsDoc::default(),
    })
}

fn params(window: usize) -> ProgressParams {
    ProgressParams {
        tolerance_m: 0.3,
        window,
        back_confirm: 3,
    }
}

#[test]
fn progress_follows_the_path_in_order_even_where_it_crosses_itself() {
    // Out along y = 0 and back along the same line.
    let pts = [
        (0.0, 0.0),
        (1.0, 0.0),
        (2.0, 0.0),
        (3.0, 0.0),
        (2.0, 0.0),
        (1.0, 0.0),
        (0.0, 0.0),
    ];
    let p = params(2);
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    assert_eq!(a.advance(1.0, 0.05, None, &p), Advance::Forward);
    assert_eq!(a.index, 1, "the outbound (1,0), not the return one");
    a.advance(2.9, 0.0, None, &p);
    assert_eq!(a.index, 3);
    assert!((a.fraction() - 0.5).abs() < 1e-12);
    assert_eq!(
        a.advance(10.0, 10.0, None, &p),
        Advance::Stayed,
        "far away: no progress"
    );
    a.advance(1.0, 0.0, None, &p);
    a.advance(0.0, 0.0, None, &p);
    assert!(a.finished());
    assert!((a.driven_m() - 6.0).abs() < 1e-12);
}

#[test]
fn a_correction_moves_the_reached_index_past_the_patch() {
    let pts: Vec<(f64, f64)> = (0..6).map(|i| (i as f64, 0.0)).collect();
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    a.index = 4;
    // waypoints[1..3) (two) replaced by three.
    let new: Vec<(f64, f64)> = vec![
        (0.0, 0.0),
        (0.5, 0.5),
        (1.0, 0.6),
        (1.5, 0.5),
        (3.0, 0.0),
        (4.0, 0.0),
        (5.0, 0.0),
    ];
    a.corrected(doc(&new), 1, 3, 3);
    assert_eq!(a.index, 5, "still at (4, 0)");
    assert_eq!(a.doc.waypoints[a.index].x, 4.0);
    assert_eq!(a.plan_id, "p-1");
    // Inside the patch: back to the waypoint before it.
    a.index = 2;
    a.corrected(doc(&new), 2, 4, 1);
    assert_eq!(a.index, 1);
    // Before it: unchanged.
    a.index = 0;
    a.corrected(doc(&new), 2, 4, 1);
    assert_eq!(a.index, 0);
}

/// A figure eight: along y = 0 to the east, round, then along x = 5 to the north through (5, 0), where both
/// branches cross at right angles.
fn crossing_path() -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = (0..=100).map(|i| (i as f64 * 0.1, 0.0)).collect(); // (0,0) → (10,0)
    pts.extend((1..=50).map(|i| (10.0, -(i as f64) * 0.1))); // down to (10,-5)
    pts.extend((1..=50).map(|i| (10.0 - i as f64 * 0.1, -5.0))); // west to (5,-5)
    pts.extend((1..=100).map(|i| (5.0, -5.0 + i as f64 * 0.1))); // north to (5,5), crossing (5,0)
    pts
}

#[test]
fn at_a_self_crossing_the_heading_keeps_the_branch_being_driven() {
    let pts = crossing_path();
    let p = ProgressParams {
        window: 400,
        ..ProgressParams::default()
    };
    // Driving east through the crossing: both branches are in the window; progress stays on the east branch.
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    let mut last = 0;
    for i in 0..=100 {
        a.advance(i as f64 * 0.1, 0.02, Some(0.0), &p);
        assert!(a.index >= last, "monotone");
        last = a.index;
        assert!(
            a.index <= 100,
            "at x = {} jumped to the north branch ({})",
            i as f64 * 0.1,
            a.index
        );
    }
    // Then round and north through the same crossing: progress goes on along the north branch.
    for i in 1..=50 {
        a.advance(10.0, -(i as f64) * 0.1, Some(-std::f64::consts::FRAC_PI_2), &p);
    }
    for i in 1..=50 {
        a.advance(10.0 - i as f64 * 0.1, -5.0, Some(std::f64::consts::PI), &p);
    }
    for i in 1..=100 {
        a.advance(5.0, -5.0 + i as f64 * 0.1, Some(std::f64::consts::FRAC_PI_2), &p);
        assert!(a.index >= last, "monotone");
        last = a.index;
    }
    assert!(a.finished());
}

#[test]
fn a_robot_turning_at_its_dock_stays_on_the_first_pass_though_a_later_lane_passes_the_dock_its_way() {
    // East from the dock at (0, 0), round, and later north along x = 0.2, past the dock again.
    let mut pts: Vec<(f64, f64)> = (0..=50).map(|i| (i as f64 * 0.1, 0.0)).collect();
    pts.extend((1..=20).map(|i| (5.0, -(i as f64) * 0.1)));
    pts.extend((1..=48).map(|i| (5.0 - i as f64 * 0.1, -2.0)));
    pts.extend((1..=50).map(|i| (0.2, -2.0 + i as f64 * 0.1)));
    let p = ProgressParams {
        window: 400,
        ..ProgressParams::default()
    };
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    // Still facing north while it turns on the spot towards the first lane: the later lane agrees with its
    // heading, the first one does not; it has driven neither.
    for k in 0..=8 {
        let yaw = std::f64::consts::FRAC_PI_2 * (1.0 - f64::from(k) / 8.0);
        a.advance(0.01, 0.0, Some(yaw), &p);
        assert!(
            a.index <= 1,
            "turning at the dock (yaw {yaw:.2}) moved progress to {}",
            a.index
        );
    }
    // Then it drives the plan in order, through the later pass too.
    let mut last = 0;
    for (k, &(x, y)) in pts.iter().enumerate().skip(1) {
        let (px, py) = pts[k - 1];
        a.advance(x, y, Some((y - py).atan2(x - px)), &p);
        assert!(
            a.index >= last && a.index <= k,
            "at waypoint {k} progress is {}",
            a.index
        );
        last = a.index;
    }
    assert!(a.finished());
}

#[test]
fn a_robot_between_two_waypoints_of_a_detour_is_on_it_not_on_a_lane_that_runs_by_later() {
    // A detour's long straight piece (two waypoints 4 m apart), round, and later a lane the same way along
    // y = 0.3 with waypoints every 0.1 m.
    let mut pts = vec![(0.0, 0.0), (4.0, 0.0), (4.0, 2.0), (0.0, 2.0)];
    pts.extend((0..=40).map(|i| (i as f64 * 0.1, 0.3)));
    let p = ProgressParams {
        window: 400,
        ..ProgressParams::default()
    };
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    // Up to the tolerance before the detour's end.
    for k in 1..=34 {
        a.advance(k as f64 * 0.1, 0.02, Some(0.0), &p);
        assert_eq!(
            a.index,
            0,
            "at x = {:.1} on the detour progress went to {}",
            k as f64 * 0.1,
            a.index
        );
    }
    a.advance(3.95, 0.0, Some(0.0), &p);
    assert_eq!(a.index, 1, "the detour's end reached");
}

#[test]
fn a_robot_first_seen_far_along_its_plan_is_found_there() {
    let pts = crossing_path();
    let p = ProgressParams {
        window: 50,
        ..ProgressParams::default()
    };
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    // First pose: on the west leg, far beyond the window of a robot at waypoint 0.
    let got = a.advance(7.0, -5.02, Some(std::f64::consts::PI), &p);
    assert_eq!(got, Advance::Reacquired { from: 0, to: 180 });
    // A pose jump to the north branch at the crossing (relocalised), heading north: found there, not on the
    // east branch behind it, which crosses the same point.
    let got = a.advance(5.0, 0.0, Some(std::f64::consts::FRAC_PI_2), &p);
    assert_eq!(got, Advance::Reacquired { from: 180, to: 250 });
}

#[test]
fn progress_goes_back_only_when_the_robot_really_went_back() {
    let pts: Vec<(f64, f64)> = (0..=100).map(|i| (i as f64 * 0.1, 0.0)).collect();
    let p = ProgressParams {
        tolerance_m: 0.3,
        window: 20,
        back_confirm: 3,
    };
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    a.advance(8.0, 0.0, Some(0.0), &p);
    assert_eq!(a.index, 80);
    // One pose back at x = 2 (a localisation glitch): progress holds.
    assert_eq!(a.advance(2.0, 0.0, Some(0.0), &p), Advance::Stayed);
    assert_eq!(a.advance(8.1, 0.0, Some(0.0), &p), Advance::Forward);
    // Three in a row: the robot is back there.
    for _ in 0..2 {
        assert_eq!(a.advance(2.0, 0.0, Some(0.0), &p), Advance::Stayed);
    }
    assert_eq!(
        a.advance(2.0, 0.0, Some(0.0), &p),
        Advance::Reacquired { from: 81, to: 20 }
    );
    assert_eq!(a.index, 20);
}

#[test]
fn garbage_poses_change_nothing() {
    let pts: Vec<(f64, f64)> = (0..10).map(|i| (i as f64, 0.0)).collect();
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    let p = ProgressParams::default();
    for (x, y) in [(f64::NAN, 0.0), (0.0, f64::INFINITY), (1e300, -1e300)] {
        assert_eq!(a.advance(x, y, Some(f64::NAN), &p), Advance::Stayed);
    }
    assert_eq!(a.index, 0);
}

mod props {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        /// The grid's whole-plan search finds exactly what a scan of every waypoint finds.
        #[test]
        fn the_grid_finds_what_a_full_scan_finds(
            pts in prop::collection::vec((-20.0f64..20.0, -20.0f64..20.0), 2..200),
            x in -20.0f64..20.0,
            y in -20.0f64..20.0,
            tol in 0.1f64..3.0,
        ) {
            let d = doc(&pts);
            let grid = WaypointGrid::new(&d, tol);
            let mut got: Vec<usize> = grid
                .around(x, y)
                .filter(|&i| (d.waypoints[i].x - x).hypot(d.waypoints[i].y - y) <= tol)
                .collect();
            got.sort_unstable();
            let want: Vec<usize> = (0..pts.len())
                .filter(|&i| (pts[i].0 - x).hypot(pts[i].1 - y) <= tol)
                .collect();
            prop_assert_eq!(got, want);
        }
    }
}

#[test]
fn a_replaced_plan_waits_for_the_robot_at_its_start_before_searching_it() {
    // The new plan starts at (0, 0) and sweeps out to (5, 0) and back; the robot still drives its old plan
    // at (4, 0.1) heading +x, which the new one passes: without waiting that would be found far ahead.
    let pts: Vec<(f64, f64)> = (0..=10)
        .map(|i| (f64::from(i) * 0.5, 0.0))
        .chain((0..10).rev().map(|i| (f64::from(i) * 0.5, 1.0)))
        .collect();
    let p = params(3);
    let mut plain = Assignment::new("p-1".into(), doc(&pts));
    assert!(matches!(
        plain.advance(4.0, 0.1, Some(0.0), &p),
        Advance::Reacquired { .. }
    ));
    let mut a = Assignment::new("p-1".into(), doc(&pts));
    a.await_start = true;
    for x in [3.0, 3.5, 4.0, 4.5] {
        assert_eq!(
            a.advance(x, 0.1, Some(0.0), &p),
            Advance::Stayed,
            "still on its old plan at {x}"
        );
    }
    assert_eq!(a.index, 0);
    // It reaches the start and drives on: progress as usual from there.
    assert_eq!(a.advance(0.05, 0.0, Some(0.0), &p), Advance::Stayed);
    assert!(!a.await_start);
    assert_eq!(a.advance(1.0, 0.05, Some(0.0), &p), Advance::Forward);
    assert_eq!(a.index, 2);
}
