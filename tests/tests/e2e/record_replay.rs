//! Recording and replay end to end: a fleet session over loopback Zenoh with `[record]` on (a scripted robot
//! with a liveliness token streaming CDR odometry and a cloud, a plan assigned and delivered, a late joiner's
//! query, the token dropped → lost); the server stops (files finished); the recording replays into the engine
//! to the same decisions, replays onto Zenoh into a second daemon that sees the same robot and obstacles, and
//! the Python `mcap` + `mcap-ros2-support` readers open it and decode the cloud to the points sent.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, anyhow};
use serde_json::{Value, json};
use shift_proto::keys::{KeySpace, Ros2Mapping};
use shift_proto::ros::odometry::encode_odometry;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_tests::fleet::{LONG, free_port, header, obstacle_box, odom, poll, robot_session, wait_robot_alive};
use shift_tests::{TestServer, demo_request, test_config};
use shiftd::replay::{Action, KeyMap, Recorded, into_engine, onto_zenoh};
use zenoh::bytes::Encoding;

fn zerr(e: zenoh::Error) -> anyhow::Error {
    anyhow!("{e}")
}

/// Runs the scripted session against a recording server; returns the points of the cloud sent.
async fn recorded_session(record_dir: &Path, data_dir: &Path) -> Result<Vec<[f32; 3]>> {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = test_config(data_dir);
    // The obstacle box overlaps a demo-map obstacle and is counted voxel by voxel (see fleet_zenoh).
    config.zenoh.known_tolerance_m = 0.0;
    config.zenoh.listen = vec![endpoint.clone()];
    config.record.dir = record_dir.to_path_buf();
    config.record.grid_interval_s = 1;
    let server = TestServer::start(config).await?;

    let robot = robot_session(&endpoint).await?;
    let token = robot
        .liveliness()
        .declare_token("shift/default/robots/r1/alive")
        .await
        .map_err(zerr)?;
    let plans = robot
        .declare_subscriber("shift/default/robots/r1/plan")
        .await
        .map_err(zerr)?;
    wait_robot_alive(&server, "r1").await?;

    robot
        .put("shift/default/robots/r1/odom", encode_odometry(&odom(0.5, 0.5, 1)))
        .encoding(Encoding::APPLICATION_CDR)
        .await
        .map_err(zerr)?;
    // A 0.4 m box at (4, 4), three layers (8 × 8 ground-plane voxels), plus a floor point that is filtered.
    let mut pts = obstacle_box(4.0, 4.0, 20, 3);
    pts.push([4.0, 4.0, 0.0]);
    robot
        .put(
            "shift/default/robots/r1/cloud",
            encode_point_cloud2_xyz(&header("map", 1), &pts),
        )
        .encoding(Encoding::APPLICATION_CDR)
        .await
        .map_err(zerr)?;
    poll(
        async || {
            let (_, s) = server.get("/v1/sites/demo").await?;
            Ok((s["points_in_tree"].as_u64().unwrap_or(0) > 0).then_some(()))
        },
        "points in the live map",
    )
    .await?;

    let (_, acc) = server.post("/v1/plans", &demo_request()).await?;
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    server.wait_plan(&id, LONG, |s| s == "ready").await?;
    let (code, st) = server
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": "r1"}))
        .await?;
    assert_eq!(code, 200, "{st}");
    let sample = tokio::time::timeout(LONG, plans.recv_async()).await?.map_err(zerr)?;
    let doc: Value = serde_json::from_slice(&sample.payload().to_bytes())?;
    assert_eq!(doc["plan_id"], id.as_str());

    // A late joiner asks for the plan.
    let late = robot_session(&endpoint).await?;
    let replies = late.get("shift/default/robots/r1/plan").await.map_err(zerr)?;
    let reply = tokio::time::timeout(LONG, replies.recv_async()).await?.map_err(zerr)?;
    assert!(reply.result().is_ok(), "the late joiner gets the plan");

    // Drive the first waypoints (CDR), and one JSON pose.
    let wps = doc["waypoints"].as_array().context("waypoints")?;
    for (n, w) in wps.iter().take(6).enumerate() {
        let (x, y) = (w["x"].as_f64().unwrap_or(0.0), w["y"].as_f64().unwrap_or(0.0));
        robot
            .put(
                "shift/default/robots/r1/odom",
                encode_odometry(&odom(x, y, 2 + n as i32)),
            )
            .encoding(Encoding::APPLICATION_CDR)
            .await
            .map_err(zerr)?;
    }
    let last = &wps[wps.len().min(6) - 1];
    let json_pose = json!({"x": last["x"], "y": last["y"], "yaw": 0.25, "stamp": 9.0});
    robot
        .put("shift/default/robots/r1/odom", serde_json::to_vec(&json_pose)?)
        .encoding(Encoding::APPLICATION_JSON)
        .await
        .map_err(zerr)?;
    poll(
        async || {
            let (_, r) = server.get("/v1/robots/r1").await?;
            Ok(((r["pose"]["yaw"].as_f64().unwrap_or(0.0) - 0.25).abs() < 1e-9).then_some(()))
        },
        "the JSON pose",
    )
    .await?;

    token.undeclare().await.map_err(zerr)?;
    poll(
        async || {
            let (_, r) = server.get("/v1/robots/r1").await?;
            Ok((r["alive"] == false).then_some(()))
        },
        "robot r1 lost",
    )
    .await?;
    late.close().await.map_err(zerr)?;
    robot.close().await.map_err(zerr)?;
    server.stop().await?;
    Ok(pts)
}

