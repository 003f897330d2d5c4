//! Helpers of the daemon's process-level tests: a real `shiftd serve` child on loopback (so it can be killed),
//! a tiny HTTP/1.1 client, and a robot that is its own Zenoh participant.

// Each test binary uses its own part of these helpers.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use anyhow::{Context, Result, anyhow, bail};
use serde_json::Value;
use shift_proto::ros::odometry::{Odometry, encode_odometry};
use shift_proto::ros::point_cloud2::encode_point_cloud2_xyz;
use shift_proto::ros::{Header, Time};
use shift_proto::{CorrectionDoc, WaypointDoc};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use zenoh::bytes::Encoding;

/// A free TCP port on 127.0.0.1.
pub fn free_port() -> Result<u16> {
    Ok(std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port())
}

/// One HTTP/1.1 request with `Connection: close` → (status, JSON body or Null).
pub async fn http(port: u16, method: &str, path: &str, body: Option<&Value>) -> Result<(u16, Value)> {
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

/// `GET path` as text (`/metrics`).
pub async fn text(port: u16, path: &str) -> Result<String> {
    let mut s = tokio::net::TcpStream::connect(("127.0.0.1", port)).await?;
    let req = format!("GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
    s.write_all(req.as_bytes()).await?;
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).await?;
    let text = String::from_utf8_lossy(&raw);
    let (_, body) = text.split_once("\r\n\r\n").context("HTTP response")?;
    Ok(body.to_owned())
}

/// A `shiftd serve` process with its data under `dir/data`.
pub struct Daemon {
    child: Child,
    /// Its HTTP port.
    pub port: u16,
}

impl Daemon {
    /// Starts shiftd with the TOML `config` and waits until `/readyz` answers 200.
    pub async fn start(dir: &Path, port: u16, endpoint: &str, config: &str) -> Result<Self> {
        Self::start_wrapped(dir, &dir.join("data"), port, endpoint, config, &[]).await
    }

    /// Starts shiftd on `data_dir` as the last arguments of the command `wrapper` (empty: shiftd itself; e.g.
    /// `unshare … sh -c '… exec "$@"'` to give it a mount of its own), its config in `dir/shiftd.toml`.
    pub async fn start_wrapped(
        dir: &Path,
        data_dir: &Path,
        port: u16,
        endpoint: &str,
        config: &str,
        wrapper: &[String],
    ) -> Result<Self> {
        let config_path = dir.join("shiftd.toml");
        std::fs::write(&config_path, config)?;
        let shiftd = env!("CARGO_BIN_EXE_shiftd");
        let mut command = match wrapper.split_first() {
            Some((program, args)) => {
                let mut c = Command::new(program);
                c.args(args).arg(shiftd);
                c
            }
            None => Command::new(shiftd),
        };
        let child = command
            .args([
                "serve",
                "--bind",
                &format!("127.0.0.1:{port}"),
                "--zenoh-listen",
                endpoint,
            ])
            .arg("--data-dir")
            .arg(data_dir)
            .arg("--config")
            .arg(&config_path)
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

    /// `GET path`.
    pub async fn get(&self, path: &str) -> Result<(u16, Value)> {
        http(self.port, "GET", path, None).await
    }

    /// `POST path` with a JSON body.
    pub async fn post(&self, path: &str, body: &Value) -> Result<(u16, Value)> {
        http(self.port, "POST", path, Some(body)).await
    }

    /// The child's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// SIGKILL: no shutdown, no flush beyond what was committed.
    pub fn kill9(mut self) -> Result<()> {
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

/// A robot: its own Zenoh session (peer, connecting to the daemon's endpoint only), a liveliness token, and a
/// subscription to its corrections.
pub struct Robot {
    /// Its session.
    pub session: zenoh::Session,
    id: String,
    _token: zenoh::liveliness::LivelinessToken,
    corrections: zenoh::pubsub::Subscriber<zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>>,
}

impl Robot {
    /// Joins as robot `id` of the default fleet.
    pub async fn join(endpoint: &str, id: &str) -> Result<Self> {
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
            .declare_token(format!("shift/default/robots/{id}/alive"))
            .await
            .map_err(|e| anyhow!("{e}"))?;
        let corrections = session
            .declare_subscriber(format!("shift/default/robots/{id}/corrections"))
            .await
            .map_err(|e| anyhow!("{e}"))?;
        Ok(Self {
            session,
            id: id.to_owned(),
            _token: token,
            corrections,
        })
    }

    /// nav_msgs/Odometry in the map frame at stamp `ns`.
    pub async fn odom(&self, x: f64, y: f64, yaw: f64, ns: i64) -> Result<()> {
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
            .put(format!("shift/default/robots/{}/odom", self.id), encode_odometry(&o))
            .encoding(Encoding::APPLICATION_CDR)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    /// A PointCloud2 of map-frame points at stamp `ns`.
    pub async fn cloud(&self, points: &[[f32; 3]], ns: i64) -> Result<()> {
        let header = Header {
            stamp: Time::from_ns(ns),
            frame_id: "map".into(),
        };
        self.session
            .put(
                format!("shift/default/robots/{}/cloud", self.id),
                encode_point_cloud2_xyz(&header, points),
            )
            .encoding(Encoding::APPLICATION_CDR)
            .await
            .map_err(|e| anyhow!("{e}"))
    }

    /// The next correction, waiting at most `wait`.
    pub async fn next_correction(&self, wait: Duration) -> Result<CorrectionDoc> {
        let sample = tokio::time::timeout(wait, self.corrections.recv_async())
            .await
            .context("no correction arrived")?
            .map_err(|e| anyhow!("{e}"))?;
        Ok(serde_json::from_slice(&sample.payload().to_bytes())?)
    }

    /// Corrections already received, without waiting.
    pub fn drain_corrections(&self) -> Result<Vec<CorrectionDoc>> {
        let mut out = Vec::new();
        while let Ok(Some(sample)) = self.corrections.try_recv() {
            out.push(serde_json::from_slice(&sample.payload().to_bytes())?);
        }
        Ok(out)
    }

    /// Leaves the fleet (closes the session).
    pub async fn leave(self) -> Result<()> {
        self.session.close().await.map_err(|e| anyhow!("{e}"))
    }
}

/// The start of the first straight stretch at least `min_m` long beginning `from_m` metres or more along the
/// path: `(x, y, heading)`.
pub fn stretch_after(w: &[WaypointDoc], from_m: f64, min_m: f64) -> Option<(f64, f64, f64)> {
    let mut s = 0.0;
    for i in 1..w.len() {
        s += (w[i].x - w[i - 1].x).hypot(w[i].y - w[i - 1].y);
        if s < from_m {
            continue;
        }
        let heading = (w[i].y - w[i - 1].y).atan2(w[i].x - w[i - 1].x);
        let mut j = i;
        while j + 1 < w.len() && ((w[j + 1].y - w[j].y).atan2(w[j + 1].x - w[j].x) - heading).abs() <= 1e-6 {
            j += 1;
        }
        if (w[j].x - w[i - 1].x).hypot(w[j].y - w[i - 1].y) >= min_m {
            return Some((w[i - 1].x, w[i - 1].y, heading));
        }
    }
    None
}

/// A free `side` × `side` JSON grid at 5 cm with 40 pillars placed by `seed` (different bytes per site).
pub fn pillar_grid(side: usize, seed: usize) -> Value {
    let mut cells = vec![0u8; side * side];
    for k in 0..40 {
        let (x, y) = (
            (seed * 7 + k * 13) % (side - 4) + 2,
            (seed * 11 + k * 29) % (side - 4) + 2,
        );
        cells[y * side + x] = 100;
    }
    serde_json::json!({"resolution": 0.05, "origin": [0.0, 0.0], "width": side, "height": side, "cells": cells})
}

/// A seeded xorshift generator of uniform draws in [0, 1), for test scenes and traffic.
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed.max(1);
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}
