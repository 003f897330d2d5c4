//! `shiftd replay`: a recording (see [`crate::record`]) played back.
//!
//! - Onto Zenoh ([`onto_zenoh`]): every ingested message is put back on the key it came in on, and liveliness
//!   tokens are declared and undeclared, with the original spacing divided by `--speed`, so a robot's session
//!   can be reproduced against a running daemon. A ROS 2 bag (rosbag2's MCAP storage: topics such as
//!   `/robot1/scan` with `ros2msg` schemas and CDR messages) replays too: each topic is mapped to the key the
//!   configured `[zenoh] mapping` reads ([`KeyMap`]: leading slash dropped, namespace kept for
//!   zenoh-bridge-ros2dds; `[ns/]{robot}/{odom|points|scan}` re-keyed for native and rmw_zenoh fleets).
//! - Into the engine ([`into_engine`], `--into-engine`): the recorded engine inputs, in their handling order,
//!   through a fresh `Engine` built with the recorded sizes and fed the recorded clock; one JSON line per
//!   decision. With `--check` each input's decisions are compared with the recorded ones, and any difference
//!   (or a gap: a message the recorder had to drop) is a mismatch. Deterministic: for tests and incidents.

use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::bail;
use crate::err;
use crate::error::{Context, Result};
use serde_json::Value;
use shift_engine::recorded::{Decision, RecordedDecisions, RecordedEngineConfig, RecordedInput, decisions_of};
use shift_engine::{Engine, EngineConfig};
use shift_proto::keys::{KeySpace, Ros2Mapping, Stream};
use zenoh::bytes::Encoding;

use crate::record::channels::Kind;
use crate::record::writer::recordings_in;

/// A message to put back on Zenoh.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// A payload on its key.
    Put {
        /// The key it came in on.
        key: String,
        /// Its channel kind (tells the encoding).
        kind: Kind,
        /// The payload.
        bytes: Vec<u8>,
    },
    /// A liveliness token appeared (`alive`) or went.
    Token {
        /// The token's key.
        key: String,
        /// Declared or undeclared.
        alive: bool,
    },
}

/// A recording read into memory.
#[derive(Debug, Default)]
pub struct Recorded {
    /// Engine inputs by (run, seq).
    pub inputs: BTreeMap<(u64, u64), RecordedInput>,
    /// Recorded decisions by (run, seq).
    pub decisions: BTreeMap<(u64, u64), RecordedDecisions>,
    /// Engine sizes by run.
    pub configs: BTreeMap<u64, RecordedEngineConfig>,
    /// What robots sent, in log-time order: (log time ns, action).
    pub ingest: Vec<(u64, Action)>,
    /// Messages of our channels that did not parse.
    pub unreadable: usize,
    /// Messages per topic.
    pub topics: BTreeMap<String, usize>,
}

/// Files given on the command line: folders expand to their `*.mcap` in name order.
pub fn expand(paths: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            files.extend(recordings_in(p)?);
        } else {
            files.push(p.clone());
        }
    }
    if files.is_empty() {
        bail!("no MCAP files in {paths:?}");
    }
    Ok(files)
}

impl Recorded {
    /// Reads files (in order). A truncated file (a crash's `.part`) is read up to its last good record.
    pub fn read(files: &[PathBuf]) -> Result<Self> {
        let mut rec = Self::default();
        for f in files {
            rec.read_one(f)?;
        }
        rec.ingest.sort_by_key(|(t, _)| *t);
        Ok(rec)
    }

