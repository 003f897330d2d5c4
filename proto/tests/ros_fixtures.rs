//! Byte-exact fixtures written by the Python `rosbags` serializer (`tests/fixtures/make_ros_fixtures.py`): our
//! decoders must return the values of `expected.json`, our encoders the very bytes of the `.cdr` files.

use std::path::PathBuf;

use serde_json::Value;
use shift_proto::ros::laser_scan::encode_laser_scan_with;
use shift_proto::ros::odometry::encode_odometry_with;
use shift_proto::ros::point_cloud2::encode_point_cloud2_with;
use shift_proto::ros::{
    Header, Odometry, PointField, Quaternion, Time, cloud_xyz, decode_cloud_xyz, decode_laser_scan,
    decode_odom_payload, decode_odometry, decode_path, decode_point_cloud2, encode_laser_scan, encode_odometry,
    encode_path, encode_point_cloud2, encode_point_cloud2_xyz, msg_defs, scan_points, type_hash,
};

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn fixture(name: &str) -> Vec<u8> {
    let path = dir().join(format!("{name}.cdr"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn expected(name: &str) -> Value {
    let text = std::fs::read_to_string(dir().join("expected.json")).expect("expected.json");
    let all: Value = serde_json::from_str(&text).expect("expected.json parses");
    all.get(name)
        .cloned()
        .unwrap_or_else(|| panic!("expected.json has no `{name}`"))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn fs(v: &Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(f).collect()
}

fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("not an unsigned integer: {v}"))
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{what}: {a} != {b}");
}

fn close_all(a: &[f64], b: &[f64], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        close(*x, *y, &format!("{what}[{i}]"));
    }
}

fn header(v: &Value) -> Header {
    Header {
        stamp: Time {
            sec: v["sec"].as_i64().expect("sec") as i32,
            nanosec: u(&v["nanosec"]) as u32,
        },
        frame_id: v["frame_id"].as_str().expect("frame_id").to_owned(),
    }
}

/// The Odometry that `expected.json` describes, built without our decoder.
fn odometry_from_json(e: &Value) -> Odometry {
    let mut o = Odometry {
        header: header(&e["header"]),
        child_frame_id: e["child_frame_id"].as_str().expect("child").to_owned(),
        ..Odometry::default()
    };
    let [px, py, pz] = fs(&e["position"])[..] else {
        panic!("position")
    };
    let [qx, qy, qz, qw] = fs(&e["orientation"])[..] else {
        panic!("orientation")
    };
    let [lx, ly, lz] = fs(&e["linear"])[..] else {
        panic!("linear")
    };
    let [ax, ay, az] = fs(&e["angular"])[..] else {
        panic!("angular")
    };
    o.pose.pose.position = shift_proto::ros::Point { x: px, y: py, z: pz };
    o.pose.pose.orientation = Quaternion {
        x: qx,
        y: qy,
        z: qz,
        w: qw,
    };
    o.pose.covariance = fs(&e["pose_covariance"]).try_into().expect("36");
    o.twist.twist.linear = shift_proto::ros::Vector3 { x: lx, y: ly, z: lz };
    o.twist.twist.angular = shift_proto::ros::Vector3 { x: ax, y: ay, z: az };
    o.twist.covariance = fs(&e["twist_covariance"]).try_into().expect("36");
    o
}

#[test]
fn odometry_decodes_and_encodes_byte_exact() {
    for (name, big) in [("odometry", false), ("odometry_be", true)] {
        let bytes = fixture(name);
        let e = expected(name);
        let want = odometry_from_json(&e);
        let got = decode_odometry(&bytes).expect(name);
        assert_eq!(got, want, "{name}");
        assert_eq!(
            encode_odometry_with(&want, big),
            bytes,
            "{name}: encoder bytes differ from rosbags"
        );
        if !big {
            assert_eq!(encode_odometry(&want), bytes);
        }
        let pose = decode_odom_payload(&bytes, None).expect("payload");
        close(pose.yaw, f(&e["yaw"]), "yaw");
        assert_eq!(pose.stamp_ns, e["stamp_ns"].as_i64().expect("stamp_ns"));
        assert_eq!(
            (pose.x, pose.y, pose.vx, pose.vy, pose.wz),
            (12.5, -3.25, 0.4, -0.05, 0.3)
        );
        assert_eq!(pose.frame_id, "odom");
    }
}

const CLOUDS: [&str; 8] = [
    "cloud_f32_le",
    "cloud_f64",
    "cloud_bigendian_data",
    "cloud_be_body",
    "cloud_organised",
    "cloud_extra_fields",
    "cloud_nan",
    "cloud_empty",
];

#[test]
fn point_clouds_decode_to_the_expected_points() {
    for name in CLOUDS {
        let bytes = fixture(name);
        let e = expected(name);
        let msg = decode_point_cloud2(&bytes).unwrap_or_else(|err| panic!("{name}: {err}"));
        assert_eq!(msg.header, header(&e["header"]), "{name}");
        assert_eq!(u64::from(msg.height), u(&e["height"]), "{name}");
        assert_eq!(u64::from(msg.width), u(&e["width"]), "{name}");
        assert_eq!(u64::from(msg.point_step), u(&e["point_step"]), "{name}");
        assert_eq!(u64::from(msg.row_step), u(&e["row_step"]), "{name}");
        assert_eq!(Some(msg.is_bigendian), e["is_bigendian"].as_bool(), "{name}");
        assert_eq!(Some(msg.is_dense), e["is_dense"].as_bool(), "{name}");
        assert_eq!(msg.data.len() as u64, u(&e["data_len"]), "{name}");
        let fields: Vec<PointField> = e["fields"]
            .as_array()
            .expect("fields")
            .iter()
            .map(|v| PointField {
                name: v["name"].as_str().expect("name").to_owned(),
                offset: u(&v["offset"]) as u32,
                datatype: u(&v["datatype"]) as u8,
                count: u(&v["count"]) as u32,
            })
            .collect();
        assert_eq!(msg.fields, fields, "{name}");

        let xyz = cloud_xyz(&msg).unwrap_or_else(|err| panic!("{name}: {err}"));
        let want: Vec<Vec<f64>> = e["points"].as_array().expect("points").iter().map(fs).collect();
        assert_eq!(xyz.points.len(), want.len(), "{name}: point count");
        for (i, (p, w)) in xyz.points.iter().zip(&want).enumerate() {
            close_all(p, w, &format!("{name} point {i}"));
        }
        assert_eq!(xyz.skipped as u64, u(&e["skipped"]), "{name}: skipped");
        assert_eq!(xyz.header, msg.header);
        assert_eq!(decode_cloud_xyz(&bytes).expect("borrowed path"), xyz, "{name}");

        // Re-encoding the decoded message gives rosbags' bytes back, in the body's byte order.
        let big_body = bytes[1] == 0;
        assert_eq!(
            encode_point_cloud2_with(&msg, big_body),
            bytes,
            "{name}: re-encoded bytes differ"
        );
    }
}

#[test]
fn xyz_cloud_encoder_matches_rosbags() {
    let bytes = fixture("cloud_f32_le");
    let e = expected("cloud_f32_le");
    let points: Vec<[f32; 3]> = e["points"]
        .as_array()
        .expect("points")
        .iter()
        .map(|p| to3(fs(p).iter().map(|&v| v as f32).collect()))
        .collect();
    let ours = encode_point_cloud2_xyz(&header(&e["header"]), &points);
    assert_eq!(ours, bytes, "encode_point_cloud2_xyz differs from rosbags");
    assert_eq!(
        encode_point_cloud2(&decode_point_cloud2(&bytes).expect("decode")),
        bytes
    );
}

fn to3(v: Vec<f32>) -> [f32; 3] {
    v.try_into().expect("three coordinates")
}

#[test]
fn laser_scans_decode_and_encode_byte_exact() {
    for (name, big) in [("laser_scan", false), ("laser_scan_be", true)] {
        let bytes = fixture(name);
        let e = expected(name);
        let scan = decode_laser_scan(&bytes).unwrap_or_else(|err| panic!("{name}: {err}"));
        assert_eq!(scan.header, header(&e["header"]));
        for (got, key) in [
            (scan.angle_min, "angle_min"),
            (scan.angle_max, "angle_max"),
            (scan.angle_increment, "angle_increment"),
            (scan.time_increment, "time_increment"),
            (scan.scan_time, "scan_time"),
            (scan.range_min, "range_min"),
            (scan.range_max, "range_max"),
        ] {
            assert_eq!(f64::from(got), f(&e[key]), "{name}.{key}");
        }
        let ranges = e["ranges"].as_array().expect("ranges");
        assert_eq!(scan.ranges.len(), ranges.len());
        for (r, w) in scan.ranges.iter().zip(ranges) {
            match w.as_str() {
                Some("inf") => assert!(r.is_infinite() && *r > 0.0),
                Some("nan") => assert!(r.is_nan()),
                _ => assert_eq!(f64::from(*r), f(w)),
            }
        }
        close_all(
            &scan.intensities.iter().map(|&v| f64::from(v)).collect::<Vec<_>>(),
            &fs(&e["intensities"]),
            "i",
        );
        let pts = scan_points(&scan);
        let want: Vec<Vec<f64>> = e["points"].as_array().expect("points").iter().map(fs).collect();
        assert_eq!(pts.len(), want.len(), "{name}: points");
        for (p, w) in pts.iter().zip(&want) {
            close_all(p, w, name);
        }
        assert_eq!(
            encode_laser_scan_with(&scan, big),
            bytes,
            "{name}: encoder bytes differ from rosbags"
        );
        if !big {
            assert_eq!(encode_laser_scan(&scan), bytes);
        }
    }
}

#[test]
fn paths_encode_byte_exact_and_decode() {
    for name in ["path", "path_empty"] {
        let bytes = fixture(name);
        let e = expected(name);
        let h = header(&e["header"]);
        let poses: Vec<(f64, f64, f64)> = e["poses"]
            .as_array()
            .expect("poses")
            .iter()
            .map(|p| {
                let [x, y, yaw] = fs(p)[..] else { panic!("pose") };
                (x, y, yaw)
            })
            .collect();
        assert_eq!(
            encode_path(&h, &poses),
            bytes,
            "{name}: encoder bytes differ from rosbags"
        );
        let path = decode_path(&bytes).expect(name);
        assert_eq!(path.header, h);
        assert!(path.poses.iter().all(|p| p.header == h), "each pose carries the header");
        for ((x, y, yaw), (wx, wy, wyaw)) in path.poses_2d().into_iter().zip(&poses) {
            close(x, *wx, "x");
            close(y, *wy, "y");
            let d = (yaw - wyaw).rem_euclid(std::f64::consts::TAU);
            assert!(d < 1e-12 || (std::f64::consts::TAU - d) < 1e-12, "yaw {yaw} vs {wyaw}");
        }
        assert_eq!(path.poses.len(), poses.len());
    }
}

#[test]
fn type_hashes_and_schema_texts_match_rosbags() {
    let h = expected("type_hashes");
    assert_eq!(h["nav_msgs/msg/Odometry"], type_hash::ODOMETRY);
    assert_eq!(h["sensor_msgs/msg/PointCloud2"], type_hash::POINT_CLOUD2);
    assert_eq!(h["sensor_msgs/msg/LaserScan"], type_hash::LASER_SCAN);
    assert_eq!(h["nav_msgs/msg/Path"], type_hash::PATH);
    assert_eq!(h["geometry_msgs/msg/PoseStamped"], type_hash::POSE_STAMPED);
    for (file, text) in [
        ("Odometry", msg_defs::ODOMETRY),
        ("PointCloud2", msg_defs::POINT_CLOUD2),
        ("LaserScan", msg_defs::LASER_SCAN),
        ("Path", msg_defs::PATH),
    ] {
        let want = std::fs::read_to_string(dir().join(format!("msgdefs/{file}.msg"))).expect("msgdef");
        assert_eq!(text, want, "{file}");
        let sep = format!("\n{}\nMSG: ", "=".repeat(80));
        assert!(
            text.contains(&sep),
            "{file}: dependencies are separated by 80 `=` and MSG:"
        );
        assert!(
            text.contains("MSG: std_msgs/msg/Header\n"),
            "{file}: pkg/msg/Type names"
        );
    }
}
