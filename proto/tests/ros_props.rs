//! Property tests of the ROS codecs: encode → decode round trips for random messages and point layouts, and no
//! panic (an error or a valid result) on random bytes, every truncation and corrupted layouts.

use proptest::prelude::*;
use shift_proto::CodecError;
use shift_proto::ros::laser_scan::encode_laser_scan_with;
use shift_proto::ros::odometry::encode_odometry_with;
use shift_proto::ros::point_cloud2::encode_point_cloud2_with;
use shift_proto::ros::{
    Header, LaserScan, Odometry, PointCloud2, PointField, Quaternion, Time, cloud_xyz, decode_cloud_xyz,
    decode_laser_scan, decode_odom_payload, decode_odometry, decode_path, decode_point_cloud2, encode_laser_scan,
    encode_odometry, encode_path, encode_point_cloud2_xyz,
};

fn fixture_names() -> Vec<&'static str> {
    vec![
        "odometry",
        "odometry_be",
        "cloud_f32_le",
        "cloud_f64",
        "cloud_bigendian_data",
        "cloud_be_body",
        "cloud_organised",
        "cloud_extra_fields",
        "cloud_nan",
        "cloud_empty",
        "laser_scan",
        "laser_scan_be",
        "path",
        "path_empty",
    ]
}

fn fixture(name: &str) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/fixtures/{name}.cdr"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Runs every decoder on `bytes`; none may panic. Returns how many succeeded.
fn decode_all(bytes: &[u8]) -> usize {
    let mut ok = 0;
    ok += usize::from(decode_odometry(bytes).is_ok());
    ok += usize::from(decode_odom_payload(bytes, None).is_ok());
    ok += usize::from(decode_odom_payload(bytes, Some("application/json")).is_ok());
    ok += usize::from(decode_odom_payload(bytes, Some("application/cdr")).is_ok());
    ok += usize::from(decode_laser_scan(bytes).is_ok());
    ok += usize::from(decode_path(bytes).is_ok());
    if let Ok(c) = decode_point_cloud2(bytes) {
        ok += 1;
        check_xyz_invariants(&c, cloud_xyz(&c));
    }
    ok += usize::from(decode_cloud_xyz(bytes).is_ok());
    ok
}

/// A successful extraction holds only finite points, and points + skipped = height × width.
fn check_xyz_invariants(c: &PointCloud2, r: Result<shift_proto::ros::CloudXyz, CodecError>) {
    if let Ok(xyz) = r {
        assert!(xyz.points.iter().flatten().all(|v| v.is_finite()));
        assert_eq!(
            (xyz.points.len() + xyz.skipped) as u64,
            u64::from(c.height) * u64::from(c.width)
        );
    }
}

fn header() -> impl Strategy<Value = Header> {
    (any::<i32>(), 0u32..1_000_000_000, "[a-z_/]{0,12}").prop_map(|(sec, nanosec, frame_id)| Header {
        stamp: Time { sec, nanosec },
        frame_id,
    })
}

fn finite() -> impl Strategy<Value = f64> {
    -1e6f64..1e6
}

fn coord32() -> impl Strategy<Value = f32> {
    prop_oneof![8 => -1e4f32..1e4, 1 => Just(f32::NAN), 1 => Just(f32::INFINITY), 1 => Just(f32::NEG_INFINITY)]
}

/// A random point layout: x, y, z (each FLOAT32 or FLOAT64) plus filler fields, in random order and packing.
#[derive(Debug, Clone)]
struct Layout {
    fields: Vec<PointField>,
    point_step: u32,
    is_bigendian: bool,
}

fn layout() -> impl Strategy<Value = Layout> {
    (
        prop::collection::vec(prop_oneof![Just(7u8), Just(8u8)], 3),
        prop::collection::vec(0u32..4, 4), // gaps before x, y, z and after
        any::<bool>(),
        any::<bool>(),
        Just(vec![0usize, 1, 2]).prop_shuffle(),
    )
        .prop_map(|(types, gaps, is_bigendian, with_intensity, order)| {
            let mut fields = Vec::new();
            let mut off = 0u32;
            for (k, &axis) in order.iter().enumerate() {
                off += gaps[k];
                let name = ["x", "y", "z"][axis];
                fields.push(PointField::new(name, off, types[axis]));
                off += if types[axis] == 7 { 4 } else { 8 };
                if with_intensity && k == 0 {
                    fields.push(PointField::new("intensity", off, PointField::FLOAT32));
                    off += 4;
                }
            }
            fields.reverse(); // the list order need not follow the offsets
            Layout {
                fields,
                point_step: off + gaps[3],
                is_bigendian,
            }
        })
}

