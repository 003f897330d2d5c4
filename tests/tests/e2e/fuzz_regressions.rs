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
    // mcap_replay: one recording twice, plain (seed-0: no chunks, compression or CRCs, so mutations reach the
    // messages) and as the daemon's writer makes it (seed-1: zstd chunks, summary).
    let messages = mcap_replay_messages(&header, &scan, &odom);
    let dir = root.join("mcap_replay");
    std::fs::create_dir_all(&dir).expect("seed dir");
    std::fs::write(dir.join("seed-0"), plain_mcap(&messages)).expect("seed");
    let tmp = tempfile::tempdir().expect("tmp");
    let mut files = shiftd::record::writer::RotatingWriter::new(shiftd::record::writer::FileSettings {
        dir: tmp.path().to_path_buf(),
        run: 1,
        max_file_bytes: 0,
        max_file_age: std::time::Duration::ZERO,
        chunk_bytes: 4096,
    });
    for (kind, topic, log_ns, data) in &messages {
        files.write(*kind, topic, *log_ns, data).expect("record");
    }
    let file = files.finish().expect("finish").expect("a file");
    std::fs::copy(file, dir.join("seed-1")).expect("seed");
}

/// A short recording as `shiftd serve --record` makes one, with a ROS 2 bag's topics among the ingest: the
/// engine's sizes; a map upload, a robot's liveliness and pose and a plan request, each with the decisions a
/// fresh engine made for it; the robot's liveliness token and odometry (CDR and JSON) on SHIFT keys; a scan and
/// a cloud on ROS 2 topics. (kind, topic, log time ns, payload), in log-time order.
fn mcap_replay_messages(
    header: &shift_proto::ros::Header,
    scan: &shift_proto::ros::laser_scan::LaserScan,
    odom: &shift_proto::ros::odometry::Odometry,
) -> Vec<(shiftd::record::channels::Kind, String, u64, Vec<u8>)> {
    use shift_engine::recorded::{RecordedDecisions, RecordedEngineConfig, RecordedInput, decisions_of};
    use shift_engine::{Engine, EngineConfig, Event, LoadedSite, MapSource, Pose2, SiteRecord};
    use shift_proto::ros::laser_scan::encode_laser_scan;
    use shift_proto::ros::odometry::encode_odometry;
    use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
    use shiftd::record::channels::{self, Kind};

    let run = 1_796_290_080_000u64;
    let json = |v: serde_json::Value| serde_json::to_vec(&v).expect("json");
    let config = EngineConfig::default();
    let mut out = vec![(
        Kind::EngineConfig,
        channels::ENGINE_CONFIG.to_owned(),
        run * 1_000_000,
        serde_json::to_vec(&RecordedEngineConfig::of(run, &config)).expect("json"),
    )];
    let cells = [0; 100].map(|c: i32| c.to_string()).join(", ");
    let site = LoadedSite::parse(SiteRecord {
        site: "demo".into(),
        source: MapSource::Json {
            text: format!(
                r#"{{"width": 10, "height": 10, "resolution": 0.2, "origin": [0.0, 0.0], "cells": [{cells}]}}"#
            ),
        },
        updated_ms: run,
    })
    .expect("site");
    let request = serde_json::from_value(serde_json::json!({"site": "demo", "start": [0.5, 0.5],
        "robot": {"radius": 0.15, "tool_width": 0.3}, "region": [[0.2, 0.2], [1.8, 0.2], [1.8, 1.8], [0.2, 1.8]],
        "objective": "time", "snap_start_m": 0.5}))
    .expect("request");
    let pose = Pose2 {
        x: 0.5,
        y: 0.5,
        yaw: 0.0,
        stamp_ns: (run as i64 + 300) * 1_000_000,
    };
    let events = vec![
        Event::MapUploaded { site },
        Event::RobotLiveliness {
            robot: "r1".into(),
            alive: true,
        },
        Event::RobotPose {
            robot: "r1".into(),
            pose,
        },
        Event::PlanRequested { request },
    ];
    let mut engine = Engine::new(config);
    for (seq, event) in (1u64..).zip(events) {
        let now_ms = run + seq * 100;
        let input = RecordedInput {
            run,
            seq,
            now_ms,
            event: event.clone(),
        };
        let decisions = RecordedDecisions {
            run,
            seq,
            now_ms,
            decisions: decisions_of(&engine.handle(event, now_ms)),
        };
        let log_ns = now_ms * 1_000_000;
        for (kind, topic, bytes) in [
            (Kind::EngineInput, channels::ENGINE_INPUT, serde_json::to_vec(&input)),
            (
                Kind::EngineDecisions,
                channels::ENGINE_DECISIONS,
                serde_json::to_vec(&decisions),
            ),
        ] {
            out.push((kind, topic.to_owned(), log_ns, bytes.expect("json")));
        }
    }
    let alive = |alive: bool| json(serde_json::json!({"key": "shift/default/robots/r1/alive", "alive": alive}));
    let ingest = [
        (Kind::Liveliness, channels::LIVELINESS, alive(true)),
        (Kind::Odometry, "shift/default/robots/r1/odom", encode_odometry(odom)),
        (
            Kind::OdomJson,
            "shift/default/robots/r2/odom",
            json(serde_json::json!({"x": 1.0, "y": 2.0, "yaw": 0.5})),
        ),
        (Kind::LaserScan, "/robot1/scan", encode_laser_scan(scan)),
        (
            Kind::PointCloud2,
            "/fleet_a/robot1/points",
            encode_point_cloud2_xyz(header, &[[1.0, 2.0, 0.5]]),
        ),
        (Kind::Liveliness, channels::LIVELINESS, alive(false)),
    ];
    let t = (run + 1000) * 1_000_000;
    out.extend(
        (t..)
            .zip(ingest)
            .map(|(log_ns, (kind, topic, data))| (kind, topic.to_owned(), log_ns, data)),
    );
    out
}

