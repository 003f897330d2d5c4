//! The one typed configuration of `shiftd serve` (TOML, unknown keys refused). `deploy/shiftd.toml` documents
//! every key with its default and is parsed by a unit test, so the two cannot drift.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use crate::error::{Context, Result};
use crate::http::token::Secret;
use serde::Deserialize;

/// Everything `shiftd serve` can be told.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// HTTP API.
    pub http: HttpConfig,
    /// Persistence.
    pub store: StoreConfig,
    /// Plan jobs.
    pub jobs: JobsConfig,
    /// The bundled demo site.
    pub demo: DemoConfig,
    /// The fleet over Zenoh.
    pub zenoh: crate::fleet::config::ZenohConfig,
    /// Watching assigned plans and correcting them around new obstacles (IKD-SWOpt).
    pub watch: shift_engine::WatchParams,
    /// MCAP recording.
    pub record: crate::record::config::RecordConfig,
}

impl Config {
    /// The engine's sizes, routing and watching from this configuration.
    pub fn engine_config(&self) -> shift_engine::EngineConfig {
        shift_engine::EngineConfig {
            workers: self.jobs.effective_workers(),
            queue_capacity: self.jobs.queue_capacity,
            watch: self.watch,
            default_site: self.zenoh.default_site(),
            blind_after_ms: self.zenoh.robot_timeout_s.max(1).saturating_mul(1000),
            progress: shift_engine::ProgressParams::default(),
            retain_plans: match self.store.retain_plans {
                0 => usize::MAX,
                n => n,
            },
            coverage_commit_ms: self.store.coverage_commit_s.saturating_mul(1000),
        }
    }
}

/// `[http]`: the API's doors (DESIGN §8). What each limit answers is documented in `deploy/shiftd.toml`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HttpConfig {
    /// Listen address.
    pub bind: SocketAddr,
    /// Largest map upload body (`POST /v1/sites/{site}/map`), bytes; 413 above.
    pub max_body_bytes: usize,
    /// Largest body of every other route (plan requests, assignments), bytes; 413 above.
    pub max_request_bytes: usize,
    /// Per-request timeout, seconds, body reading included (event streams exempt); 408 after it.
    pub request_timeout_s: u64,
    /// A connection that has not sent a whole request head this many seconds after it opened (or after its
    /// previous response) is closed.
    pub header_read_timeout_s: u64,
    /// Open connections at most; more wait in the listen backlog until one closes.
    pub max_connections: usize,
    /// A connection whose peer takes no byte of a response (an event stream included) for this many
    /// seconds is closed.
    pub write_stall_s: u64,
    /// Seconds between keep-alive comments on an event stream (a reader that is gone is noticed at the next).
    pub sse_keep_alive_s: u64,
    /// `Retry-After` seconds of a 429 (the plan queue is full).
    pub retry_after_s: u64,
    /// Bearer token for mutating routes; empty = none (see also `auth_token_file` and `SHIFT_AUTH_TOKEN`).
    pub auth_token: Secret,
    /// A file holding the bearer token (one line); empty = none.
    pub auth_token_file: PathBuf,
}

impl Default for HttpConfig {
    fn default() -> Self {
        Self {
            bind: SocketAddr::from(([127, 0, 0, 1], 7878)),
            max_body_bytes: 64 << 20,
            max_request_bytes: 1 << 20,
            request_timeout_s: 30,
            header_read_timeout_s: 10,
            max_connections: 512,
            write_stall_s: 30,
            sse_keep_alive_s: 15,
            retry_after_s: 5,
            auth_token: Secret::default(),
            auth_token_file: PathBuf::new(),
        }
    }
}

impl HttpConfig {
    /// Checks the values that must not be zero.
    pub fn validate(&self) -> Result<()> {
        let nonzero = [
            ("max_body_bytes", self.max_body_bytes as u64),
            ("max_request_bytes", self.max_request_bytes as u64),
            ("request_timeout_s", self.request_timeout_s),
            ("header_read_timeout_s", self.header_read_timeout_s),
            ("max_connections", self.max_connections as u64),
            ("write_stall_s", self.write_stall_s),
            ("sse_keep_alive_s", self.sse_keep_alive_s),
            ("retry_after_s", self.retry_after_s),
        ];
        for (key, v) in nonzero {
            if v == 0 {
                return Err(crate::error::DaemonError::config(format!(
                    "[http] {key} must be at least 1"
                )));
            }
        }
        if self.max_connections > u32::MAX as usize >> 3 {
            return Err(crate::error::DaemonError::config("[http] max_connections is too large"));
        }
        Ok(())
    }
}

