//! The fleet loop as the outside world drives it: a backend over HTTP with its own site, robots that are
//! separate Zenoh participants, join late, feed any site, publish scans before the odometry that places them,
//! or run under a ROS 2 key layout. Every test asserts what a user would see: a correction on the robot's key,
//! points in the right live map and none in the wrong one, progress where the robot is, status on Zenoh.

use std::time::Duration;

use anyhow::{Context, Result, anyhow, bail};
use serde_json::{Value, json};
use shift_proto::keys::Ros2Mapping;
use shift_proto::ros::laser_scan::encode_laser_scan;
use shift_proto::ros::odometry::encode_odometry;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_proto::ros::{LaserScan, Time};
use shift_proto::{CorrectionDoc, CorrectionReason, PlanDocument, PlanStatusResponse};
use shift_tests::fleet::{LONG, free_port, header_ns, odom_at, poll, robot_session, room_grid};
use shift_tests::path::{along, check_correction, clearance, index_at, length, post, seg_dist, straight_from};
use shift_tests::{TestServer, test_config};
use zenoh::bytes::Encoding;

const RADIUS: f64 = 0.15;
const SEC: i64 = 1_000_000_000;

/// How a test robot names its keys.
#[derive(Clone, Copy, PartialEq)]
enum Layout {
    /// DESIGN §5.4 keys with a liveliness token.
    Native,
    /// zenoh-bridge-ros2dds: `{robot}/odom`, `{robot}/points`, `{robot}/scan`; no token.
    Bridge,
}

/// A robot as a separate Zenoh participant, publishing stamped CDR odometry, clouds and scans.
struct Robot {
    name: String,
    layout: Layout,
    session: zenoh::Session,
    _token: Option<zenoh::liveliness::LivelinessToken>,
    corrections: zenoh::pubsub::Subscriber<zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>>,
}

impl Robot {
    async fn join(endpoint: &str, name: &str, layout: Layout) -> Result<Self> {
        let session = robot_session(endpoint).await?;
        let token = match layout {
            Layout::Native => Some(
                session
                    .liveliness()
                    .declare_token(format!("shift/default/robots/{name}/alive"))
                    .await
                    .map_err(|e| anyhow!("{e}"))?,
            ),
            Layout::Bridge => None,
        };
        let corrections = session
            .declare_subscriber(format!("shift/default/robots/{name}/corrections"))
            .await
            .map_err(|e| anyhow!("{e}"))?;
        Ok(Self {
            name: name.into(),
            layout,
            session,
            _token: token,
            corrections,
        })
    }

    fn key(&self, stream: &str) -> String {
        match (self.layout, stream) {
            (Layout::Native, s) => format!("shift/default/robots/{}/{s}", self.name),
            (Layout::Bridge, "cloud") => format!("{}/points", self.name),
            (Layout::Bridge, s) => format!("{}/{s}", self.name),
        }
    }

