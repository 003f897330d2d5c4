//! kill -9 of a real `shiftd` process while a robot drives its plan: after the restart the robot (a separate
//! Zenoh participant) keeps publishing, its progress is recovered from its first odometry message, and a new
//! obstacle still gets a correction based on the last committed version.
//!
//! This test lives in the daemon's package because it needs the `shiftd` binary (`CARGO_BIN_EXE_shiftd`) to kill;
//! its HTTP helper is deliberately tiny, the plan geometry is the end-to-end tests' own (`tests/src/path.rs`).

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use anyhow::{Context, Result, anyhow, bail};
use serde_json::{Value, json};
use shift_proto::ros::odometry::{Odometry, encode_odometry};
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_proto::ros::{Header, Time};
use shift_proto::{CorrectionDoc, PlanDocument, WaypointDoc};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use zenoh::bytes::Encoding;

/// The end-to-end tests' plan geometry (`tests/src/path.rs`), shared by path: this package cannot depend on
/// `shift-tests`, which depends on it.
#[allow(dead_code)]
#[path = "../../../tests/src/path.rs"]
mod path;

const LONG: Duration = Duration::from_secs(120);

fn free_port() -> Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// One HTTP/1.1 request with `Connection: close` → (status, JSON body or Null).
async fn http(port: u16, method: &str, path: &str, body: Option<&Value>) -> Result<(u16, Value)> {
    let mut s = tokio::net::TcpStream::connect(("127.0.0.1", port)).await?;
    let body = body.map(Value::to_string).unwrap_or_default();
    let req = format!(
        "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\nContent-Type: application/json\r\n\
         Content-Length: {}\r\n\r\n{body}",
        body.len()
    );
    s.write_all(req.as_bytes()).await?;
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).await?;
    let text = String::from_utf8_lossy(&raw);
    let (head, rest) = text.split_once("\r\n\r\n").context("HTTP response")?;
    let status = head.split(' ').nth(1).context("status")?.parse()?;
    // The body may be chunked: take the JSON between the first '{' or '[' and the last '}' or ']'.
    let json = match (rest.find(['{', '[']), rest.rfind(['}', ']'])) {
        (Some(a), Some(b)) if b >= a => serde_json::from_str(&rest[a..=b]).unwrap_or(Value::Null),
        _ => Value::Null,
    };
    Ok((status, json))
}

/// A `shiftd serve` process.
struct Daemon {
    child: Child,
    port: u16,
}

impl Daemon {
    async fn start(dir: &Path, port: u16, endpoint: &str) -> Result<Self> {
        let config = dir.join("shiftd.toml");
        std::fs::write(
            &config,
            "[zenoh]\nknown_tolerance_m = 0.0\n[jobs]\nworkers = 1\nshutdown_grace_s = 0\n",
        )?;
        let child = Command::new(env!("CARGO_BIN_EXE_shiftd"))
            .args([
                "serve",
                "--bind",
                &format!("127.0.0.1:{port}"),
                "--zenoh-listen",
                endpoint,
            ])
            .arg("--data-dir")
            .arg(dir.join("data"))
            .arg("--config")
            .arg(&config)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()?;
        let mut d = Self { child, port };
        for _ in 0..2400 {
            if let Some(status) = d.child.try_wait()? {
                bail!("shiftd exited while starting: {status}");
            }
            if let Ok((200, _)) = http(port, "GET", "/readyz", None).await {
                return Ok(d);
            }
            tokio::time::sleep(Duration::from_millis(25)).await;
        }
        d.child.kill()?;
        bail!("shiftd did not become ready")
    }

    async fn get(&self, path: &str) -> Result<(u16, Value)> {
        http(self.port, "GET", path, None).await
    }

    async fn post(&self, path: &str, body: &Value) -> Result<(u16, Value)> {
        http(self.port, "POST", path, Some(body)).await
    }