/// An MCAP file of `messages` without chunks, compression, CRCs or summary: the header, each schema and channel
/// before its first message, the messages, data end and footer. Schema texts are left empty (a replay goes by
/// the schema's name) to keep the seed small.
fn plain_mcap(messages: &[(shiftd::record::channels::Kind, String, u64, Vec<u8>)]) -> Vec<u8> {
    const MAGIC: &[u8] = b"\x89MCAP0\r\n";
    fn record(out: &mut Vec<u8>, opcode: u8, body: &[u8]) {
        out.push(opcode);
        out.extend((body.len() as u64).to_le_bytes());
        out.extend(body);
    }
    /// A string, byte array or map: u32 length, then the bytes.
    fn prefixed(out: &mut Vec<u8>, bytes: &[u8]) {
        out.extend((bytes.len() as u32).to_le_bytes());
        out.extend(bytes);
    }
    let mut out = MAGIC.to_vec();
    let mut body = Vec::new();
    prefixed(&mut body, b"ros2");
    prefixed(&mut body, b"shift fuzz seed");
    record(&mut out, 0x01, &body);
    let (mut schemas, mut channels) = (Vec::new(), Vec::new());
    for (sequence, (kind, topic, log_ns, data)) in (0u32..).zip(messages) {
        let schema_id = match schemas.iter().position(|k| k == kind) {
            Some(i) => i as u16 + 1,
            None => {
                schemas.push(*kind);
                let id = schemas.len() as u16;
                let mut body = id.to_le_bytes().to_vec();
                prefixed(&mut body, kind.schema().name.as_bytes());
                prefixed(&mut body, kind.schema().encoding.as_bytes());
                prefixed(&mut body, b"");
                record(&mut out, 0x03, &body);
                id
            }
        };
        let channel_id = match channels.iter().position(|c| c == &(*kind, topic)) {
            Some(i) => i as u16 + 1,
            None => {
                channels.push((*kind, topic));
                let id = channels.len() as u16;
                let mut body = [id.to_le_bytes(), schema_id.to_le_bytes()].concat();
                prefixed(&mut body, topic.as_bytes());
                prefixed(&mut body, kind.message_encoding().as_bytes());
                let mut metadata = Vec::new();
                for (k, v) in kind.metadata() {
                    prefixed(&mut metadata, k.as_bytes());
                    prefixed(&mut metadata, v.as_bytes());
                }
                prefixed(&mut body, &metadata);
                record(&mut out, 0x04, &body);
                id
            }
        };
        let mut body = channel_id.to_le_bytes().to_vec();
        body.extend(sequence.to_le_bytes());
        body.extend(log_ns.to_le_bytes());
        body.extend(log_ns.to_le_bytes());
        body.extend(data);
        record(&mut out, 0x05, &body);
    }
    record(&mut out, 0x0f, &0u32.to_le_bytes());
    record(&mut out, 0x02, &[0; 20]);
    out.extend(MAGIC);
    out
}