/// Builds a cloud with `layout` from row-major points; the filler bytes are 0xA5.
fn build_cloud(layout: &Layout, height: u32, width: u32, row_pad: u32, pts: &[[f64; 3]]) -> PointCloud2 {
    let row_step = width * layout.point_step + row_pad;
    let mut data = vec![0xA5u8; (row_step * height) as usize];
    for (i, p) in pts.iter().enumerate() {
        let (row, col) = (i as u32 / width, i as u32 % width);
        let base = (row * row_step + col * layout.point_step) as usize;
        for f in &layout.fields {
            let v = match f.name.as_str() {
                "x" => p[0],
                "y" => p[1],
                "z" => p[2],
                _ => 42.0,
            };
            let bytes: Vec<u8> = match (f.datatype, layout.is_bigendian) {
                (7, false) => (v as f32).to_le_bytes().to_vec(),
                (7, true) => (v as f32).to_be_bytes().to_vec(),
                (_, false) => v.to_le_bytes().to_vec(),
                (_, true) => v.to_be_bytes().to_vec(),
            };
            let o = base + f.offset as usize;
            data[o..o + bytes.len()].copy_from_slice(&bytes);
        }
    }
    PointCloud2 {
        header: Header::new(1, "lidar"),
        height,
        width,
        fields: layout.fields.clone(),
        is_bigendian: layout.is_bigendian,
        point_step: layout.point_step,
        row_step,
        data,
        is_dense: false,
    }
}

/// What a decoder must give for `pts` under `layout`: values rounded through f32 where the field is FLOAT32.
fn expected_points(layout: &Layout, pts: &[[f64; 3]]) -> (Vec<[f64; 3]>, usize) {
    let ty = |name: &str| {
        layout
            .fields
            .iter()
            .find(|f| f.name == name)
            .map(|f| f.datatype)
            .unwrap_or(8)
    };
    let round = |v: f64, t: u8| if t == 7 { f64::from(v as f32) } else { v };
    let (tx, ty_, tz) = (ty("x"), ty("y"), ty("z"));
    let mut out = Vec::new();
    let mut skipped = 0;
    for p in pts {
        let q = [round(p[0], tx), round(p[1], ty_), round(p[2], tz)];
        if q.iter().all(|v| v.is_finite()) {
            out.push(q);
        } else {
            skipped += 1;
        }
    }
    (out, skipped)
}