    fn read_one(&mut self, path: &Path) -> Result<()> {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let stream = mcap::MessageStream::new(&bytes).with_context(|| format!("{} is not MCAP", path.display()))?;
        for m in stream {
            let m = match m {
                Ok(m) => m,
                Err(e) => {
                    tracing::warn!(file = %path.display(), "recording ends early: {e}");
                    break;
                }
            };
            let topic = m.channel.topic.as_str();
            *self.topics.entry(topic.to_owned()).or_default() += 1;
            let Some(kind) = m.channel.schema.as_ref().and_then(|s| Kind::from_schema_name(&s.name)) else {
                continue;
            };
            let data: &[u8] = &m.data;
            let ok = match kind {
                k if k.is_ingest() => {
                    self.ingest.push((
                        m.log_time,
                        Action::Put {
                            key: topic.to_owned(),
                            kind: k,
                            bytes: data.to_vec(),
                        },
                    ));
                    true
                }
                Kind::Liveliness => match serde_json::from_slice::<Value>(data) {
                    Ok(v) => match (v["key"].as_str(), v["alive"].as_bool()) {
                        (Some(key), Some(alive)) => {
                            self.ingest.push((
                                m.log_time,
                                Action::Token {
                                    key: key.to_owned(),
                                    alive,
                                },
                            ));
                            true
                        }
                        _ => false,
                    },
                    Err(_) => false,
                },
                Kind::EngineInput => match serde_json::from_slice::<RecordedInput>(data) {
                    Ok(i) => {
                        self.inputs.insert((i.run, i.seq), i);
                        true
                    }
                    Err(e) => {
                        tracing::warn!("unreadable engine input: {e}");
                        false
                    }
                },
                Kind::EngineDecisions => match serde_json::from_slice::<RecordedDecisions>(data) {
                    Ok(d) => {
                        self.decisions.insert((d.run, d.seq), d);
                        true
                    }
                    Err(e) => {
                        tracing::warn!("unreadable engine decisions: {e}");
                        false
                    }
                },
                Kind::EngineConfig => match serde_json::from_slice::<RecordedEngineConfig>(data) {
                    Ok(c) => {
                        self.configs.insert(c.run, c);
                        true
                    }
                    Err(_) => false,
                },
                _ => true,
            };
            if !ok {
                self.unreadable += 1;
            }
        }
        Ok(())
    }
}

/// What a replay into the engine found.
#[derive(Debug, Default)]
pub struct EngineReplay {
    /// Inputs fed.
    pub inputs: usize,
    /// Decisions printed.
    pub decisions: usize,
    /// Differences from the recorded decisions (only with `check`), the first ones in full.
    pub mismatches: Vec<String>,
}

const MAX_REPORTED: usize = 20;

/// One line of `--into-engine` output.
#[derive(serde::Serialize)]
struct DecisionLine<'a> {
    run: u64,
    seq: u64,
    now_ms: u64,
    decision: &'a Decision,
}

/// Feeds the recorded inputs through a fresh engine per daemon run and writes one JSON line per decision to
/// `out`: `{"run", "seq", "now_ms", "decision"}`. With `check`, compares with the recorded decisions.
pub fn into_engine(rec: &Recorded, out: &mut dyn Write, check: bool) -> Result<EngineReplay> {
    if check && rec.inputs.is_empty() {
        bail!(
            "no recorded engine inputs ({} messages on {} topics): --into-engine --check needs a recording made by \
             `shiftd serve --record`; a ROS 2 bag or an ingest-only file can only be replayed onto Zenoh",
            rec.topics.values().sum::<usize>(),
            rec.topics.len()
        );
    }
    fn mismatch(report: &mut EngineReplay, m: String) {
        if report.mismatches.len() < MAX_REPORTED {
            report.mismatches.push(m);
        } else if report.mismatches.len() == MAX_REPORTED {
            report.mismatches.push("…".into());
        }
    }
    let mut report = EngineReplay::default();
    let mut engine: Option<(u64, Engine, u64)> = None;
    for (&(run, seq), input) in &rec.inputs {
        if engine.as_ref().is_none_or(|(r, _, _)| *r != run) {
            let config = rec.configs.get(&run).map_or_else(
                || {
                    tracing::warn!(run, "no engine config recorded for this run: defaults");
                    EngineConfig::default()
                },
                RecordedEngineConfig::engine_config,
            );
            engine = Some((run, Engine::new(config), 0));
        }
        let Some((_, eng, last_seq)) = engine.as_mut() else {
            continue;
        };
        if check && seq != *last_seq + 1 {
            mismatch(
                &mut report,
                format!(
                    "run {run}: inputs {}..{seq} are missing (dropped while recording)",
                    *last_seq + 1
                ),
            );
        }
        *last_seq = seq;
        report.inputs += 1;
        let decisions = decisions_of(&eng.handle(input.event.clone(), input.now_ms));
        for decision in &decisions {
            let line = DecisionLine {
                run,
                seq,
                now_ms: input.now_ms,
                decision,
            };
            writeln!(out, "{}", serde_json::to_string(&line)?)?;
            report.decisions += 1;
        }
        if check {
            // A recording of an older format is compared with what that format could hold.
            let format = rec.configs.get(&run).map_or(1, |c| c.format);
            let got: Vec<Decision> = decisions.iter().filter_map(|d| d.as_format(format)).collect();
            let got = serde_json::to_value(&got)?;
            match rec.decisions.get(&(run, seq)) {
                None => mismatch(&mut report, format!("run {run} seq {seq}: no recorded decisions")),
                Some(r) => {
                    let want = serde_json::to_value(&r.decisions)?;
                    if got != want {
                        mismatch(
                            &mut report,
                            format!("run {run} seq {seq}: replayed {got} but recorded {want}"),
                        );
                    }
                }
            }
        }
    }
    if check {
        for &(run, seq) in rec.decisions.keys() {
            if !rec.inputs.contains_key(&(run, seq)) {
                mismatch(
                    &mut report,
                    format!("run {run} seq {seq}: decisions recorded without their input"),
                );
            }
        }
    }
    Ok(report)
}