    /// SIGKILL: no shutdown, no flush beyond what was committed.
    fn kill9(mut self) -> Result<()> {
        self.child.kill()?;
        self.child.wait()?;
        Ok(())
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The robot: its own Zenoh session, a liveliness token, its corrections.
struct Robot {
    session: zenoh::Session,
    _token: zenoh::liveliness::LivelinessToken,
    corrections: zenoh::pubsub::Subscriber<zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>>,
}

impl Robot {
    async fn join(endpoint: &str) -> Result<Self> {
        let mut c = zenoh::Config::default();
        for (k, v) in [
            ("mode", "\"peer\"".to_owned()),
            ("listen/endpoints", "[]".to_owned()),
            ("connect/endpoints", format!("[\"{endpoint}\"]")),
            ("scouting/multicast/enabled", "false".to_owned()),
            ("scouting/gossip/enabled", "false".to_owned()),
        ] {
            c.insert_json5(k, &v).map_err(|e| anyhow!("{k}: {e}"))?;
        }
        let session = zenoh::open(c).await.map_err(|e| anyhow!("{e}"))?;
        let token = session
            .liveliness()
            .declare_token("shift/default/robots/r1/alive")
            .await
            .map_err(|e| anyhow!("{e}"))?;
        let corrections = session
            .declare_subscriber("shift/default/robots/r1/corrections")
            .await
            .map_err(|e| anyhow!("{e}"))?;
        Ok(Self {
            session,
            _token: token,
            corrections,
        })
    }

    async fn odom(&self, x: f64, y: f64, yaw: f64, ns: i64) -> Result<()> {
        let mut o = Odometry {
            header: Header {
                stamp: Time::from_ns(ns),
                frame_id: "map".into(),
            },
            child_frame_id: "base_link".into(),
            ..Odometry::default()
        };
        o.pose.pose.position.x = x;
        o.pose.pose.position.y = y;
        o.pose.pose.orientation.z = (yaw / 2.0).sin();
        o.pose.pose.orientation.w = (yaw / 2.0).cos();
        self.session
            .put("shift/default/robots/r1/odom", encode_odometry(&o))
            .encoding(Encoding::APPLICATION_CDR)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    /// A 0.2 m post of map-frame points at (x, y).
    async fn post_at(&self, x: f64, y: f64, ns: i64) -> Result<()> {
        let pts = path::post(x, y);
        let header = Header {
            stamp: Time::from_ns(ns),
            frame_id: "map".into(),
        };
        self.session
            .put("shift/default/robots/r1/cloud", encode_point_cloud2_xyz(&header, &pts))
            .encoding(Encoding::APPLICATION_CDR)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    async fn next_correction(&self) -> Result<CorrectionDoc> {
        let sample = tokio::time::timeout(LONG, self.corrections.recv_async())
            .await
            .context("no correction arrived")?
            .map_err(|e| anyhow!("{e}"))?;
        Ok(serde_json::from_slice(&sample.payload().to_bytes())?)
    }
}

/// The first straight stretch at least `min_m` long whose start lies `from_m` metres or more along the path,
/// as `(x, y, heading)` at its start and the unit direction.
fn stretch_after(w: &[WaypointDoc], from_m: f64, min_m: f64) -> Option<(f64, f64, f64)> {
    let mut s = 0.0;
    for i in 1..w.len() {
        s += (w[i].x - w[i - 1].x).hypot(w[i].y - w[i - 1].y);
        if s < from_m {
            continue;
        }
        let (dx, dy) = (w[i].x - w[i - 1].x, w[i].y - w[i - 1].y);
        let heading = dy.atan2(dx);
        let mut j = i;
        while j + 1 < w.len() {
            let (ex, ey) = (w[j + 1].x - w[j].x, w[j + 1].y - w[j].y);
            if (ey.atan2(ex) - heading).abs() > 1e-6 {
                break;
            }
            j += 1;
        }
        if (w[j].x - w[i - 1].x).hypot(w[j].y - w[i - 1].y) >= min_m {
            return Some((w[i - 1].x, w[i - 1].y, heading));
        }
    }
    None
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_kill_9_progress_is_recovered_and_corrections_continue_from_the_committed_version() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (port, zport) = (free_port()?, free_port()?);
    let endpoint = format!("tcp/127.0.0.1:{zport}");
    let daemon = Daemon::start(dir.path(), port, &endpoint).await?;
    let robot = Robot::join(&endpoint).await?;
    let req = json!({"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}});
    let (code, acc) = daemon.post("/v1/plans", &req).await?;
    assert_eq!(code, 202, "{acc}");
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    for _ in 0..2400 {
        let (_, st) = daemon.get(&format!("/v1/plans/{id}")).await?;
        if st["status"] == "ready" {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let (code, st) = daemon
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": "r1"}))
        .await?;
    assert_eq!(code, 200, "{st}");
    let (_, doc) = daemon.get(&format!("/v1/plans/{id}/path")).await?;
    let doc: PlanDocument = serde_json::from_value(doc)?;
    let total: f64 = doc
        .waypoints
        .windows(2)
        .map(|p| (p[1].x - p[0].x).hypot(p[1].y - p[0].y))
        .sum();

    // Mid-plan: the robot at 30 % of its plan, an obstacle 1.5 m ahead, a correction.
    let (x, y, h) = stretch_after(&doc.waypoints, 0.3 * total, 2.5).context("a stretch after 30 %")?;
    let mut t = 10_000_000_000i64;
    for _ in 0..3 {
        robot.odom(x, y, h, t).await?;
        t += 50_000_000;
        tokio::time::sleep(Duration::from_millis(30)).await;
    }
    robot.post_at(x + 1.5 * h.cos(), y + 1.5 * h.sin(), t).await?;
    let first = robot.next_correction().await?;
    assert_eq!(first.base_version, 1);
    // Let the daemon settle, then read what it committed.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let (_, before) = daemon.get(&format!("/v1/plans/{id}")).await?;
    let committed = before["version"].as_u64().context("version")?;
    assert!(committed >= 2, "{before}");
    daemon.kill9()?;

    // Restart on the same data dir; the robot (re)joins and keeps publishing, further along.
    let daemon = Daemon::start(dir.path(), port, &endpoint).await?;
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    let robot = Robot::join(&endpoint).await?;
    let (_, after) = daemon.get(&format!("/v1/plans/{id}")).await?;
    assert_eq!(after["status"], "active", "{after}");
    assert_eq!(after["version"].as_u64(), Some(committed), "{after}");
    let (_, current) = daemon.get(&format!("/v1/plans/{id}/path")).await?;
    let current: PlanDocument = serde_json::from_value(current)?;
    assert_eq!(current.version, committed);
    let (x, y, h) = stretch_after(&current.waypoints, 0.6 * total, 2.5).context("a stretch after 60 %")?;
    for _ in 0..3 {
        robot.odom(x, y, h, t).await?;
        t += 50_000_000;
        tokio::time::sleep(Duration::from_millis(30)).await;
    }
    let mut recovered = Value::Null;
    for _ in 0..400 {
        let (_, st) = daemon.get(&format!("/v1/plans/{id}")).await?;
        if st["driven_fraction"].as_f64().unwrap_or(0.0) >= 0.55 {
            recovered = st;
            break;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    assert!(
        !recovered.is_null(),
        "progress recovered from the first odometry after the restart"
    );
    let (_, r) = daemon.get("/v1/robots/r1").await?;
    assert_eq!(r["plan_id"].as_str(), Some(id.as_str()), "{r}");
    assert_eq!(r["site"], "demo", "{r}");
    robot.post_at(x + 1.5 * h.cos(), y + 1.5 * h.sin(), t).await?;
    let c = robot.next_correction().await?;
    assert_eq!(c.plan_id, id);
    assert_eq!(c.base_version, committed, "based on the last committed version");
    assert_eq!(c.version, committed + 1);
    c.apply(&current).map_err(|e| anyhow!("{e}"))?;
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    drop(daemon);
    Ok(())
}
