//! Helpers of the Zenoh end-to-end tests: a loopback robot session, CDR message builders, polling.

use std::time::Duration;

use anyhow::{Result, anyhow, bail};
use shift_proto::ros::odometry::Odometry;
use shift_proto::ros::{Header, Time};

/// How long a poll waits before the test fails.
pub const LONG: Duration = Duration::from_secs(120);

/// A free TCP port on 127.0.0.1 (bound and released).
pub fn free_port() -> Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// A peer session connected to `endpoint` only (no listening, no scouting), like a robot on loopback.
pub async fn robot_session(endpoint: &str) -> Result<zenoh::Session> {
    let mut c = zenoh::Config::default();
    let set = |c: &mut zenoh::Config, k: &str, v: &str| c.insert_json5(k, v).map_err(|e| anyhow!("{k}: {e}"));
    set(&mut c, "mode", "\"peer\"")?;
    set(&mut c, "listen/endpoints", "[]")?;
    set(&mut c, "connect/endpoints", &format!("[\"{endpoint}\"]"))?;
    set(&mut c, "scouting/multicast/enabled", "false")?;
    set(&mut c, "scouting/gossip/enabled", "false")?;
    zenoh::open(c).await.map_err(|e| anyhow!("robot session: {e}"))
}

/// A header in `frame` stamped `sec` seconds.
pub fn header(frame: &str, sec: i32) -> Header {
    Header {
        stamp: Time { sec, nanosec: 0 },
        frame_id: frame.into(),
    }
}

/// A header in `frame` stamped `ns` nanoseconds.
pub fn header_ns(frame: &str, ns: i64) -> Header {
    Header {
        stamp: Time::from_ns(ns),
        frame_id: frame.into(),
    }
}

/// Odometry at (x, y) heading +x, stamped `sec` seconds, in the map frame.
pub fn odom(x: f64, y: f64, sec: i32) -> Odometry {
    odom_at(x, y, 0.0, header("map", sec))
}

/// Odometry at (x, y) with heading `yaw` (radians) and the given header.
pub fn odom_at(x: f64, y: f64, yaw: f64, header: Header) -> Odometry {
    let mut o = Odometry {
        header,
        child_frame_id: "base_link".into(),
        ..Odometry::default()
    };
    o.pose.pose.position.x = x;
    o.pose.pose.position.y = y;
    o.pose.pose.orientation.z = (yaw / 2.0).sin();
    o.pose.pose.orientation.w = (yaw / 2.0).cos();
    o
}

/// Points of a box of obstacle points: `n × n × layers` cell-centred on a 2 cm lattice from (x0, y0), layers
/// 0.2 m apart from z = 0.21 m — `(n / 2.5)² × layers` voxels of 5 cm when n is a multiple of 5.
pub fn obstacle_box(x0: f32, y0: f32, n: usize, layers: usize) -> Vec<[f32; 3]> {
    let mut pts = Vec::with_capacity(n * n * layers);
    for i in 0..n {
        for j in 0..n {
            for k in 0..layers {
                pts.push([
                    x0 + 0.01 + i as f32 * 0.02,
                    y0 + 0.01 + j as f32 * 0.02,
                    0.21 + k as f32 * 0.2,
                ]);
            }
        }
    }
    pts
}

/// Calls `f` every 50 ms until it gives a value or [`LONG`] passes.
pub async fn poll<T>(mut f: impl AsyncFnMut() -> Result<Option<T>>, what: &str) -> Result<T> {
    let deadline = tokio::time::Instant::now() + LONG;
    loop {
        if let Some(v) = f().await? {
            return Ok(v);
        }
        if tokio::time::Instant::now() > deadline {
            bail!("timed out waiting for {what}");
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}
