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

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::bail;
use crate::err;
use crate::error::{Context, Result};
use mcap::McapError;
use mcap::read::ChannelAccumulator;
use mcap::records::{Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use serde_json::Value;
use shift_engine::recorded::{Decision, RecordedDecisions, RecordedEngineConfig, RecordedInput, decisions_of};
use shift_engine::{Engine, EngineConfig};
use shift_proto::keys::{KeySpace, Ros2Mapping, Stream};
use zenoh::bytes::Encoding;

use crate::record::channels::Kind;
use crate::record::writer::recordings_in;

/// The longest record a recording is read with, unless the file is longer: far above any message the daemon
/// records (a map upload is at most `[http] max_body_bytes`, 64 MiB by default, twice that hex-encoded in its
/// engine input), far below the lengths only a corrupt file declares.
const MAX_RECORD_BYTES: usize = 256 << 20;

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
        self.read_bytes(&bytes, &path.display().to_string())
    }

    /// Reads one recording held in memory (an MCAP file's bytes; `name` names it in messages), as [`Self::read`]
    /// reads each file, except that the ingest is left in file order.
    pub fn read_bytes(&mut self, bytes: &[u8], name: &str) -> Result<()> {
        for m in Messages::new(bytes) {
            let m = match m {
                Ok(m) => m,
                Err(e) => {
                    tracing::warn!(file = name, "recording ends early: {e}");
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

/// The messages of an MCAP file held in memory, in file order, linked to their channels as `mcap::MessageStream`
/// links them, up to the first error. Unlike it, nothing is reserved at a length the file only declares (a record
/// in a zstd chunk declaring 2^62 bytes aborted `shiftd replay`, a string declaring 2 GiB had it reserved): reads
/// stop at the file's end, a record may not exceed [`MAX_RECORD_BYTES`] (or the file's length), and only
/// schemas, channels and messages are parsed, once their strings fit in their record. The summary after the data
/// end (which repeats schemas and channels) is not read.
struct Messages<'a> {
    reader: LinearReader,
    channels: ChannelAccumulator<'static>,
    rest: &'a [u8],
    done: bool,
}

impl<'a> Messages<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        let options = LinearReaderOptions::default().with_record_length_limit(bytes.len().max(MAX_RECORD_BYTES));
        Self {
            reader: LinearReader::new_with_options(options),
            channels: ChannelAccumulator::default(),
            rest: bytes,
            done: false,
        }
    }

    fn next_message(&mut self) -> Option<Result<mcap::Message<'static>>> {
        loop {
            let (opcode, body) = match self.reader.next_event()? {
                Ok(LinearReadEvent::ReadRequest(want)) => {
                    let n = want.min(self.rest.len());
                    self.reader.insert(n).copy_from_slice(&self.rest[..n]);
                    self.reader.notify_read(n);
                    self.rest = &self.rest[n..];
                    continue;
                }
                Ok(LinearReadEvent::Record { opcode, data }) => (opcode, data),
                Err(e) => return Some(Err(e.into())),
            };
            match opcode {
                op::SCHEMA | op::CHANNEL | op::MESSAGE => {}
                op::DATA_END => return None,
                _ => continue,
            }
            if !strings_fit(opcode, body) {
                return Some(Err(err!("record {opcode:#04x} holds a string longer than itself")));
            }
            let record = match mcap::parse_record(opcode, body) {
                Ok(record) => record,
                Err(e) => return Some(Err(e.into())),
            };
            let linked = match record {
                Record::Schema { header, data } => self.channels.add_schema(header, Cow::Owned(data.into_owned())),
                Record::Channel(channel) => self.channels.add_channel(channel),
                Record::Message { header, data } => {
                    return Some(match self.channels.get(header.channel_id) {
                        Some(channel) => Ok(mcap::Message {
                            channel,
                            sequence: header.sequence,
                            log_time: header.log_time,
                            publish_time: header.publish_time,
                            data: Cow::Owned(data.into_owned()),
                        }),
                        None => Err(McapError::UnknownChannel(header.sequence, header.channel_id).into()),
                    });
                }
                _ => Ok(()),
            };
            if let Err(e) = linked {
                return Some(Err(e.into()));
            }
        }
    }
}

impl Iterator for Messages<'_> {
    type Item = Result<mcap::Message<'static>>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let next = self.next_message();
        self.done = !matches!(next, Some(Ok(_)));
        next
    }
}

