//! ROS 2 robots without an adapter: a robot publishing nav_msgs/Odometry, sensor_msgs/PointCloud2 and
//! sensor_msgs/LaserScan on zenoh-bridge-ros2dds keys, on rmw_zenoh keys (with and without the 33-byte
//! attachment), and on the native keys. The live map grows by exactly the expected voxels, the scan is placed
//! with the pose interpolated at its stamp, scans outside the odometry history and malformed ones are dropped
//! and counted, and a ROS 2 robot is alive while it is heard and lost after `robot_timeout_s` of silence.

use anyhow::{Result, anyhow};
use shift_proto::keys::{KeySpace, Ros2Mapping, Stream};
use shift_proto::ros::LaserScan;
use shift_proto::ros::laser_scan::encode_laser_scan;
use shift_proto::ros::odometry::encode_odometry;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_tests::fleet::{free_port, header, header_ns, obstacle_box, odom_at, poll, robot_session};
use shift_tests::{TestServer, test_config};
use zenoh::bytes::Encoding;
use zenoh::qos::CongestionControl;

/// rmw_zenoh's attachment: i64 sequence number, i64 source time (ns), 16-byte gid with its length (33 bytes).
fn rmw_attachment(seq: i64) -> Vec<u8> {
    let mut a = Vec::with_capacity(33);
    a.extend_from_slice(&seq.to_le_bytes());
    a.extend_from_slice(&1_700_000_000_000_000_000i64.to_le_bytes());
    a.push(16);
    a.extend_from_slice(&[7u8; 16]);
    a
}

struct Robot {
    session: zenoh::Session,
    mapping: Ros2Mapping,
    keys: KeySpace,
    seq: i64,
}

impl Robot {
    /// Puts CDR `bytes` on the robot's key for `stream`; rmw_zenoh samples carry the attachment when `attach`.
    async fn put(&mut self, stream: Stream, bytes: Vec<u8>, attach: bool) -> Result<()> {
        let key = self
            .mapping
            .robot_key(&self.keys, "bot1", stream)?
            .ok_or_else(|| anyhow!("no key for {stream:?}"))?;
        self.seq += 1;
        let put = self
            .session
            .put(&key, bytes)
            .encoding(Encoding::APPLICATION_CDR)
            .congestion_control(CongestionControl::Block);
        let put = if attach {
            put.attachment(rmw_attachment(self.seq))
        } else {
            put
        };
        put.await.map_err(|e| anyhow!("put {key}: {e}"))
    }
}

async fn site_points(server: &TestServer) -> Result<(u64, u64)> {
    let (_, s) = server.get("/v1/sites/demo").await?;
    Ok((
        s["points_in_tree"].as_u64().unwrap_or(0),
        s["dropped_clouds"].as_u64().unwrap_or(0),
    ))
}

