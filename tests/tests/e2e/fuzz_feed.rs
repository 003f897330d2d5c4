//! One input through each parser that takes bytes from outside: the bodies of the cargo-fuzz targets in `fuzz/`
//! (which include this file by path) and of the regression test that replays every file under
//! `fuzz/regressions/TARGET/` (`fuzz_regressions.rs`). A parser may refuse its input; it must never panic,
//! hang or allocate without bound.

use shift_engine::robots::Pose2;
use shift_engine::sensors::geometry::{SensorOffset, scan_to_map};
use shift_planner::geom::Point2;
use shift_planner::map::json_grid::JsonGrid;
use shift_planner::map::{CellState, GridGeometry, OccupancyGrid, load_ros_map};
use shift_proto::keys::{KeySpace, Ros2Mapping};
use shift_proto::ros::laser_scan::decode_laser_scan;
use shift_proto::ros::odometry::{decode_odom_payload, decode_odometry};
use shift_proto::ros::path::decode_path;
use shift_proto::ros::point_cloud2::{decode_cloud_xyz, decode_point_cloud2};
use shift_proto::{CorrectionDoc, PlanDocument, PlanMetricsDoc, PlanRequest, WaypointDoc, WaypointKindDoc};
use shiftd::replay::{Action, KeyMap, Recorded, into_engine};

/// A target's body: one input, any bytes.
pub type Feed = fn(&[u8]);

/// Every target: its name (the folder of its regressions and corpus) and its body.
pub const TARGETS: &[(&str, Feed)] = &[
    ("cdr_point_cloud2", cdr_point_cloud2),
    ("cdr_laser_scan", cdr_laser_scan),
    ("cdr_odometry", cdr_odometry),
    ("cdr_path", cdr_path),
    ("map_ros", map_ros),
    ("map_json_grid", map_json_grid),
    ("plan_request", plan_request),
    ("correction_json", correction_json),
    ("mcap_replay", mcap_replay),
];

/// sensor_msgs/PointCloud2 as a whole and as the ingest's xyz view.
pub fn cdr_point_cloud2(data: &[u8]) {
    let _ = decode_point_cloud2(data);
    let _ = decode_cloud_xyz(data);
}

/// sensor_msgs/LaserScan, then its beams into map-frame points as the ingest places them.
pub fn cdr_laser_scan(data: &[u8]) {
    if let Ok(scan) = decode_laser_scan(data) {
        let pose = Pose2 {
            x: 1.0,
            y: 2.0,
            yaw: 0.5,
            stamp_ns: 0,
        };
        let offset = SensorOffset {
            x_m: 0.1,
            y_m: 0.0,
            yaw_rad: 0.0,
        };
        let _ = scan_to_map(&scan, pose, offset);
    }
}

/// nav_msgs/Odometry, and the odometry payload as CDR or JSON.
pub fn cdr_odometry(data: &[u8]) {
    let _ = decode_odometry(data);
    let _ = decode_odom_payload(data, None);
    let _ = decode_odom_payload(data, Some("application/json"));
}

/// nav_msgs/Path.
pub fn cdr_path(data: &[u8]) {
    let _ = decode_path(data);
}

/// A ROS map_server YAML and its image: the YAML is the input up to its first NUL byte, the image the rest.
pub fn map_ros(data: &[u8]) {
    let (yaml, image) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let _ = load_ros_map(&String::from_utf8_lossy(yaml), |_| Ok(image.to_vec()));
}

/// The JSON occupancy grid of `POST /v1/sites/{site}/map`.
pub fn map_json_grid(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data)
        && let Ok(grid) = JsonGrid::parse(text)
    {
        let _ = grid.into_grid();
    }
}

/// A plan request, validated against a free 4 m × 4 m site.
pub fn plan_request(data: &[u8]) {
    let Ok(request) = serde_json::from_slice::<PlanRequest>(data) else {
        return;
    };
    if let Ok(geometry) = GridGeometry::new(40, 40, 0.1, Point2::new(0.0, 0.0)) {
        let grid = OccupancyGrid::filled(geometry, CellState::Free);
        let _ = shift_engine::request::validate(&request, &grid);
    }
}

/// A correction, applied to a 20-waypoint plan at its base version.
pub fn correction_json(data: &[u8]) {
    let Ok(correction) = serde_json::from_slice::<CorrectionDoc>(data) else {
        return;
    };
    let doc = PlanDocument {
        plan_id: correction.plan_id.clone(),
        version: correction.base_version,
        frame: "map".into(),
        waypoints: (0..20)
            .map(|i| WaypointDoc {
                x: f64::from(i) * 0.1,
                y: 0.0,
                z: 0.0,
                v: 0.5,
                t: f64::from(i) * 0.2,
                kind: WaypointKindDoc::Cover,
                region: Some(0),
            })
            .collect(),
        regions: Vec::new(),
        metrics: PlanMetricsDoc::default(),
    };
    let _ = correction.apply(&doc);
}

/// An MCAP recording (shiftd's own or a ROS 2 bag) read as `shiftd replay` reads a file, then what both replays
/// do with it short of Zenoh: its engine inputs through a fresh engine checked against its recorded decisions
/// (`--into-engine --check`), and its ingested topics mapped to the keys of every `[zenoh] mapping`.
pub fn mcap_replay(data: &[u8]) {
    let mut rec = Recorded::default();
    if rec.read_bytes(data, "fuzz input").is_err() {
        return;
    }
    rec.ingest.sort_by_key(|(t, _)| *t);
    let _ = into_engine(&rec, &mut std::io::sink(), true);
    if rec.ingest.is_empty() {
        return;
    }
    let Ok(keys) = KeySpace::new("shift", "default") else {
        return;
    };
    let mappings = [
        Ros2Mapping::Native,
        Ros2Mapping::BridgeRos2dds { namespace: None },
        Ros2Mapping::RmwZenoh { domain: 0 },
    ];
    for mapping in mappings {
        let map = KeyMap::new(keys.clone(), mapping);
        for (_, action) in &rec.ingest {
            if let Action::Put { key, kind, .. } = action {
                let _ = map.key_for(key, *kind);
            }
        }
    }
}