fn coord64() -> impl Strategy<Value = f64> {
    prop_oneof![8 => -1e4f64..1e4, 1 => Just(f64::NAN), 1 => Just(f64::INFINITY)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn xyz_clouds_round_trip(h in header(), pts in prop::collection::vec([coord32(), coord32(), coord32()], 0..200)) {
        let bytes = encode_point_cloud2_xyz(&h, &pts);
        let xyz = decode_cloud_xyz(&bytes).expect("own encoding decodes");
        let finite: Vec<[f64; 3]> = pts
            .iter()
            .filter(|p| p.iter().all(|v| v.is_finite()))
            .map(|p| p.map(f64::from))
            .collect();
        prop_assert_eq!(&xyz.points, &finite);
        prop_assert_eq!(xyz.skipped, pts.len() - finite.len());
        prop_assert_eq!(&xyz.header, &h);
        let msg = decode_point_cloud2(&bytes).expect("message");
        prop_assert_eq!(msg.is_dense, finite.len() == pts.len());
    }

    #[test]
    fn any_layout_round_trips(
        layout in layout(),
        height in 1u32..4,
        width in 0u32..20,
        row_pad in 0u32..9,
        big_body in any::<bool>(),
        seed_pts in prop::collection::vec([coord64(), coord64(), coord64()], 80),
    ) {
        let pts = &seed_pts[..(height * width) as usize];
        let cloud = build_cloud(&layout, height, width, row_pad, pts);
        let bytes = encode_point_cloud2_with(&cloud, big_body);
        let decoded = decode_point_cloud2(&bytes).expect("decodes");
        prop_assert_eq!(&decoded, &cloud);
        let xyz = decode_cloud_xyz(&bytes).expect("xyz");
        let (want, skipped) = expected_points(&layout, pts);
        prop_assert_eq!(xyz.points, want);
        prop_assert_eq!(xyz.skipped, skipped);
    }

    #[test]
    fn corrupted_layouts_never_panic(
        layout in layout(),
        height in 0u32..4,
        width in 0u32..12,
        pts in prop::collection::vec([coord64(), coord64(), coord64()], 48),
        point_step in prop_oneof![Just(None), (0u32..64).prop_map(Some), Just(Some(u32::MAX))],
        new_width in prop_oneof![Just(None), (0u32..100).prop_map(Some), Just(Some(u32::MAX))],
        new_height in prop_oneof![Just(None), (0u32..10).prop_map(Some), Just(Some(u32::MAX))],
        row_step in prop_oneof![Just(None), (0u32..500).prop_map(Some), Just(Some(u32::MAX))],
        offset in prop_oneof![Just(None), (0u32..40).prop_map(Some), Just(Some(u32::MAX))],
        cut in 0usize..64,
    ) {
        let mut c = build_cloud(&layout, height, width, 3, &pts[..(height * width) as usize]);
        if let Some(v) = point_step { c.point_step = v; }
        if let Some(v) = new_width { c.width = v; }
        if let Some(v) = new_height { c.height = v; }
        if let Some(v) = row_step { c.row_step = v; }
        if let Some(v) = offset { c.fields[0].offset = v; }
        let keep = c.data.len().saturating_sub(cut);
        c.data.truncate(keep);
        check_xyz_invariants(&c, cloud_xyz(&c));
        let bytes = encode_point_cloud2_with(&c, false);
        let r = decode_cloud_xyz(&bytes);
        check_xyz_invariants(&c, r.clone());
        prop_assert_eq!(r, cloud_xyz(&c));
    }

    #[test]
    fn odometry_round_trips(
        h in header(),
        child in "[a-z_]{0,10}",
        v in prop::collection::vec(finite(), 13),
        pc in prop::collection::vec(finite(), 36),
        tc in prop::collection::vec(finite(), 36),
        big in any::<bool>(),
    ) {
        let mut o = Odometry { header: h, child_frame_id: child, ..Odometry::default() };
        o.pose.pose.position = shift_proto::ros::Point { x: v[0], y: v[1], z: v[2] };
        o.pose.pose.orientation = Quaternion { x: v[3], y: v[4], z: v[5], w: v[6] };
        o.twist.twist.linear = shift_proto::ros::Vector3 { x: v[7], y: v[8], z: v[9] };
        o.twist.twist.angular = shift_proto::ros::Vector3 { x: v[10], y: v[11], z: v[12] };
        o.pose.covariance.copy_from_slice(&pc);
        o.twist.covariance.copy_from_slice(&tc);
        let bytes = encode_odometry_with(&o, big);
        prop_assert_eq!(decode_odometry(&bytes).expect("decodes"), o.clone());
        let p = decode_odom_payload(&bytes, None).expect("payload");
        prop_assert_eq!((p.x, p.y, p.vx, p.vy, p.wz), (v[0], v[1], v[7], v[8], v[12]));
        prop_assert_eq!(p.stamp_ns, o.header.stamp.to_ns());
        prop_assert!((p.yaw - o.pose.pose.orientation.yaw()).abs() < 1e-12);
        // Every strict prefix is an error: the last field is required.
        for n in 0..bytes.len() {
            prop_assert!(decode_odometry(&bytes[..n]).is_err(), "prefix {}", n);
        }
        if !big {
            prop_assert_eq!(encode_odometry(&o), bytes);
        }
    }

    #[test]
    fn scans_round_trip(
        h in header(),
        angles in prop::collection::vec(-4f32..4.0, 7),
        ranges in prop::collection::vec(prop_oneof![8 => 0f32..30.0, 1 => Just(f32::NAN), 1 => Just(f32::INFINITY)], 0..100),
        intensities in prop::collection::vec(0f32..1000.0, 0..100),
        big in any::<bool>(),
    ) {
        let s = LaserScan {
            header: h,
            angle_min: angles[0],
            angle_max: angles[1],
            angle_increment: angles[2],
            time_increment: angles[3],
            scan_time: angles[4],
            range_min: angles[5].abs(),
            range_max: angles[5].abs() + angles[6].abs() * 5.0,
            ranges,
            intensities,
        };
        let bytes = encode_laser_scan_with(&s, big);
        let d = decode_laser_scan(&bytes).expect("decodes");
        prop_assert_eq!(d.ranges.len(), s.ranges.len());
        for (a, b) in d.ranges.iter().zip(&s.ranges) {
            prop_assert!(a.to_bits() == b.to_bits());
        }
        prop_assert_eq!(&d.intensities, &s.intensities);
        prop_assert_eq!(&d.header, &s.header);
        prop_assert_eq!(d.angle_increment, s.angle_increment);
        prop_assert_eq!(shift_proto::ros::scan_points(&d).len(), shift_proto::ros::scan_points(&s).len());
        let expect_pts = s.ranges.iter().filter(|r| r.is_finite() && **r >= s.range_min && **r <= s.range_max).count();
        prop_assert_eq!(shift_proto::ros::scan_points(&d).len(), expect_pts);
        for (p, r) in shift_proto::ros::scan_points(&d).iter().zip(s.ranges.iter().filter(|r| r.is_finite() && **r >= s.range_min && **r <= s.range_max)) {
            prop_assert!((p[0].hypot(p[1]) - f64::from(*r)).abs() < 1e-9);
        }
        for n in 0..bytes.len() {
            prop_assert!(decode_laser_scan(&bytes[..n]).is_err(), "prefix {}", n);
        }
        if !big {
            prop_assert_eq!(encode_laser_scan(&s), bytes);
        }
    }

    #[test]
    fn paths_round_trip(h in header(), poses in prop::collection::vec((finite(), finite(), -3.1f64..3.1), 0..30)) {
        let bytes = encode_path(&h, &poses);
        let p = decode_path(&bytes).expect("decodes");
        prop_assert_eq!(&p.header, &h);
        for ((x, y, yaw), (wx, wy, wyaw)) in p.poses_2d().into_iter().zip(&poses) {
            prop_assert_eq!((x, y), (*wx, *wy));
            prop_assert!((yaw - wyaw).abs() < 1e-12);
        }
        prop_assert_eq!(p.poses.len(), poses.len());
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        decode_all(&bytes);
        let mut le = vec![0, 1, 0, 0];
        le.extend_from_slice(&bytes);
        decode_all(&le);
        let mut be = vec![0, 0, 0, 0];
        be.extend_from_slice(&bytes);
        decode_all(&be);
    }

    #[test]
    fn corrupted_fixtures_never_panic(which in 0usize..14, flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6)) {
        let mut bytes = fixture(fixture_names()[which]);
        for (i, v) in flips {
            let i = i.index(bytes.len());
            bytes[i] = v;
        }
        decode_all(&bytes);
    }
}

