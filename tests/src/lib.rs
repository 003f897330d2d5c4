//! # shift-tests
//!
//! End-to-end tests start `shiftd` in-process on 127.0.0.1:0 with a temporary data dir and drive it over
//! HTTP like a fleet backend would. This library holds the harness; the tests are in `tests/`.

pub mod bench;
pub mod field;
pub mod fleet;
pub mod path;
pub mod raw;
pub mod sse;

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use serde_json::Value;
use shiftd::Config;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;

/// A running server.
pub struct TestServer {
    /// `http://127.0.0.1:PORT`.
    pub base: String,
    /// HTTP client.
    pub http: reqwest::Client,
    /// The data dir (kept so a restart can reuse it).
    pub data_dir: PathBuf,
    stop: CancellationToken,
    task: JoinHandle<Result<()>>,
}

/// A config for tests: loopback, ephemeral port, given data dir, small pool and queue.
pub fn test_config(data_dir: &Path) -> Config {
    let mut c = Config::default();
    c.store.data_dir = data_dir.to_path_buf();
    c.jobs.workers = 1;
    c.jobs.queue_capacity = 8;
    c.jobs.shutdown_grace_s = 0;
    // In-process Zenoh only: parallel test servers must not fight over port 7447.
    c.zenoh.listen = Vec::new();
    c
}

impl TestServer {
    /// Starts shiftd with `config` on 127.0.0.1:0.
    pub async fn start(config: Config) -> Result<Self> {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
        let base = format!("http://{}", listener.local_addr()?);
        let data_dir = config.store.data_dir.clone();
        let stop = CancellationToken::new();
        let s = stop.clone();
        let task = tokio::spawn(async move {
            shiftd::run(config, listener, async move { s.cancelled().await })
                .await
                .map_err(anyhow::Error::from)
        });
        let http = reqwest::Client::builder().timeout(Duration::from_secs(60)).build()?;
        let server = Self {
            base,
            http,
            data_dir,
            stop,
            task,
        };
        // Ready once /readyz answers (parallel tests on a loaded 2-core machine can take seconds); a server
        // that stopped on its own reports why.
        for _ in 0..2400 {
            if server.task.is_finished() {
                let err = server.task.await.map_err(anyhow::Error::from).and_then(|r| r);
                bail!("shiftd stopped while starting: {err:?}");
            }
            if let Ok(r) = server.http.get(server.url("/readyz")).send().await
                && r.status().is_success()
            {
                return Ok(server);
            }
            tokio::time::sleep(Duration::from_millis(25)).await;
        }
        bail!("shiftd did not become ready within 60 s")
    }

    /// Full URL of a path.
    pub fn url(&self, path: &str) -> String {
        format!("{}{path}", self.base)
    }

    /// GET → (status, JSON body or Null).
    pub async fn get(&self, path: &str) -> Result<(u16, Value)> {
        let r = self.http.get(self.url(path)).send().await?;
        let status = r.status().as_u16();
        Ok((status, r.json().await.unwrap_or(Value::Null)))
    }

    /// POST JSON → (status, JSON body).
    pub async fn post(&self, path: &str, body: &Value) -> Result<(u16, Value)> {
        let r = self.http.post(self.url(path)).json(body).send().await?;
        let status = r.status().as_u16();
        Ok((status, r.json().await.unwrap_or(Value::Null)))
    }

    /// DELETE → (status, JSON body).
    pub async fn delete(&self, path: &str) -> Result<(u16, Value)> {
        let r = self.http.delete(self.url(path)).send().await?;
        let status = r.status().as_u16();
        Ok((status, r.json().await.unwrap_or(Value::Null)))
    }

    /// Polls `GET /v1/plans/{id}` until `done(status)` or the timeout; returns the last body.
    pub async fn wait_plan(&self, id: &str, timeout: Duration, done: impl Fn(&str) -> bool) -> Result<Value> {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            let (code, body) = self.get(&format!("/v1/plans/{id}")).await?;
            if code != 200 {
                bail!("GET plan {id}: {code} {body}");
            }
            let status = body["status"].as_str().context("status")?.to_owned();
            if done(&status) {
                return Ok(body);
            }
            if tokio::time::Instant::now() > deadline {
                bail!("plan {id} still {status} after {timeout:?}");
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }

    /// Stops the server gracefully and waits for it.
    pub async fn stop(self) -> Result<()> {
        self.stop.cancel();
        self.task.await?
    }
}

/// The design's example plan request on the demo site.
pub fn demo_request() -> Value {
    serde_json::json!({
        "site": "demo", "start": [0.5, 0.5],
        "robot": {"radius": 0.15, "tool_width": 0.3, "v_min": 0.1, "v_max": 1.0, "a_max": 0.5}
    })
}