/// Where recorded topics go on Zenoh.
#[derive(Debug, Clone)]
pub struct KeyMap {
    keys: KeySpace,
    mapping: Ros2Mapping,
}

impl KeyMap {
    /// Topics mapped for a fleet with these keys and this mapping.
    pub fn new(keys: KeySpace, mapping: Ros2Mapping) -> Self {
        Self { keys, mapping }
    }

    /// The key a recorded `topic` of `kind` is put on: SHIFT recordings keep the Zenoh key as the topic; a ROS 2
    /// topic (`/…`) loses its leading slash and, unless the fleet reads zenoh-bridge-ros2dds keys (which are
    /// exactly that), is re-keyed from its `{robot}/{odom|points|scan}` tail. `None` for a ROS topic of no
    /// robot stream.
    pub fn key_for(&self, topic: &str, kind: Kind) -> Option<String> {
        let Some(ros_topic) = topic.strip_prefix('/') else {
            return Some(topic.to_owned());
        };
        if matches!(self.mapping, Ros2Mapping::BridgeRos2dds { .. }) {
            return Some(ros_topic.to_owned());
        }
        let mut parts = ros_topic.rsplitn(3, '/');
        let (_leaf, robot) = (parts.next()?, parts.next()?);
        let stream = match kind {
            Kind::Odometry | Kind::OdomJson => Stream::Odom,
            Kind::PointCloud2 => Stream::Cloud,
            Kind::LaserScan => Stream::Scan,
            _ => return None,
        };
        self.mapping.robot_key(&self.keys, robot, stream).ok().flatten()
    }
}

/// Puts the recorded ingest messages back on Zenoh with their original spacing divided by `speed`,
/// declaring and undeclaring liveliness tokens as they were. Returns the number of actions carried out.
pub async fn onto_zenoh(rec: &Recorded, session: &zenoh::Session, keys: &KeyMap, speed: f64) -> Result<usize> {
    if !(speed.is_finite() && speed > 0.0) {
        bail!("--speed must be a positive number, got {speed}");
    }
    let z = |e: zenoh::Error| err!("zenoh: {e}");
    let Some(&(t0, _)) = rec.ingest.first() else {
        return Ok(0);
    };
    let start = tokio::time::Instant::now();
    let mut tokens = HashMap::new();
    let mut done = 0;
    for (t, action) in &rec.ingest {
        let offset = Duration::from_secs_f64(t.saturating_sub(t0) as f64 * 1e-9 / speed);
        tokio::time::sleep_until(start + offset).await;
        match action {
            Action::Put { key, kind, bytes } => {
                let encoding = if kind.is_ros() {
                    Encoding::APPLICATION_CDR
                } else {
                    Encoding::APPLICATION_JSON
                };
                let Some(key) = keys.key_for(key, *kind) else {
                    tracing::warn!(topic = key, "no key for this topic in the configured mapping: skipped");
                    continue;
                };
                session.put(&key, bytes.clone()).encoding(encoding).await.map_err(z)?;
            }
            Action::Token { key, alive: true } => {
                let token = session.liveliness().declare_token(key).await.map_err(z)?;
                tokens.insert(key.clone(), token);
            }
            Action::Token { key, alive: false } => {
                if let Some(token) = tokens.remove(key) {
                    token.undeclare().await.map_err(z)?;
                }
            }
        }
        done += 1;
    }
    Ok(done)
}

