use shift_proto::ros::laser_scan::encode_laser_scan;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_proto::ros::{Header, Time};

use super::*;

const SEC: i64 = 1_000_000_000;

fn header(frame: &str, ns: i64) -> Header {
    Header {
        stamp: Time::from_ns(ns),
        frame_id: frame.into(),
    }
}

/// One beam straight ahead, 1 m.
fn scan(ns: i64) -> Vec<u8> {
    encode_laser_scan(&LaserScan {
        header: header("laser", ns),
        angle_min: 0.0,
        angle_max: 0.0,
        angle_increment: 0.1,
        range_min: 0.1,
        range_max: 10.0,
        ranges: vec![1.0],
        ..LaserScan::default()
    })
}

fn odom(x: f64, ns: i64) -> FramedPose {
    FramedPose {
        pose: Pose2 {
            x,
            y: 0.0,
            yaw: 0.0,
            stamp_ns: ns,
        },
        frame: "odom".into(),
    }
}

fn hub(default_site: Option<&str>) -> SensorHub {
    SensorHub::new(SensorParams {
        default_site: default_site.map(str::to_owned),
        wait_ms: 500,
        wait_max: 3,
        ..SensorParams::default()
    })
}

fn placed(o: &[Outcome]) -> Vec<&Placed> {
    o.iter()
        .filter_map(|o| match o {
            Outcome::Placed(p) => Some(p),
            Outcome::Dropped(_) => None,
        })
        .collect()
}

fn dropped(o: &[Outcome]) -> Vec<&Dropped> {
    o.iter()
        .filter_map(|o| match o {
            Outcome::Dropped(d) => Some(d),
            Outcome::Placed(_) => None,
        })
        .collect()
}

#[test]
fn an_unassigned_robot_without_a_default_site_feeds_nothing_and_is_warned_about_once() {
    let mut h = hub(None);
    let cloud = encode_point_cloud2_xyz(&header("map", SEC), &[[1.0, 1.0, 0.5]]);
    let first = h.sensor("r1", Stream::Cloud, &cloud, 0);
    let second = h.sensor("r1", Stream::Cloud, &cloud, 1);
    assert_eq!(dropped(&first)[0].reason, DropReason::Unrouted);
    assert!(dropped(&first)[0].first);
    assert!(!dropped(&second)[0].first, "one warning per robot");
    let counts = h.counts("r1").expect("counted");
    assert_eq!(counts.dropped.get("unrouted"), Some(&2));
    assert_eq!(counts.site, None);

    // Assigned: its points go to the plan's site.
    assert_eq!(h.route("r1", Some("hall".into())), Some((None, Some("hall".into()))));
    let out = h.sensor("r1", Stream::Cloud, &cloud, 2);
    assert_eq!(placed(&out)[0].site, "hall");
    assert_eq!(placed(&out)[0].points, vec![[1.0, 1.0, 0.5]]);
    assert_eq!(h.route("r1", Some("hall".into())), None, "no change");
}

#[test]
fn the_default_site_takes_unassigned_robots_and_assignment_moves_the_feed() {
    let mut h = hub(Some("demo"));
    assert_eq!(h.site_of("r1"), Some("demo"));
    assert_eq!(
        h.route("r1", Some("hall".into())),
        Some((Some("demo".into()), Some("hall".into())))
    );
    assert_eq!(h.site_of("r1"), Some("hall"));
    assert_eq!(h.route("r1", None), Some((Some("hall".into()), Some("demo".into()))));
}

#[test]
fn a_scan_that_arrives_before_its_odometry_waits_for_it() {
    let mut h = hub(Some("demo"));
    assert!(h.odometry("r1", odom(0.0, SEC), 0).pose.is_some());
    // Stamped 2 s: newer than the newest pose (1 s) beyond the 0.1 s tolerance.
    assert!(h.sensor("r1", Stream::Scan, &scan(2 * SEC), 10).is_empty(), "waits");
    assert_eq!(h.counts("r1").map(|c| c.waiting), Some(1));
    let out = h.odometry("r1", odom(2.0, 2 * SEC), 20);
    let p = placed(&out.released);
    assert_eq!(p.len(), 1);
    assert!(p[0].waited);
    // Placed with the pose at its stamp: robot at x = 2, beam 1 m ahead.
    assert!((p[0].points[0][0] - 3.0).abs() < 1e-6, "{:?}", p[0].points);
    assert_eq!(h.counts("r1").map(|c| c.waiting), Some(0));
}

