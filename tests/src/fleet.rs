//! Helpers of the Zenoh end-to-end tests: a loopback robot session, CDR message builders, polling.

use std::time::Duration;

use anyhow::{Context, Result, anyhow, bail};
use serde_json::{Value, json};
use shift_proto::ros::odometry::Odometry;
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_proto::ros::{Header, Time};
use shift_proto::{CorrectionDoc, PlanDocument};
use zenoh::bytes::Encoding;

use crate::TestServer;

/// How long a poll waits before the test fails.
pub const LONG: Duration = Duration::from_secs(120);

/// A free TCP port on 127.0.0.1 (bound and released).
pub fn free_port() -> Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// A test config whose Zenoh listens on a free loopback port, with no default site (robots feed the site of
/// their assignment only) and no demo site; returns it with the endpoint robots connect to.
pub fn fleet_config(data_dir: &std::path::Path) -> Result<(shiftd::Config, String)> {
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut config = crate::test_config(data_dir);
    config.zenoh.listen = vec![endpoint.clone()];
    config.zenoh.site = String::new();
    config.demo.enabled = false;
    Ok((config, endpoint))
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

/// Waits until the daemon's API sees robot `name` alive.
pub async fn wait_robot_alive(server: &TestServer, name: &str) -> Result<()> {
    let path = format!("/v1/robots/{name}");
    poll(
        async || {
            let (code, r) = server.get(&path).await?;
            Ok((code == 200 && r["alive"] == true).then_some(()))
        },
        &format!("robot {name} alive"),
    )
    .await
}

/// A JSON grid map (DESIGN §5.3) of `w × h` cells of `res` metres from the origin, free inside a one-cell wall
/// ring, with the rectangles `(x0, y0, x1, y1)` (metres) occupied.
pub fn room_grid(w: usize, h: usize, res: f64, blocked: &[(f64, f64, f64, f64)]) -> Value {
    let mut cells = vec![0i32; w * h];
    for r in 0..h {
        for c in 0..w {
            let (x, y) = ((c as f64 + 0.5) * res, (r as f64 + 0.5) * res);
            let wall = r == 0 || c == 0 || r + 1 == h || c + 1 == w;
            let inside = blocked
                .iter()
                .any(|&(x0, y0, x1, y1)| x >= x0 && x <= x1 && y >= y0 && y <= y1);
            if wall || inside {
                cells[r * w + c] = 100;
            }
        }
    }
    json!({"resolution": res, "origin": [0.0, 0.0], "width": w, "height": h, "cells": cells})
}

/// A scripted robot: a Zenoh session with a liveliness token and a subscription to its corrections.
pub struct ScriptedRobot {
    /// Its session.
    pub session: zenoh::Session,
    _token: zenoh::liveliness::LivelinessToken,
    /// Corrections sent to it.
    pub corrections: zenoh::pubsub::Subscriber<zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>>,
}

impl ScriptedRobot {
    /// Connects to `endpoint`, announces itself as `name` and subscribes to its corrections.
    pub async fn join(endpoint: &str, name: &str) -> Result<Self> {
        let session = robot_session(endpoint).await?;
        let token = session
            .liveliness()
            .declare_token(format!("shift/default/robots/{name}/alive"))
            .await
            .map_err(|e| anyhow!("{e}"))?;
        let corrections = session
            .declare_subscriber(format!("shift/default/robots/{name}/corrections"))
            .await
            .map_err(|e| anyhow!("{e}"))?;
        Ok(Self {
            session,
            _token: token,
            corrections,
        })
    }

    /// Publishes JSON odometry (map frame).
    pub async fn odom(&self, name: &str, x: f64, y: f64, yaw: f64) -> Result<()> {
        let body = json!({"x": x, "y": y, "yaw": yaw, "vx": 0.3, "vy": 0.0, "wz": 0.0, "stamp": 1.0});
        self.session
            .put(format!("shift/default/robots/{name}/odom"), serde_json::to_vec(&body)?)
            .encoding(Encoding::APPLICATION_JSON)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    /// Publishes JSON odometry (map frame) stamped `stamp_s` seconds on the robot's clock.
    pub async fn odom_stamped(&self, name: &str, x: f64, y: f64, yaw: f64, stamp_s: f64) -> Result<()> {
        let body = json!({"x": x, "y": y, "yaw": yaw, "vx": 0.3, "vy": 0.0, "wz": 0.0, "stamp": stamp_s});
        self.session
            .put(format!("shift/default/robots/{name}/odom"), serde_json::to_vec(&body)?)
            .encoding(Encoding::APPLICATION_JSON)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    /// Publishes a PointCloud2 (CDR) of map-frame points.
    pub async fn cloud(&self, name: &str, pts: &[[f32; 3]]) -> Result<()> {
        self.cloud_in(name, "map", Time { sec: 2, nanosec: 0 }, pts).await
    }

    /// Publishes a PointCloud2 (CDR) of points in `frame` stamped `stamp` (a robot-frame cloud is placed by the
    /// odometry at its stamp).
    pub async fn cloud_in(&self, name: &str, frame: &str, stamp: Time, pts: &[[f32; 3]]) -> Result<()> {
        let header = Header {
            stamp,
            frame_id: frame.into(),
        };
        self.session
            .put(
                format!("shift/default/robots/{name}/cloud"),
                encode_point_cloud2_xyz(&header, pts),
            )
            .encoding(Encoding::APPLICATION_CDR)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    /// Waits up to `timeout` for the next correction.
    pub async fn next_correction(&self, timeout: Duration) -> Result<CorrectionDoc> {
        let sample = tokio::time::timeout(timeout, self.corrections.recv_async())
            .await
            .context("no correction arrived")?
            .map_err(|e| anyhow!("{e}"))?;
        Ok(serde_json::from_slice(&sample.payload().to_bytes())?)
    }

    /// Fetches its current plan from the daemon's queryable (what a robot that reconnects does).
    pub async fn query_plan(&self, name: &str, timeout: Duration) -> Result<PlanDocument> {
        let replies = self
            .session
            .get(format!("shift/default/robots/{name}/plan"))
            .await
            .map_err(|e| anyhow!("{e}"))?;
        let reply = tokio::time::timeout(timeout, replies.recv_async())
            .await?
            .map_err(|e| anyhow!("{e}"))?;
        let sample = reply.result().map_err(|e| anyhow!("query error {e:?}"))?;
        Ok(serde_json::from_slice(&sample.payload().to_bytes())?)
    }
}