fn mcap_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let all: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    let unfinished: Vec<_> = all.iter().filter(|p| p.to_string_lossy().ends_with(".part")).collect();
    assert!(unfinished.is_empty(), "unfinished files after shutdown: {unfinished:?}");
    Ok(shiftd::record::writer::recordings_in(dir)?)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recorded_fleet_session_replays_to_the_same_decisions_and_reads_in_python() -> Result<()> {
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::new("warn,shiftd=info"))
        .with_test_writer()
        .try_init();
    let dir = tempfile::tempdir()?;
    let record_dir = dir.path().join("rec");
    let sent = recorded_session(&record_dir, &dir.path().join("data")).await?;
    let files = mcap_files(&record_dir)?;
    assert!(!files.is_empty(), "no recording written");

    // Into the engine: the same decisions, and the ones the session was about.
    let rec = Recorded::read(&files)?;
    assert_eq!(rec.unreadable, 0);
    let mut out = Vec::new();
    let report = into_engine(&rec, &mut out, true)?;
    assert!(report.mismatches.is_empty(), "{:#?}", report.mismatches);
    assert!(report.inputs > 5 && report.decisions > report.inputs, "{report:?}");
    let lines: Vec<Value> = String::from_utf8(out)?
        .lines()
        .map(serde_json::from_str)
        .collect::<Result<_, _>>()?;
    let any = |f: &dyn Fn(&Value) -> bool| lines.iter().any(|l| f(&l["decision"]));
    assert!(any(&|d| d["type"] == "robot"
        && d["view"]["robot"] == "r1"
        && d["view"]["alive"] == true));
    assert!(any(&|d| d["type"] == "plan_status" && d["status"]["status"] == "active"));
    assert!(any(&|d| d["type"] == "deliver_plan" && d["robot"] == "r1"));
    assert!(any(&|d| d["type"] == "robot" && d["view"]["alive"] == false));
    let last_robot = lines
        .iter()
        .rev()
        .find(|l| l["decision"]["type"] == "robot")
        .context("robot decisions")?;
    assert_eq!(
        last_robot["decision"]["view"]["alive"], false,
        "the run ends with r1 lost"
    );

    // A tampered recording is caught.
    let mut tampered = Recorded::read(&files)?;
    let key = *tampered
        .inputs
        .iter()
        .find(|(_, i)| matches!(i.event, shift_engine::Event::RobotPose { .. }))
        .context("a pose input")?
        .0;
    if let Some(i) = tampered.inputs.get_mut(&key)
        && let shift_engine::Event::RobotPose { pose, .. } = &mut i.event
    {
        pose.x += 1.0;
    }
    let report = into_engine(&tampered, &mut std::io::sink(), true)?;
    assert!(
        !report.mismatches.is_empty(),
        "a changed pose must change the decisions"
    );

    // What robots sent is there to put back: the cloud on its key, the token's life.
    let clouds = rec
        .ingest
        .iter()
        .filter(|(_, a)| matches!(a, Action::Put { key, .. } if key == "shift/default/robots/r1/cloud"))
        .count();
    assert_eq!(clouds, 1);
    let tokens: Vec<bool> = rec
        .ingest
        .iter()
        .filter_map(|(_, a)| match a {
            Action::Token { alive, .. } => Some(*alive),
            Action::Put { .. } => None,
        })
        .collect();
    assert_eq!(tokens, vec![true, false]);

    // Onto Zenoh, into a second daemon: it sees the robot come and go and the obstacle.
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = test_config(&dir.path().join("data2"));
    config.zenoh.known_tolerance_m = 0.0;
    config.zenoh.listen = vec![endpoint.clone()];
    let second = TestServer::start(config).await?;
    let player = robot_session(&endpoint).await?;
    tokio::time::sleep(std::time::Duration::from_secs(1)).await;
    let keys = KeyMap::new(KeySpace::new("shift", "default")?, Ros2Mapping::Native);
    let n = onto_zenoh(&rec, &player, &keys, 20.0).await?;
    assert_eq!(n, rec.ingest.len());
    poll(
        async || {
            let (_, s) = second.get("/v1/sites/demo").await?;
            Ok((s["points_in_tree"] == 8 * 8).then_some(()))
        },
        "the replayed cloud in the second daemon",
    )
    .await?;
    poll(
        async || {
            let (code, r) = second.get("/v1/robots/r1").await?;
            Ok((code == 200 && r["alive"] == false && r["pose"]["yaw"].as_f64() == Some(0.25)).then_some(()))
        },
        "the replayed robot, lost at the end with its last pose",
    )
    .await?;
    player.close().await.map_err(zerr)?;
    second.stop().await?;

    python_reads(&files, &sent)
}

