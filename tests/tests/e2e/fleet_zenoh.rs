//! End-to-end over Zenoh on loopback (no scouting): a scripted robot announces itself, streams CDR odometry
//! and clouds, receives its plan, a late joiner fetches it by query, and losing the token marks it lost.

use anyhow::{Context, Result, anyhow};
use serde_json::{Value, json};
use shift_proto::PlanDocument;
use shift_proto::ros::odometry::encode_odometry;
use shift_proto::ros::path::decode_path;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_tests::fleet::{LONG, free_port, header, obstacle_box, odom, poll, robot_session, wait_robot_alive};
use shift_tests::{TestServer, demo_request, test_config};
use zenoh::bytes::Encoding;
use zenoh::qos::CongestionControl;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn robot_streams_gets_its_plan_and_is_lost_when_its_token_drops() -> Result<()> {
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::new("warn,shiftd=info"))
        .with_test_writer()
        .try_init();
    let dir = tempfile::tempdir()?;
    let port = free_port()?;
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let mut config = test_config(dir.path());
    // The obstacle box below overlaps one of the demo map's own obstacles and is counted voxel by voxel; keep
    // the points the static map explains (dropping them is tested in live_map and the corrections test).
    config.zenoh.known_tolerance_m = 0.0;
    config.zenoh.listen = vec![endpoint.clone()];
    let server = TestServer::start(config).await?;

    let robot = robot_session(&endpoint).await?;
    let token = robot
        .liveliness()
        .declare_token("shift/default/robots/r1/alive")
        .await
        .map_err(|e| anyhow!("{e}"))?;
    let plans = robot
        .declare_subscriber("shift/default/robots/r1/plan")
        .await
        .map_err(|e| anyhow!("{e}"))?;
    let paths = robot
        .declare_subscriber("shift/default/robots/r1/plan_path")
        .await
        .map_err(|e| anyhow!("{e}"))?;

    // The robot is seen alive.
    wait_robot_alive(&server, "r1").await?;

    // Odometry (CDR) and a cloud of an obstacle cluster in the map frame (a 3-D box 0.2-0.6 m high).
    robot
        .put("shift/default/robots/r1/odom", encode_odometry(&odom(0.5, 0.5, 1)))
        .encoding(Encoding::APPLICATION_CDR)
        .congestion_control(CongestionControl::Block)
        .await
        .map_err(|e| anyhow!("{e}"))?;
    // Cell-centred so no point sits on a voxel boundary.
    let mut pts = obstacle_box(4.0, 4.0, 20, 3);
    pts.push([4.0, 4.0, 0.0]); // floor: not an obstacle
    robot
        .put(
            "shift/default/robots/r1/cloud",
            encode_point_cloud2_xyz(&header("map", 1), &pts),
        )
        .encoding(Encoding::APPLICATION_CDR)
        .congestion_control(CongestionControl::Block)
        .await
        .map_err(|e| anyhow!("{e}"))?;
    let site = poll(
        async || {
            let (_, s) = server.get("/v1/sites/demo").await?;
            Ok((s["points_in_tree"].as_u64().unwrap_or(0) > 0).then_some(s))
        },
        "points in the live map",
    )
    .await?;
    // 0.4 m × 0.4 m × 3 layers at 0.05 m voxels: 8 × 8 ground-plane voxels (the layers are one obstacle; the
    // floor point is filtered).
    assert_eq!(site["points_in_tree"], 8 * 8, "{site}");
    let r = server.get("/v1/robots/r1").await?.1;
    assert!((r["pose"]["x"].as_f64().unwrap_or(0.0) - 0.5).abs() < 1e-9, "{r}");

    // Plan, assign, receive.
    let (_, acc) = server.post("/v1/plans", &demo_request()).await?;
    let id = acc["plan_id"].as_str().context("id")?.to_owned();
    server.wait_plan(&id, LONG, |s| s == "ready").await?;
    let (code, st) = server
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": "r1"}))
        .await?;
    assert_eq!(code, 200, "{st}");
    assert_eq!(st["status"], "active");
    let (_, served) = server.get(&format!("/v1/plans/{id}/path")).await?;
    let sample = tokio::time::timeout(LONG, plans.recv_async())
        .await?
        .map_err(|e| anyhow!("{e}"))?;
    let got: Value = serde_json::from_slice(&sample.payload().to_bytes())?;
    assert_eq!(got, served, "the published plan is the served one");
    let sample = tokio::time::timeout(LONG, paths.recv_async())
        .await?
        .map_err(|e| anyhow!("{e}"))?;
    let path = decode_path(&sample.payload().to_bytes())?;
    let doc: PlanDocument = serde_json::from_value(served.clone())?;
    assert_eq!(path.poses.len(), doc.waypoints.len());

    // A robot that joins late asks for its plan.
    let late = robot_session(&endpoint).await?;
    let replies = late
        .get("shift/default/robots/r1/plan")
        .await
        .map_err(|e| anyhow!("{e}"))?;
    let reply = tokio::time::timeout(LONG, replies.recv_async())
        .await?
        .map_err(|e| anyhow!("{e}"))?;
    let sample = reply.result().map_err(|e| anyhow!("query error {e:?}"))?;
    let fetched: Value = serde_json::from_slice(&sample.payload().to_bytes())?;
    assert_eq!(fetched, served);

    // Driving along the plan advances its progress.
    let mid = &doc.waypoints[doc.waypoints.len() / 8];
    for (n, w) in doc.waypoints.iter().take(doc.waypoints.len() / 8 + 1).enumerate() {
        robot
            .put(
                "shift/default/robots/r1/odom",
                encode_odometry(&odom(w.x, w.y, 2 + n as i32)),
            )
            .encoding(Encoding::APPLICATION_CDR)
            .congestion_control(CongestionControl::Block)
            .await
            .map_err(|e| anyhow!("{e}"))?;
    }
    let st = poll(
        async || {
            let (_, st) = server.get(&format!("/v1/plans/{id}")).await?;
            Ok((st["driven_fraction"].as_f64().unwrap_or(0.0) > 0.0).then_some(st))
        },
        "progress along the plan",
    )
    .await?;
    assert_eq!(st["robot"], "r1");
    // The last pose sent arrives (in order, after the others).
    let (mx, my) = (mid.x, mid.y);
    let r = poll(
        async || {
            let (_, r) = server.get("/v1/robots/r1").await?;
            let at = |k: &str| r["pose"][k].as_f64().unwrap_or(f64::NAN);
            Ok(((at("x") - mx).abs() < 1e-9 && (at("y") - my).abs() < 1e-9).then_some(r))
        },
        "the last pose",
    )
    .await?;
    assert_eq!(r["plan_id"], id.as_str());
    assert!(r["driven_m"].as_f64().unwrap_or(0.0) > 0.0, "{r}");

    // The token goes: the robot is lost.
    token.undeclare().await.map_err(|e| anyhow!("{e}"))?;
    poll(
        async || {
            let (_, r) = server.get("/v1/robots/r1").await?;
            Ok((r["alive"] == false).then_some(()))
        },
        "robot r1 lost",
    )
    .await?;
    let robots = server.get("/v1/robots").await?.1;
    assert_eq!(robots.as_array().map(Vec::len), Some(1));

    // Malformed clouds are dropped and counted; ingest keeps working.
    robot
        .put("shift/default/robots/r1/cloud", vec![0u8, 1, 0, 0, 9, 9])
        .await
        .map_err(|e| anyhow!("{e}"))?;
    poll(
        async || {
            let (_, s) = server.get("/v1/sites/demo").await?;
            Ok((s["dropped_clouds"].as_u64().unwrap_or(0) >= 1).then_some(()))
        },
        "malformed cloud counted",
    )
    .await?;
    late.close().await.map_err(|e| anyhow!("{e}"))?;
    robot.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}