/// `shiftd replay FILE… [--speed X] [--into-engine [--check]]`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// MCAP files, or folders of them (their `*.mcap` in name order: a rotated recording).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Playback speed onto Zenoh: 2 = twice as fast as recorded.
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Feed the recorded engine inputs straight through an engine and print its decisions (JSON lines).
    #[arg(long)]
    pub into_engine: bool,
    /// With --into-engine: compare with the recorded decisions; exit non-zero on a mismatch.
    #[arg(long, requires = "into_engine")]
    pub check: bool,
    /// TOML config whose [zenoh] section opens the session (see deploy/shiftd.toml).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Zenoh endpoint to connect to (repeatable); default: [zenoh] connect, else the daemon's [zenoh] listen.
    #[arg(long)]
    pub zenoh_connect: Vec<String>,
}

/// Runs the command.
pub fn run_cli(args: ReplayArgs) -> Result<()> {
    if !(args.speed.is_finite() && args.speed > 0.0) {
        bail!("--speed must be a positive number, got {}", args.speed);
    }
    let files = expand(&args.files)?;
    let rec = Recorded::read(&files)?;
    if args.into_engine {
        let stdout = std::io::stdout();
        let mut out = std::io::BufWriter::new(stdout.lock());
        let report = into_engine(&rec, &mut out, args.check)?;
        out.flush()?;
        eprintln!(
            "{} inputs, {} decisions{}",
            report.inputs,
            report.decisions,
            if args.check {
                format!(", {} mismatches", report.mismatches.len())
            } else {
                String::new()
            }
        );
        if !report.mismatches.is_empty() {
            for m in &report.mismatches {
                eprintln!("mismatch: {m}");
            }
            bail!("the replay diverged from the recording");
        }
        return Ok(());
    }
    let mut config = match &args.config {
        Some(p) => crate::Config::load(p)?.zenoh,
        None => crate::fleet::config::ZenohConfig::default(),
    };
    // A replayer only connects: to the given endpoints, else the configured ones, else the daemon's own.
    config.connect = if !args.zenoh_connect.is_empty() {
        args.zenoh_connect
    } else if !config.connect.is_empty() {
        config.connect
    } else {
        std::mem::take(&mut config.listen)
    };
    config.listen = Vec::new();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the tokio runtime")?;
    runtime.block_on(async move {
        let session = zenoh::open(config.to_zenoh()?)
            .await
            .map_err(|e| err!("opening the zenoh session: {e}"))?;
        // Give the session a moment to meet its peers before the first put.
        tokio::time::sleep(Duration::from_millis(500)).await;
        let keys = KeySpace::new(&config.prefix, &config.fleet).map_err(|e| err!("zenoh keys: {e}"))?;
        let map = KeyMap::new(keys, config.mapping.clone());
        let n = onto_zenoh(&rec, &session, &map, args.speed).await?;
        eprintln!("{n} messages and token changes replayed onto zenoh");
        session
            .close()
            .await
            .map_err(|e| err!("closing the zenoh session: {e}"))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ros2_topics_map_to_the_keys_the_fleet_reads() {
        let keys = || KeySpace::new("shift", "default").expect("keys");
        let native = KeyMap::new(keys(), Ros2Mapping::Native);
        assert_eq!(
            native.key_for("/robot1/scan", Kind::LaserScan).as_deref(),
            Some("shift/default/robots/robot1/scan")
        );
        assert_eq!(
            native.key_for("/fleet_a/robot1/points", Kind::PointCloud2).as_deref(),
            Some("shift/default/robots/robot1/cloud")
        );
        assert_eq!(
            native.key_for("/robot1/odom", Kind::PlanStatus),
            None,
            "not a robot stream"
        );
        // SHIFT's own recordings keep their Zenoh keys.
        assert_eq!(
            native
                .key_for("shift/default/robots/r1/odom", Kind::Odometry)
                .as_deref(),
            Some("shift/default/robots/r1/odom")
        );
        let bridge = KeyMap::new(keys(), Ros2Mapping::BridgeRos2dds { namespace: None });
        assert_eq!(
            bridge.key_for("/fleet_a/robot1/odom", Kind::Odometry).as_deref(),
            Some("fleet_a/robot1/odom"),
            "leading slash dropped, namespace kept"
        );
        let rmw = KeyMap::new(keys(), Ros2Mapping::RmwZenoh { domain: 0 });
        let key = rmw.key_for("/robot1/odom", Kind::Odometry).expect("a key");
        assert!(
            key.starts_with("0/robot1/odom/nav_msgs::msg::dds_::Odometry_/RIHS01_"),
            "{key}"
        );
    }
}