/// The recording opens with the Python readers and its cloud decodes to the points sent.
fn python_reads(files: &[PathBuf], sent: &[[f32; 3]]) -> Result<()> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("python/read_recording.py");
    let out = match Command::new("python3").arg(&script).args(files).output() {
        Ok(o) => o,
        Err(e) if std::env::var_os("CI").is_none() => {
            eprintln!("SKIPPED the Python check: python3 not runnable ({e})");
            return Ok(());
        }
        Err(e) => return Err(anyhow!("python3: {e}")),
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(3) {
        anyhow::ensure!(
            std::env::var_os("CI").is_none(),
            "in CI the Python readers must be installed: {stderr}"
        );
        eprintln!("SKIPPED the Python check: {stderr}");
        return Ok(());
    }
    anyhow::ensure!(out.status.success(), "read_recording.py failed: {stderr}");
    let v: Value = serde_json::from_slice(&out.stdout)?;
    for f in v["files"].as_array().context("files")? {
        assert_eq!(f["summary"], true, "every file finished: {f}");
        assert_eq!(f["profile"], "ros2");
    }
    let ch = &v["channels"];
    let cloud = &ch["shift/default/robots/r1/cloud"];
    assert_eq!(cloud["schema"], "sensor_msgs/msg/PointCloud2", "{ch}");
    assert_eq!(cloud["schema_encoding"], "ros2msg");
    assert_eq!(cloud["message_encoding"], "cdr");
    assert_eq!(
        cloud["metadata"]["topic_type_hash"],
        shift_proto::ros::type_hash::POINT_CLOUD2
    );
    assert_eq!(
        ch["shift/default/robots/r1/odom"]["schema"], "nav_msgs/msg/Odometry",
        "{ch}"
    );
    assert!(ch["/shift/engine/events"]["count"].as_u64().unwrap_or(0) > 5, "{ch}");
    assert!(ch["/shift/engine/decisions"]["count"].as_u64().unwrap_or(0) > 5, "{ch}");
    assert_eq!(ch["/shift/plans"]["schema"], "shift.PlanDocument");
    assert_eq!(ch["/shift/plan_status"]["schema_encoding"], "jsonschema");
    assert_eq!(ch["/shift/sites/demo/occupancy"]["schema"], "foxglove.Grid", "{ch}");
    assert_eq!(v["undecodable"], 0);
    let clouds = v["clouds"].as_array().context("clouds")?;
    assert_eq!(clouds.len(), 1);
    assert_eq!(clouds[0]["frame_id"], "map");
    let got: Vec<[f32; 3]> = clouds[0]["points"]
        .as_array()
        .context("points")?
        .iter()
        .map(|p| {
            let c = |i: usize| p[i].as_f64().unwrap_or(f64::NAN) as f32;
            [c(0), c(1), c(2)]
        })
        .collect();
    assert_eq!(got, sent, "the recorded cloud decodes to the points sent");
    Ok(())
}

/// A recording made by the daemon before routing by assignment (format 1: two runs, a map upload, plans queued,
/// cancelled, refused, computed, assigned and re-assigned, a restart that restores an active plan) still
/// replays through today's engine without a mismatch: what format 1 could not hold is left out of the comparison.
#[test]
fn a_format_1_recording_still_checks() -> Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/recordings/format1");
    let files = shiftd::replay::expand(&[dir])?;
    assert_eq!(files.len(), 2);
    let rec = Recorded::read(&files)?;
    assert!(rec.configs.values().all(|c| c.format == 1));
    let report = into_engine(&rec, &mut std::io::sink(), true)?;
    assert!(report.inputs >= 50, "{} inputs", report.inputs);
    assert!(report.mismatches.is_empty(), "{:?}", report.mismatches);
    Ok(())
}