#[test]
fn a_scan_just_ahead_of_the_newest_pose_waits_for_the_next_one_before_the_tolerance_stands_in() {
    let mut h = hub(Some("demo"));
    h.odometry("r1", odom(0.0, SEC), 0);
    // 50 ms after the newest pose: within the 0.1 s tolerance, yet the odometry at its stamp is on its way.
    assert!(
        h.sensor("r1", Stream::Scan, &scan(SEC + SEC / 20), 10).is_empty(),
        "waits"
    );
    let out = h.odometry("r1", odom(1.0, SEC + SEC / 10), 20);
    let p = placed(&out.released);
    // Interpolated halfway: robot at x = 0.5, beam 1 m ahead (the end pose would have said 1.0).
    assert!((p[0].points[0][0] - 1.5).abs() < 1e-6, "{:?}", p[0].points);
    // With no newer odometry by its deadline, the end pose within the tolerance stands in.
    assert!(
        h.sensor("r1", Stream::Scan, &scan(SEC + SEC / 10 + SEC / 20), 30)
            .is_empty()
    );
    let out = h.expire(530);
    let p = placed(&out);
    assert!((p[0].points[0][0] - 2.0).abs() < 1e-6, "{:?}", p[0].points);
}

#[test]
fn a_robot_whose_clock_restarts_is_placed_on_its_new_clock() {
    // A robot ran for an hour of its clock, then restarted: its stamps begin again near zero.
    let mut h = hub(Some("demo"));
    for k in 0..5 {
        h.odometry("r1", odom(9.0, 3600 * SEC + k * SEC / 10), 0);
    }
    let out = h.odometry("r1", odom(1.0, 2 * SEC), 10);
    assert!(out.clock_jumped_back && out.pose.is_some());
    // Before the fix the scan was dropped at once as older than the hour-old history.
    let out = h.sensor("r1", Stream::Scan, &scan(2 * SEC + SEC / 20), 20);
    assert!(out.is_empty(), "waits for the odometry at its stamp: {out:?}");
    let next = h.odometry("r1", odom(1.1, 2 * SEC + SEC / 10), 30);
    assert!(!next.clock_jumped_back);
    let p = placed(&next.released);
    assert_eq!(p.len(), 1, "{:?}", next.released);
    // Placed with the new clock's poses (x = 1.05 at its stamp), not the hour-old one (x = 9).
    assert!((p[0].points[0][0] - 2.05).abs() < 1e-6, "{:?}", p[0].points);
}

#[test]
fn a_scan_whose_odometry_never_comes_is_dropped_at_its_deadline_with_the_lookup_reason() {
    let mut h = hub(Some("demo"));
    h.odometry("r1", odom(0.0, SEC), 0);
    assert!(h.sensor("r1", Stream::Scan, &scan(5 * SEC), 100).is_empty());
    assert!(h.expire(599).is_empty(), "before the deadline");
    assert_eq!(h.next_deadline_ms(), Some(600));
    let out = h.expire(600);
    assert_eq!(dropped(&out)[0].reason, DropReason::Future);
    // A robot with no odometry at all.
    assert!(h.sensor("r2", Stream::Scan, &scan(5 * SEC), 100).is_empty());
    assert_eq!(dropped(&h.expire(700))[0].reason, DropReason::NoPose);
    assert_eq!(h.next_deadline_ms(), None);
}

#[test]
fn waiting_is_bounded_per_robot_oldest_first() {
    let mut h = hub(Some("demo"));
    for i in 0..3 {
        assert!(h.sensor("r1", Stream::Scan, &scan((10 + i) * SEC), 0).is_empty());
    }
    let out = h.sensor("r1", Stream::Scan, &scan(13 * SEC), 0);
    assert_eq!(dropped(&out)[0].reason, DropReason::WaitFull);
    assert_eq!(h.counts("r1").map(|c| c.waiting), Some(3));
}

