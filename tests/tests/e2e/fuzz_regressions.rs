//! Every input a fuzzer ever found a crash with (`fuzz/regressions/TARGET/*`), and the seed corpus
//! (`fuzz/seeds/TARGET/*`), replayed through its target's body (`fuzz_feed.rs`) by the ordinary test run.

use std::path::Path;

use super::fuzz_feed::TARGETS;

#[test]
fn every_fuzz_regression_and_seed_is_refused_or_parsed_without_a_panic() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut replayed = 0;
    for (name, feed) in TARGETS {
        for kind in ["regressions", "seeds"] {
            let Ok(entries) = std::fs::read_dir(root.join(kind).join(name)) else {
                continue;
            };
            for entry in entries.flatten() {
                let path = entry.path();
                let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                let outcome = std::panic::catch_unwind(|| feed(&bytes));
                assert!(outcome.is_ok(), "{name}: {} panics", path.display());
                replayed += 1;
            }
        }
    }
    assert!(
        replayed >= TARGETS.len(),
        "only {replayed} files replayed: the seeds are missing"
    );
}

/// Writes the seed corpus (`fuzz/seeds/TARGET/`): one well-formed input per target, from the project's own
/// encoders and a shared scene. Run once when a target is added: `cargo test -p shift-tests --test e2e
/// write_fuzz_seeds -- --ignored`.
#[test]
#[ignore = "writes fuzz/seeds; run by hand when a target is added"]
fn write_fuzz_seeds() {
    use shift_proto::ros::laser_scan::{LaserScan, encode_laser_scan};
    use shift_proto::ros::odometry::{Odometry, encode_odometry};
    use shift_proto::ros::path::encode_path;
    use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
    use shift_proto::ros::{Header, Time};

    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/seeds");
    let header = Header {
        stamp: Time::from_ns(1_500_000_000),
        frame_id: "map".into(),
    };
    let scan = LaserScan {
        header: header.clone(),
        angle_min: -1.5,
        angle_max: 1.5,
        angle_increment: 0.5,
        range_min: 0.1,
        range_max: 10.0,
        ranges: vec![1.0, 2.0, f32::INFINITY, 0.05, 3.0, 4.0, 5.0],
        ..LaserScan::default()
    };
    let mut odom = Odometry {
        header: header.clone(),
        child_frame_id: "base_link".into(),
        ..Odometry::default()
    };
    odom.pose.pose.position.x = 1.0;
    odom.pose.pose.orientation.w = 1.0;
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenarios/four-rooms");
    let mut map = std::fs::read(scene.join("map.yaml")).expect("scene yaml");
    map.push(0);
    map.extend(std::fs::read(scene.join("map.pgm")).expect("scene image"));
    let seeds: Vec<(&str, Vec<u8>)> =
        vec![
        ("cdr_point_cloud2", encode_point_cloud2_xyz(&header, &[[1.0, 2.0, 0.5], [1.5, 2.0, 0.2]])),
        ("cdr_laser_scan", encode_laser_scan(&scan)),
        ("cdr_odometry", encode_odometry(&odom)),
        ("cdr_path", encode_path(&header, &[(0.0, 0.0, 0.0), (1.0, 0.5, 0.3)])),
        ("map_ros", map),
        (
            "map_json_grid",
            br#"{"width": 3, "height": 2, "resolution": 0.5, "origin": [0.0, 0.0], "cells": [0, 0, 100, -1, 0, 0]}"#
                .to_vec(),
        ),
        (
            "plan_request",
            br#"{"site": "s", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3},
                "region": [[0, 0], [3, 0], [3, 3], [0, 3]], "objective": "time", "snap_start_m": 0.5}"#
                .to_vec(),
        ),
        (
            "correction_json",
            br#"{"plan_id": "p-1", "robot": "r1", "base_version": 1, "version": 2, "from": 3, "to": 6,
                "waypoints": [{"x": 0.3, "y": 0.1, "z": 0, "v": 0.4, "t": 0.6, "kind": "cover", "region": 0}],
                "reason": "obstacle", "compute_us": 5}"#
                .to_vec(),
        ),
    ];
    for (name, bytes) in seeds {
        let dir = root.join(name);
        std::fs::create_dir_all(&dir).expect("seed dir");
        std::fs::write(dir.join("seed-0"), bytes).expect("seed");
    }
}
