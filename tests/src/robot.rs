//! A scripted robot on loopback Zenoh: sessions that connect to the server's endpoint (no scouting), ROS
//! messages to send, and polling until the server shows a change.

use std::time::Duration;

use anyhow::{Result, anyhow, bail};
use shift_proto::ros::odometry::Odometry;
use shift_proto::ros::{Header, Time};

/// How long a test waits for anything (plans compute on a loaded 2-core machine).
pub const LONG: Duration = Duration::from_secs(120);

/// A free TCP port on 127.0.0.1 (bound and released).
pub fn free_port() -> Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// A peer session that only connects to `endpoint` (`tcp/127.0.0.1:PORT`), scouting off.
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

/// Odometry at `(x, y)` facing +x, map frame.
pub fn odom(x: f64, y: f64, sec: i32) -> Odometry {
    let mut o = Odometry {
        header: header("map", sec),
        child_frame_id: "base_link".into(),
        ..Odometry::default()
    };
    o.pose.pose.position.x = x;
    o.pose.pose.position.y = y;
    o.pose.pose.orientation.w = 1.0;
    o
}

/// Calls `f` every 50 ms until it returns `Some`, for at most [`LONG`].
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

/// An obstacle cluster in the map frame: a 0.4 m × 0.4 m box at (4, 4), three layers 0.2-0.6 m high, points
/// cell-centred on the 0.05 m voxels (so none sits on a boundary), plus one floor point.
pub fn obstacle_points() -> Vec<[f32; 3]> {
    let mut pts = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            for k in 0..3 {
                pts.push([4.01 + i as f32 * 0.02, 4.01 + j as f32 * 0.02, 0.21 + k as f32 * 0.2]);
            }
        }
    }
    pts.push([4.0, 4.0, 0.0]);
    pts
}