#[test]
fn a_scan_older_than_the_history_is_dropped_and_a_cloud_takes_the_latest_pose() {
    let mut h = hub(Some("demo"));
    for s in 10..20 {
        h.odometry("r1", odom(s as f64, s * SEC), 0);
    }
    let out = h.sensor("r1", Stream::Scan, &scan(SEC), 0);
    assert_eq!(dropped(&out)[0].reason, DropReason::TooOld);
    let cloud = encode_point_cloud2_xyz(&header("base_link", SEC), &[[1.0, 0.0, 0.5]]);
    let out = h.sensor("r1", Stream::Cloud, &cloud, 0);
    assert!(
        (placed(&out)[0].points[0][0] - 20.0).abs() < 1e-6,
        "latest pose x = 19, +1 m"
    );
}

#[test]
fn odometry_in_a_frame_the_daemon_cannot_place_is_reported_not_used() {
    let mut h = hub(Some("demo"));
    let mut pose = odom(1.0, SEC);
    pose.frame = "utm".into();
    let out = h.odometry("r1", pose, 0);
    assert!(out.pose.is_none());
    let rejected = out.rejected.expect("rejected");
    assert_eq!(rejected.reason, DropReason::Frame);
    assert!(rejected.first);
    assert!(rejected.detail.contains("utm"), "{}", rejected.detail);
    assert_eq!(h.latest_pose("r1"), None);
    let mut map = odom(1.0, SEC);
    map.frame = "/map".into();
    assert!(
        h.odometry("r1", map, 0).pose.is_some(),
        "a leading slash is the same frame"
    );
}

#[test]
fn garbage_is_counted_as_malformed() {
    let mut h = hub(Some("demo"));
    let out = h.sensor("r1", Stream::Cloud, b"\x00\x01garbage", 0);
    assert_eq!(dropped(&out)[0].reason, DropReason::Malformed);
    let out = h.sensor("r1", Stream::Scan, &[], 0);
    assert_eq!(dropped(&out)[0].reason, DropReason::Malformed);
    let mut nan = odom(f64::NAN, SEC);
    nan.frame.clear();
    assert_eq!(
        h.odometry("r1", nan, 0).rejected.map(|d| d.reason),
        Some(DropReason::Malformed)
    );
}

#[test]
fn memory_counts_what_waits_for_its_pose_within_the_wait_bound_and_lets_it_go() {
    let mut h = hub(Some("demo"));
    h.odometry("r1", odom(0.0, SEC), 0);
    let idle = h.memory_bytes();
    assert!(idle >= size_of::<Pose2>(), "the pose history: {idle}");
    // Scans of 1 000 beams stamped after the newest pose: they wait, at most wait_max (3) of them.
    let beams = 1000;
    let big = |ns| {
        encode_laser_scan(&LaserScan {
            header: header("laser", ns),
            angle_min: -1.0,
            angle_max: 1.0,
            angle_increment: 2.0 / (beams - 1) as f32,
            range_min: 0.1,
            range_max: 10.0,
            ranges: vec![1.0; beams],
            ..LaserScan::default()
        })
    };
    for k in 0..10 {
        h.sensor("r1", Stream::Scan, &big(2 * SEC + k), 10 + k as u64);
    }
    let waiting = h.memory_bytes() - idle;
    let scan_bytes = beams * size_of::<f32>();
    assert!(
        (3 * scan_bytes..4 * scan_bytes).contains(&waiting),
        "{waiting} bytes waiting for 3 scans of {scan_bytes}"
    );
    // The odometry that places them: they leave the hub, and so do their beams.
    let out = h.odometry("r1", odom(2.0, 3 * SEC), 20);
    assert_eq!(placed(&out.released).len(), 3);
    assert!(
        h.memory_bytes() < idle + scan_bytes,
        "{} after release",
        h.memory_bytes()
    );
}