/// A robot on `mapping` drives from (2.025, 2.025) to (3.025, 2.025) between t = 100 s and 101 s, sends one
/// map-frame cloud (16 ground-plane voxels) and one scan stamped 100.5 s (4 returns → 4 voxels).
async fn ros2_robot_feeds_the_live_map(mapping: Ros2Mapping, attach: bool) -> Result<()> {
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::new("warn,shiftd=info"))
        .with_test_writer()
        .try_init();
    let dir = tempfile::tempdir()?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = test_config(dir.path());
    config.zenoh.listen = vec![endpoint.clone()];
    config.zenoh.mapping = mapping.clone();
    config.zenoh.robot_timeout_s = 1;
    // These tests count every voxel the mapping, the scan geometry and the filters produce; points near the
    // demo map's own walls would otherwise be dropped as known obstacles (tested in live_map).
    config.zenoh.known_tolerance_m = 0.0;
    let server = TestServer::start(config).await?;
    let native = mapping.has_liveliness();

    let session = robot_session(&endpoint).await?;
    let token = if native {
        Some(
            session
                .liveliness()
                .declare_token("shift/default/robots/bot1/alive")
                .await
                .map_err(|e| anyhow!("{e}"))?,
        )
    } else {
        None
    };
    let mut robot = Robot {
        session,
        mapping,
        keys: KeySpace::default(),
        seq: 0,
    };
    // The data subscriptions may still be propagating to the new session: repeat the first pose until heard.
    let first = encode_odometry(&odom_at(2.025, 2.025, 0.0, header("odom", 100)));
    poll(
        async || {
            robot.put(Stream::Odom, first.clone(), attach).await?;
            let (code, r) = server.get("/v1/robots/bot1").await?;
            Ok((code == 200 && r["pose"]["x"].as_f64().is_some()).then_some(()))
        },
        "the robot's first pose",
    )
    .await?;
    robot
        .put(
            Stream::Odom,
            encode_odometry(&odom_at(3.025, 2.025, 0.0, header("odom", 101))),
            false,
        )
        .await?;
    let r = poll(
        async || {
            let (_, r) = server.get("/v1/robots/bot1").await?;
            let x = r["pose"]["x"].as_f64().unwrap_or(0.0);
            Ok(((x - 3.025).abs() < 1e-9 && r["alive"] == true).then_some(r))
        },
        "the robot alive at its second pose",
    )
    .await?;
    assert_eq!(r["robot"], "bot1", "{r}");
    let robots = server.get("/v1/robots").await?.1;
    assert!(
        robots
            .as_array()
            .is_some_and(|a| a.iter().any(|r| r["robot"] == "bot1")),
        "{robots}"
    );

    // A map-frame cloud: 10 × 10 × 2 points on a 2 cm lattice = 4 × 4 ground-plane voxels (the two layers are one
    // obstacle); a floor point is filtered.
    let mut pts = obstacle_box(5.0, 5.0, 10, 2);
    pts.push([5.0, 5.0, 0.0]);
    robot
        .put(
            Stream::Cloud,
            encode_point_cloud2_xyz(&header("map", 101), &pts),
            attach,
        )
        .await?;
    poll(
        async || Ok((site_points(&server).await?.0 == 16).then_some(())),
        "16 cloud voxels",
    )
    .await?;

    // A scan at t = 100.5 s: the robot was at (2.525, 2.025). Beams every 90° at 1 m, then three that are
    // no return (NaN, shorter than range_min, longer than range_max).
    let scan = |sec_ns: i64| LaserScan {
        header: header_ns("laser", sec_ns),
        angle_min: 0.0,
        angle_max: 6.0 * std::f32::consts::FRAC_PI_2,
        angle_increment: std::f32::consts::FRAC_PI_2,
        range_min: 0.1,
        range_max: 12.0,
        ranges: vec![1.0, 1.0, 1.0, 1.0, f32::NAN, 0.05, 30.0],
        ..LaserScan::default()
    };
    robot
        .put(Stream::Scan, encode_laser_scan(&scan(100_500_000_000)), false)
        .await?;
    poll(
        async || Ok((site_points(&server).await?.0 == 20).then_some(())),
        "4 more voxels from the scan",
    )
    .await?;

    // Outside the odometry history (4 s in the future, 10 s in the past) and malformed: dropped, counted.
    let (_, dropped_before) = site_points(&server).await?;
    robot
        .put(Stream::Scan, encode_laser_scan(&scan(105_000_000_000)), attach)
        .await?;
    robot
        .put(Stream::Scan, encode_laser_scan(&scan(90_000_000_000)), false)
        .await?;
    robot.put(Stream::Scan, vec![0, 1, 0, 0, 1, 2, 3], false).await?;
    let mut truncated = encode_laser_scan(&scan(100_500_000_000));
    truncated.truncate(truncated.len() - 9);
    robot.put(Stream::Scan, truncated, false).await?;
    poll(
        async || Ok((site_points(&server).await?.1 >= dropped_before + 4).then_some(())),
        "four dropped scans",
    )
    .await?;
    assert_eq!(
        site_points(&server).await?.0,
        20,
        "nothing of the dropped scans reached the map"
    );
    let metrics = server.http.get(server.url("/metrics")).send().await?.text().await?;
    for reason in ["future", "too_old", "malformed"] {
        let line = format!("shift_ingest_dropped_total{{reason=\"{reason}\",stream=\"scan\"}}");
        assert!(metrics.contains(&line), "{line} missing from\n{metrics}");
    }
    assert!(metrics.contains("shift_ingest_latency_seconds_bucket"), "{metrics}");

    // Silence: a ROS 2 robot is lost after robot_timeout_s and back with its next message; a native robot is
    // lost when its token goes.
    if let Some(t) = token {
        t.undeclare().await.map_err(|e| anyhow!("{e}"))?;
    }
    poll(
        async || {
            let (_, r) = server.get("/v1/robots/bot1").await?;
            Ok((r["alive"] == false).then_some(()))
        },
        "the robot lost",
    )
    .await?;
    if !native {
        robot
            .put(
                Stream::Odom,
                encode_odometry(&odom_at(3.025, 2.025, 0.0, header("odom", 102))),
                attach,
            )
            .await?;
        poll(
            async || {
                let (_, r) = server.get("/v1/robots/bot1").await?;
                Ok((r["alive"] == true).then_some(()))
            },
            "the robot back",
        )
        .await?;
    }
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bridge_ros2dds_robot_feeds_the_live_map() -> Result<()> {
    ros2_robot_feeds_the_live_map(Ros2Mapping::BridgeRos2dds { namespace: None }, false).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rmw_zenoh_robot_with_attachments_feeds_the_live_map() -> Result<()> {
    ros2_robot_feeds_the_live_map(Ros2Mapping::RmwZenoh { domain: 3 }, true).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn native_robot_scan_feeds_the_live_map() -> Result<()> {
    ros2_robot_feeds_the_live_map(Ros2Mapping::Native, false).await
}