    async fn put(&self, stream: &str, bytes: Vec<u8>) -> Result<()> {
        self.session
            .put(self.key(stream), bytes)
            .encoding(Encoding::APPLICATION_CDR)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    /// nav_msgs/Odometry in frame `odom`, stamped `ns`.
    async fn odom(&self, x: f64, y: f64, yaw: f64, ns: i64) -> Result<()> {
        self.put("odom", encode_odometry(&odom_at(x, y, yaw, header_ns("odom", ns))))
            .await
    }

    /// A map-frame PointCloud2.
    async fn cloud(&self, pts: &[[f32; 3]], ns: i64) -> Result<()> {
        self.put("cloud", encode_point_cloud2_xyz(&header_ns("map", ns), pts))
            .await
    }

    /// A LaserScan stamped `ns` whose beams within `half_width_m` of straight ahead return at `range_m`.
    async fn scan_ahead(&self, range_m: f32, half_width_m: f32, ns: i64) -> Result<()> {
        let n = 121;
        let (min, max) = (-0.6f32, 0.6f32);
        let inc = (max - min) / (n - 1) as f32;
        let ranges = (0..n)
            .map(|i| {
                let a = min + inc * i as f32;
                if (range_m * a.sin()).abs() <= half_width_m {
                    range_m / a.cos()
                } else {
                    f32::INFINITY
                }
            })
            .collect();
        let scan = LaserScan {
            header: header_ns("laser", ns),
            angle_min: min,
            angle_max: max,
            angle_increment: inc,
            range_min: 0.05,
            range_max: 20.0,
            ranges,
            ..LaserScan::default()
        };
        self.put("scan", encode_laser_scan(&scan)).await
    }

    async fn next_correction(&self, timeout: Duration) -> Result<CorrectionDoc> {
        let sample = tokio::time::timeout(timeout, self.corrections.recv_async())
            .await
            .context("no correction arrived")?
            .map_err(|e| anyhow!("{e}"))?;
        Ok(serde_json::from_slice(&sample.payload().to_bytes())?)
    }
}

/// A server with Zenoh on a free loopback port; `default_site` is `[zenoh] site` ("" = none).
async fn server(default_site: &str, mapping: Ros2Mapping) -> Result<(TestServer, String, tempfile::TempDir)> {
    let dir = tempfile::tempdir()?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = test_config(dir.path());
    config.zenoh.listen = vec![endpoint.clone()];
    config.zenoh.site = default_site.into();
    config.zenoh.mapping = mapping;
    config.zenoh.known_tolerance_m = 0.0;
    let server = TestServer::start(config).await?;
    Ok((server, endpoint, dir))
}

/// Uploads an 8 m × 4 m room as `site`, plans on it and assigns the plan to `robot`.
async fn plan_on(server: &TestServer, site: &str, robot: &str) -> Result<(String, PlanDocument)> {
    let (code, body) = server
        .post(&format!("/v1/sites/{site}/map"), &room_grid(160, 80, 0.05, &[]))
        .await?;
    if code != 201 {
        bail!("map upload: {code} {body}");
    }
    let req = json!({"site": site, "start": [0.5, 0.5], "robot": {"radius": RADIUS, "tool_width": 0.3}});
    let (_, acc) = server.post("/v1/plans", &req).await?;
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    server.wait_plan(&id, LONG, |s| s == "ready").await?;
    let (code, st) = server
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": robot}))
        .await?;
    if code != 200 {
        bail!("assign: {code} {st}");
    }
    let (_, served) = server.get(&format!("/v1/plans/{id}/path")).await?;
    Ok((id, serde_json::from_value(served)?))
}

/// Points of the site's live map.
async fn live_points(server: &TestServer, site: &str) -> Result<u64> {
    let (code, s) = server.get(&format!("/v1/sites/{site}")).await?;
    if code != 200 {
        bail!("site {site}: {code} {s}");
    }
    s["points_in_tree"].as_u64().context("points_in_tree")
}

/// What the obstacle is seen with.
#[derive(Clone, Copy, PartialEq)]
enum Sensor {
    Cloud,
    Scan,
}

/// A backend's own site "hall" beside the default site "demo": the robot's obstacle, seen ahead on its path,
/// gives it a collision-free correction, lands in hall's live map and not in demo's.
async fn obstacle_on_the_plans_site(sensor: Sensor, layout: Layout) -> Result<()> {
    let mapping = match layout {
        Layout::Native => Ros2Mapping::Native,
        Layout::Bridge => Ros2Mapping::BridgeRos2dds { namespace: None },
    };
    let (server, endpoint, _dir) = server("demo", mapping).await?;
    let robot = Robot::join(&endpoint, "r1", layout).await?;
    let (id, doc) = plan_on(&server, "hall", "r1").await?;
    let w = &doc.waypoints;
    let seg = straight_from(w, 0, 4.0).context("a lane 4 m long")?;
    // Drive up to the lane and 1 m onto it, odometry at 20 Hz.
    let mut t = 10 * SEC;
    for k in (0..=seg.0).step_by(3) {
        robot.odom(w[k].x, w[k].y, 0.0, t).await?;
        t += SEC / 20;
    }
    let mut pose = along(w, seg, 0.0);
    for k in 0..=5 {
        pose = along(w, seg, 0.2 * f64::from(k));
        robot.odom(pose.0, pose.1, pose.2, t).await?;
        t += SEC / 20;
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let ahead = 2.0;
    let (ox, oy, _) = along(w, seg, 1.0 + ahead);
    let obstacle = match sensor {
        Sensor::Cloud => {
            let pts = post(ox, oy);
            robot.cloud(&pts, t).await?;
            pts
        }
        Sensor::Scan => {
            // The scan at the stamp of the last pose: returns 2 m ahead, ±0.1 m wide, at z = 0.
            robot.scan_ahead(ahead as f32, 0.1, t - SEC / 20).await?;
            post(ox, oy).iter().map(|p| [p[0], p[1], 0.0]).collect()
        }
    };
    assert!(
        clearance(w, seg.0..seg.1, &obstacle) < RADIUS,
        "the old path runs into it"
    );
    let c = robot.next_correction(LONG).await?;
    assert_eq!((c.plan_id.as_str(), c.robot.as_str()), (id.as_str(), "r1"));
    assert_eq!((c.base_version, c.version), (1, 2));
    assert_ne!(c.reason, CorrectionReason::Skipped, "{c:?}");
    // Joined: the patch ends on the old lane; clear of the obstacle by the radius.
    check_correction(&doc, &c, &obstacle, false, RADIUS - 0.03)?;
    for p in [&c.waypoints[0], &c.waypoints[c.waypoints.len() - 1]] {
        let d = seg_dist((p.x, p.y), (w[seg.0].x, w[seg.0].y), (w[seg.1].x, w[seg.1].y));
        assert!(d < 1e-6, "patch end {p:?} is {d} m off the old lane");
    }
    assert!(live_points(&server, "hall").await? > 0);
    assert_eq!(
        live_points(&server, "demo").await?,
        0,
        "the default site got none of it"
    );
    // The live map's heap is reported per site.
    let metrics = server.http.get(server.url("/metrics")).send().await?.text().await?;
    let bytes = metrics
        .lines()
        .find_map(|l| l.strip_prefix("shift_live_map_bytes{site=\"hall\"} "))
        .and_then(|v| v.parse::<f64>().ok())
        .context("shift_live_map_bytes of hall in the metrics")?;
    assert!(bytes > 0.0, "{bytes}");
    // And the daemon's memory per component (set when the first points were placed): the live maps, and the
    // static clearance fields they filter with (hall's map was uploaded).
    for component in ["live_maps", "site_clearance"] {
        let prefix = format!("shift_memory_bytes{{component=\"{component}\"}} ");
        let v = metrics
            .lines()
            .find_map(|l| l.strip_prefix(prefix.as_str()))
            .and_then(|v| v.parse::<f64>().ok())
            .with_context(|| format!("{prefix}in the metrics"))?;
        assert!(v > 0.0, "{component}: {v}");
    }
    let (_, r) = server.get("/v1/robots/r1").await?;
    assert_eq!(r["site"], "hall", "{r}");
    assert!(r["sensors"]["placed"].as_u64().unwrap_or(0) >= 1, "{r}");
    let _ = pose;
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cloud_on_a_backends_own_site_gets_a_correction() -> Result<()> {
    obstacle_on_the_plans_site(Sensor::Cloud, Layout::Native).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_scan_on_a_backends_own_site_gets_a_correction() -> Result<()> {
    obstacle_on_the_plans_site(Sensor::Scan, Layout::Native).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_ros2_bridge_robot_on_a_backends_own_site_gets_a_correction() -> Result<()> {
    obstacle_on_the_plans_site(Sensor::Scan, Layout::Bridge).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_first_seen_far_along_its_plan_is_found_there_and_corrected() -> Result<()> {
    let (server, endpoint, _dir) = server("demo", Ros2Mapping::Native).await?;
    let robot = Robot::join(&endpoint, "r1", Layout::Native).await?;
    let (id, doc) = plan_on(&server, "hall", "r1").await?;
    let w = &doc.waypoints;
    let total = length(w);
    // Its first odometry: on a straight stretch at 60 % of the plan or later (it joined late).
    let seg = straight_from(w, index_at(w, 0.6 * total), 2.5).context("a straight stretch after 60 %")?;
    let (x, y, yaw) = along(w, seg, 0.0);
    let mut t = 10 * SEC;
    for _ in 0..3 {
        robot.odom(x, y, yaw, t).await?;
        t += SEC / 20;
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let st = poll(
        async || {
            let (_, st) = server.get(&format!("/v1/plans/{id}")).await?;
            Ok((st["driven_fraction"].as_f64().unwrap_or(0.0) >= 0.59).then_some(st))
        },
        "progress re-acquired",
    )
    .await?;
    let jumps = st["progress_jumps"].as_array().context("the jump is reported")?;
    assert_eq!(jumps.len(), 1, "{st}");
    assert_eq!(jumps[0]["backwards"], false);
    // An obstacle 1.5 m ahead.
    let (ox, oy, _) = along(w, seg, 1.5);
    let pts = post(ox, oy);
    robot.cloud(&pts, t).await?;
    let c = robot.next_correction(LONG).await?;
    assert_eq!(c.base_version, 1);
    assert!(c.from >= seg.0, "the patch is ahead of the robot: {c:?}");
    check_correction(&doc, &c, &pts, false, RADIUS - 0.03)?;
    let (_, st) = server.get(&format!("/v1/plans/{id}")).await?;
    assert!(st["driven_fraction"].as_f64().unwrap_or(0.0) >= 0.59, "{st}");
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_unassigned_robot_without_a_default_site_feeds_nothing() -> Result<()> {
    let (server, endpoint, _dir) = server("", Ros2Mapping::Native).await?;
    let robot = Robot::join(&endpoint, "r9", Layout::Native).await?;
    let pts = post(2.0, 2.0);
    let r = poll(
        async || {
            robot.cloud(&pts, 5 * SEC).await?;
            tokio::time::sleep(Duration::from_millis(50)).await;
            let (code, r) = server.get("/v1/robots/r9").await?;
            Ok((code == 200 && r["sensors"]["dropped"]["unrouted"].as_u64().unwrap_or(0) >= 1).then_some(r))
        },
        "the cloud counted unrouted",
    )
    .await?;
    assert!(r.get("site").is_none_or(Value::is_null), "{r}");
    assert_eq!(r["sensors"]["placed"], 0, "{r}");
    assert_eq!(live_points(&server, "demo").await?, 0);
    let metrics = server.http.get(server.url("/metrics")).send().await?.text().await?;
    assert!(
        metrics
            .lines()
            .any(|l| l.starts_with("shift_ingest_dropped_total") && l.contains("reason=\"unrouted\"")),
        "unrouted drops in the metrics"
    );
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn scans_that_arrive_before_their_odometry_wait_for_it_at_ten_times_speed() -> Result<()> {
    let (server, endpoint, _dir) = server("demo", Ros2Mapping::Native).await?;
    let robot = Robot::join(&endpoint, "r2", Layout::Native).await?;
    // A real log's rhythm (10 Hz odometry and scans with equal stamps) played at 10×: 10 ms apart. Every third
    // scan is published before its odometry.
    let n = 100;
    for k in 0..n {
        let t = 100 * SEC + k * SEC / 10;
        let x = 1.0 + 0.01 * k as f64;
        if k % 3 == 0 {
            robot.scan_ahead(1.0, 0.2, t).await?;
            robot.odom(x, 1.0, 0.0, t).await?;
        } else {
            robot.odom(x, 1.0, 0.0, t).await?;
            robot.scan_ahead(1.0, 0.2, t).await?;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let r = poll(
        async || {
            let (_, r) = server.get("/v1/robots/r2").await?;
            let s = &r["sensors"];
            let dropped: u64 = s["dropped"]
                .as_object()
                .map_or(0, |m| m.values().filter_map(Value::as_u64).sum());
            let done = s["placed"].as_u64().unwrap_or(0) + dropped >= n as u64 && s["waiting"] == 0;
            Ok(done.then_some(r))
        },
        "every scan placed or dropped",
    )
    .await?;
    assert_eq!(r["sensors"]["placed"], n, "no scan lost: {r}");
    assert!(live_points(&server, "demo").await? > 0);
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn plan_status_reaches_zenoh_in_order_and_answers_queries() -> Result<()> {
    let (server, endpoint, _dir) = server("demo", Ros2Mapping::Native).await?;
    let watcher = robot_session(&endpoint).await?;
    let sub = watcher
        .declare_subscriber("shift/default/plans/*/status")
        .await
        .map_err(|e| anyhow!("{e}"))?;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let (_, acc) = server.post("/v1/plans", &shift_tests::demo_request()).await?;
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    server.wait_plan(&id, LONG, |s| s == "ready").await?;
    let (code, _) = server
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": "r1"}))
        .await?;
    assert_eq!(code, 200);
    let mut seen: Vec<String> = Vec::new();
    while seen.last().map(String::as_str) != Some("active") {
        let sample = tokio::time::timeout(LONG, sub.recv_async())
            .await
            .context("status on zenoh")?
            .map_err(|e| anyhow!("{e}"))?;
        assert_eq!(sample.key_expr().as_str(), format!("shift/default/plans/{id}/status"));
        let st: PlanStatusResponse = serde_json::from_slice(&sample.payload().to_bytes())?;
        let status = st.status.as_str().to_owned();
        if seen.last() != Some(&status) {
            seen.push(status);
        }
    }
    assert_eq!(seen, ["queued", "planning", "ready", "active"]);
    // A get on the key answers the current status.
    let replies = watcher
        .get(format!("shift/default/plans/{id}/status"))
        .await
        .map_err(|e| anyhow!("{e}"))?;
    let reply = tokio::time::timeout(LONG, replies.recv_async())
        .await?
        .map_err(|e| anyhow!("{e}"))?;
    let sample = reply.result().map_err(|e| anyhow!("query error {e:?}"))?;
    let st: PlanStatusResponse = serde_json::from_slice(&sample.payload().to_bytes())?;
    assert_eq!((st.plan_id.as_str(), st.status.as_str()), (id.as_str(), "active"));
    assert_eq!(st.robot.as_deref(), Some("r1"));
    watcher.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}

/// Writes a ROS 2 bag (rosbag2's MCAP storage, the `mcap-ros2-support` writer) of robot1's odometry and scans.
fn write_ros2_bag(path: &std::path::Path) -> Result<()> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/python/make_ros2_bag.py");
    let defs = concat!(env!("CARGO_MANIFEST_DIR"), "/../proto/src/ros/msg_defs");
    let out = std::process::Command::new("python3")
        .arg(script)
        .arg(path)
        .arg(defs)
        .output()
        .context("running python3")?;
    if !out.status.success() {
        bail!(
            "make_ros2_bag.py failed: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_ros2_bag_replays_onto_zenoh_and_its_points_reach_the_live_map() -> Result<()> {
    use shift_proto::keys::KeySpace;
    use shiftd::replay::{KeyMap, Recorded, into_engine, onto_zenoh};
    let dir = tempfile::tempdir()?;
    let bag = dir.path().join("robot1.mcap");
    write_ros2_bag(&bag)?;
    let rec = Recorded::read(std::slice::from_ref(&bag))?;
    assert!(
        rec.ingest.len() >= 40,
        "odometry and scans read from the bag: {:?}",
        rec.topics
    );
    // It holds no engine inputs: a check of it cannot pass.
    let err = into_engine(&rec, &mut std::io::sink(), true).expect_err("nothing to check");
    assert!(err.to_string().contains("no recorded engine inputs"), "{err}");

    let mapping = Ros2Mapping::BridgeRos2dds { namespace: None };
    let (server, endpoint, _dir) = server("demo", mapping.clone()).await?;
    let player = robot_session(&endpoint).await?;
    tokio::time::sleep(Duration::from_millis(500)).await;
    let keys = KeyMap::new(KeySpace::new("shift", "default")?, mapping);
    let n = onto_zenoh(&rec, &player, &keys, 10.0).await?;
    assert_eq!(n, rec.ingest.len());
    let r = poll(
        async || {
            let (_, r) = server.get("/v1/robots/robot1").await?;
            Ok((r["sensors"]["placed"].as_u64().unwrap_or(0) >= 20).then_some(r))
        },
        "the bag's scans placed",
    )
    .await?;
    assert!(r["sensors"]["dropped"].get("future").is_none(), "{r}");
    assert!(live_points(&server, "demo").await? > 0);
    player.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}

#[test]
fn time_helper_is_exact() {
    assert_eq!(Time::from_ns(10 * SEC + 5).to_ns(), 10 * SEC + 5);
}