#[test]
fn every_truncation_of_every_fixture_fails_cleanly() {
    for name in fixture_names() {
        let bytes = fixture(name);
        assert!(decode_all(&bytes) >= 1, "{name} decodes whole");
        for n in 0..bytes.len() {
            let cut = &bytes[..n];
            decode_all(cut);
            let r = match name {
                n if n.starts_with("odometry") => decode_odometry(cut).map(drop),
                n if n.starts_with("cloud") => decode_point_cloud2(cut).map(drop),
                n if n.starts_with("laser") => decode_laser_scan(cut).map(drop),
                _ => decode_path(cut).map(drop),
            };
            let err = r.expect_err("a strict prefix cannot decode");
            assert_eq!(err.kind(), "truncated", "{name}[..{n}]: {err}");
        }
    }
}

#[test]
fn absurd_declared_sizes_are_refused_before_allocating() {
    let bytes = fixture("cloud_f32_le");
    let mut c = decode_point_cloud2(&bytes).expect("fixture");
    c.height = 5_000;
    c.width = 5_000;
    let err = decode_point_cloud2(&encode_point_cloud2_with(&c, false)).expect_err("25 M points");
    assert!(
        matches!(
            err,
            CodecError::TooLarge {
                value: 25_000_000,
                limit: 20_000_000,
                ..
            }
        ),
        "{err}"
    );

    // A data length of 600 MiB in a 200-byte payload.
    let mut bytes = encode_point_cloud2_xyz(&Header::new(0, "map"), &[[1.0, 2.0, 3.0]]);
    let len_at = bytes.len() - 1 - 12 - 4;
    bytes[len_at..len_at + 4].copy_from_slice(&(600u32 << 20).to_le_bytes());
    let err = decode_point_cloud2(&bytes).expect_err("600 MiB");
    assert_eq!(err.kind(), "too_large", "{err}");
    bytes[len_at..len_at + 4].copy_from_slice(&(100u32 << 20).to_le_bytes());
    let err = decode_point_cloud2(&bytes).expect_err("100 MiB that is not there");
    assert!(
        matches!(
            err,
            CodecError::Truncated {
                what: "PointCloud2.data",
                need: 104_857_600,
                ..
            }
        ),
        "{err}"
    );
}