/// Whether every length-prefixed string of a schema (name, encoding) or channel (topic, encoding, metadata) record
/// fits in it: the MCAP parser reserves a string's declared length (up to 4 GiB) before reading it. A record too
/// short for a length is left to the parser to refuse.
fn strings_fit(opcode: u8, body: &[u8]) -> bool {
    let len_at = |at: usize| {
        body.get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    // The string at `at`: where the next field starts (the record's end when no length is left), or `None` when it
    // runs past the record.
    let skip = |at: usize| len_at(at).map_or(Some(body.len()), |n| (n <= body.len() - at - 4).then_some(at + 4 + n));
    let pair = |at: usize| skip(at).and_then(skip);
    match opcode {
        // id; name, encoding (the parser checks the data's length).
        op::SCHEMA => pair(2).is_some(),
        // id, schema id; topic, message encoding; the metadata's length in bytes, then its keys and values, read
        // in pairs while short of that length.
        op::CHANNEL => {
            let Some(mut at) = pair(4) else {
                return false;
            };
            let Some(map_len) = len_at(at) else {
                return true;
            };
            let end = (at + 4).saturating_add(map_len);
            at += 4;
            while at < end && at < body.len() {
                match pair(at) {
                    Some(next) => at = next,
                    None => return false,
                }
            }
            true
        }
        _ => true,
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
        let undone = rec
            .decisions
            .get(&(run, seq))
            .and_then(|r| match r.decisions.as_slice() {
                [Decision::Undone { error }] => Some(error.clone()),
                _ => None,
            });
        let decisions = match undone {
            // The live daemon handled it on a snapshot and put the snapshot back: so does the replay.
            Some(error) => {
                let snapshot = eng.clone();
                let _ = eng.handle(input.event.clone(), input.now_ms);
                *eng = snapshot;
                vec![Decision::Undone { error }]
            }
            None => decisions_of(&eng.handle(input.event.clone(), input.now_ms)),
        };
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

    /// An MCAP record: opcode, length, body.
    fn record(out: &mut Vec<u8>, opcode: u8, body: &[u8]) {
        out.push(opcode);
        out.extend((body.len() as u64).to_le_bytes());
        out.extend(body);
    }

    /// An MCAP string or byte array: u32 length, bytes.
    fn prefixed(out: &mut Vec<u8>, bytes: &[u8]) {
        out.extend((bytes.len() as u32).to_le_bytes());
        out.extend(bytes);
    }

    /// A recording of one liveliness token (header, schema, channel, message), then `tail`.
    fn token_then(tail: &[u8]) -> Vec<u8> {
        let mut file = b"\x89MCAP0\r\n".to_vec();
        record(&mut file, 0x01, &[0; 8]);
        let mut schema = 1u16.to_le_bytes().to_vec();
        for s in ["shift.Liveliness", "jsonschema", ""] {
            prefixed(&mut schema, s.as_bytes());
        }
        assert!(strings_fit(op::SCHEMA, &schema));
        record(&mut file, 0x03, &schema);
        let mut channel = [1u16.to_le_bytes(), 1u16.to_le_bytes()].concat();
        for s in ["/shift/liveliness", "json", ""] {
            prefixed(&mut channel, s.as_bytes());
        }
        assert!(strings_fit(op::CHANNEL, &channel));
        record(&mut file, 0x04, &channel);
        let mut message = 1u16.to_le_bytes().to_vec();
        message.extend([0; 20]);
        message.extend(br#"{"key": "shift/default/robots/r1/alive", "alive": true}"#);
        record(&mut file, 0x05, &message);
        file.extend(tail);
        file
    }

    /// Reads `file`, which must end early after its token.
    fn token_only(file: &[u8]) {
        let mut rec = Recorded::default();
        rec.read_bytes(file, "corrupt.mcap")
            .expect("read up to the corrupt record");
        let token = Action::Token {
            key: "shift/default/robots/r1/alive".into(),
            alive: true,
        };
        assert_eq!(rec.ingest, vec![(0, token)], "what came before it is kept");
    }

    /// Found by the `mcap_replay` fuzz target: `mcap::MessageStream` reserved a record's declared length before
    /// decompressing it, so a corrupt one in a zstd chunk (here 2^62 bytes) aborted `shiftd replay`.
    #[test]
    fn a_corrupt_record_length_in_a_compressed_chunk_ends_the_recording_not_the_process() {
        // A zstd frame of one raw block: the 9 bytes that start a message record of 2^62 bytes.
        let mut inner = vec![0x05];
        inner.extend((1u64 << 62).to_le_bytes());
        let mut zstd = vec![0x28, 0xb5, 0x2f, 0xfd, 0x00, 0x00];
        zstd.extend(&(1 | (inner.len() as u32) << 3).to_le_bytes()[..3]);
        zstd.extend(&inner);
        let mut chunk = [0, 0, inner.len() as u64].map(u64::to_le_bytes).concat();
        chunk.extend(0u32.to_le_bytes());
        prefixed(&mut chunk, b"zstd");
        chunk.extend((zstd.len() as u64).to_le_bytes());
        chunk.extend(&zstd);
        let mut tail = Vec::new();
        record(&mut tail, 0x06, &chunk);
        token_only(&token_then(&tail));
    }

    /// Found by the `mcap_replay` fuzz target: the MCAP parser reserves a string's declared length before reading
    /// it, so a schema or channel naming one of up to 4 GiB had the replay reserve that much.
    #[test]
    fn a_string_longer_than_its_record_ends_the_recording() {
        let mut schema = 2u16.to_le_bytes().to_vec();
        schema.extend(0x8000_0000u32.to_le_bytes());
        schema.extend(b"shift.Liveliness");
        let mut channel = [2u16.to_le_bytes(), 1u16.to_le_bytes()].concat();
        for s in ["/shift/liveliness", "json"] {
            prefixed(&mut channel, s.as_bytes());
        }
        // Metadata of 4 bytes: a key that fits it, then a value (read with its key) that does not fit the record.
        channel.extend(4u32.to_le_bytes());
        prefixed(&mut channel, b"");
        channel.extend(0x8000_0000u32.to_le_bytes());
        for (opcode, body) in [(op::SCHEMA, schema), (op::CHANNEL, channel)] {
            assert!(!strings_fit(opcode, &body), "{opcode}");
            let mut tail = Vec::new();
            record(&mut tail, opcode, &body);
            token_only(&token_then(&tail));
        }
    }

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