/// `[store]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StoreConfig {
    /// Folder of the redb database.
    pub data_dir: PathBuf,
    /// Settled plans kept (ready, done, failed, cancelled); the oldest beyond it are forgotten when a new plan
    /// is accepted. 0 keeps every plan.
    pub retain_plans: usize,
    /// The database's page cache, MiB (redb's own default is 1 GiB: a daemon that runs for months would
    /// grow to it as its file does). Reads beyond it go to the file (the OS page cache still helps).
    pub cache_mb: usize,
    /// Seconds between commits of the measured coverage rasters while robots sweep (they are committed when
    /// the daemon stops too): what a kill -9 can lose of what was swept.
    pub coverage_commit_s: u64,
}

impl StoreConfig {
    /// Checks the values that must not be zero.
    pub fn validate(&self) -> Result<()> {
        if self.cache_mb == 0 {
            return Err(crate::error::DaemonError::config("[store] cache_mb must be at least 1"));
        }
        if self.coverage_commit_s == 0 {
            return Err(crate::error::DaemonError::config(
                "[store] coverage_commit_s must be at least 1",
            ));
        }
        Ok(())
    }
}

impl Default for StoreConfig {
    fn default() -> Self {
        Self {
            data_dir: PathBuf::from("./shift-data"),
            retain_plans: 10_000,
            cache_mb: 64,
            coverage_commit_s: 10,
        }
    }
}

/// `[jobs]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct JobsConfig {
    /// Plans computed at once; 0 = one per core.
    pub workers: usize,
    /// Plans waiting for a worker before 429.
    pub queue_capacity: usize,
    /// Seconds running plans get to finish on shutdown.
    pub shutdown_grace_s: u64,
    /// Mark the site's live obstacle points occupied in a job's grid (where the static map is free).
    pub live_overlay: bool,
}

impl Default for JobsConfig {
    fn default() -> Self {
        Self {
            workers: 0,
            queue_capacity: 64,
            shutdown_grace_s: 10,
            live_overlay: true,
        }
    }
}

impl JobsConfig {
    /// Workers with 0 resolved to the number of cores.
    pub fn effective_workers(&self) -> usize {
        if self.workers > 0 {
            self.workers
        } else {
            std::thread::available_parallelism().map_or(2, usize::from)
        }
    }
}

/// `[demo]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DemoConfig {
    /// Load the bundled demo site when the store lacks it.
    pub enabled: bool,
    /// Its name.
    pub site: String,
}

impl Default for DemoConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            site: "demo".into(),
        }
    }
}

impl Config {
    /// Parses TOML text.
    pub fn parse(text: &str) -> Result<Self> {
        Ok(toml::from_str(text)?)
    }

    /// Reads and parses a file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        Self::parse(&text).with_context(|| format!("parsing {}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn documented_default_file_matches_the_embedded_defaults() {
        let text = include_str!("../../../deploy/shiftd.toml");
        let parsed = Config::parse(text).expect("deploy/shiftd.toml parses");
        assert_eq!(parsed, Config::default());
    }

    #[test]
    fn empty_config_is_the_default_and_typos_are_errors() {
        assert_eq!(Config::parse("").expect("empty is fine"), Config::default());
        let e = Config::parse("[http]\nbnd = \"127.0.0.1:1\"").expect_err("typo");
        assert!(format!("{e:#}").contains("bnd"), "{e:#}");
        assert!(Config::parse("[jobs]\nworkers = -1").is_err());
        let c = Config::parse("[jobs]\nworkers = 3\n[http]\nauth_token = \"tok-9f3q\"").expect("parses");
        assert_eq!(c.jobs.effective_workers(), 3);
        assert_eq!(c.http.auth_token, Secret::new("tok-9f3q"));
        assert!(!format!("{c:?}").contains("tok-9f3q"), "the token never prints");
        assert!(Config::parse("[http]\nmax_connections = 0").is_ok_and(|c| c.http.validate().is_err()));
        assert!(Config::parse("[store]\ncache_mb = 0").is_ok_and(|c| c.store.validate().is_err()));
        assert!(Config::default().store.validate().is_ok());
        let c = Config::parse("[zenoh]\nmapping = { kind = \"rmw_zenoh\", domain = 7 }").expect("rmw_zenoh");
        assert_eq!(c.zenoh.mapping, shift_proto::keys::Ros2Mapping::RmwZenoh { domain: 7 });
        let c = Config::parse("[zenoh.mapping]\nkind = \"bridge_ros2dds\"\nnamespace = \"site1\"").expect("bridge");
        assert_eq!(
            c.zenoh.mapping,
            shift_proto::keys::Ros2Mapping::BridgeRos2dds {
                namespace: Some("site1".into())
            }
        );
        assert!(Config::parse("[zenoh]\nmapping = { kind = \"ros1\" }").is_err());
        assert!(Config::parse("[zenoh]\nmapping = { kind = \"rmw_zenoh\", domian = 1 }").is_err());
    }
}
