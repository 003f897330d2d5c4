//! MCAP recording (`shiftd serve --record DIR`, `[record]`): every message robots put on the ingest keys (ROS
//! channels in `ros2msg`/`cdr` with type hashes, JSON odometry in `json`), liveliness changes, every event the
//! engine handled with its clock and what it decided, plan documents and status changes, and each site's
//! occupancy as a `foxglove.Grid` at intervals. zstd chunks, files rotated by size and time and finished on
//! rotation and shutdown (see [`writer`]).
//!
//! Nothing here blocks a producer: the engine thread and the Zenoh tasks hand messages to one named writer
//! thread (`recorder`) through a bounded channel with `try_send`; when it is full — or, for ingested payloads,
//! when more than `queue_bytes` wait — the message is dropped and counted (`shift_record_dropped_total`).
//! Engine inputs are cloned (cheap: documents and grids are shared) and serialised on the writer thread.
//!
//! Hooks: [`Recorder::engine_input`] / [`Recorder::engine_output`] around `Engine::handle` in the engine loop
//! (`engine_loop/mod.rs`); [`Recording::start`] and
//! [`Recording::finish`] in `server.rs`. Ingested messages are tapped by subscribers of their own ([`tap`]), so
//! the fleet bridge needs no change to be recorded.

pub mod channels;
pub mod config;
pub mod grid;
pub mod schemas;
pub mod tap;
pub mod writer;

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use crate::error::{Context, Result};
use shift_engine::recorded::{Decision, RecordedDecisions, RecordedEngineConfig, RecordedInput};
use shift_engine::{Command, CoverageKey, CoverageRecord, EngineConfig, EngineError, Event, LiveMaps};
use shift_planner::map::grid::OccupancyGrid;
use shift_proto::keys::KeySpace;
use shift_proto::{PlanDocument, PlanEvent, PlanStatusResponse};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;

use self::channels::Kind;
use self::writer::{FileSettings, RotatingWriter};
use crate::clock::SharedClock;

/// How often the writer thread wakes when idle (time rotation, grids), and how often it cuts a chunk so a
/// crash loses at most this much.
const TICK: Duration = Duration::from_millis(500);
const FLUSH_EVERY: Duration = Duration::from_secs(5);

/// Wall clock, nanoseconds since the Unix epoch (MCAP log time).
fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64)
}

/// A message for the writer thread.
enum Entry {
    /// A payload a robot put on Zenoh (its bytes count against `queue_bytes`).
    Ingest {
        kind: Kind,
        key: String,
        log_ns: u64,
        bytes: Vec<u8>,
    },
    /// A liveliness token appeared or went.
    Liveliness { key: String, alive: bool, log_ns: u64 },
    /// An event the engine is about to handle.
    Input {
        seq: u64,
        now_ms: u64,
        log_ns: u64,
        event: Box<Event>,
    },
    /// What it decided, plus the documents and statuses among its commands.
    Output {
        seq: u64,
        now_ms: u64,
        log_ns: u64,
        decisions: Vec<Decision>,
        docs: Vec<Arc<PlanDocument>>,
        statuses: Vec<PlanStatusResponse>,
    },
    /// A site's measured coverage raster, as a `foxglove.Grid` on `/shift/sites/{site}/coverage`.
    Coverage { log_ns: u64, record: Arc<CoverageRecord> },
    /// Finish the file and leave.
    Stop,
}

struct Shared {
    tx: SyncSender<Entry>,
    run: u64,
    seq: AtomicU64,
    queued_bytes: Arc<AtomicUsize>,
    max_queued_bytes: usize,
    dropped: AtomicU64,
    /// Site grids seen at the engine boundary, for the occupancy messages.
    sites: Arc<Mutex<BTreeMap<String, Arc<OccupancyGrid>>>>,
    /// Grids of the event being handled, kept once the engine accepted it.
    pending_sites: Mutex<Vec<(String, Arc<OccupancyGrid>)>>,
}

/// A cheap, cloneable handle producers record through. Never blocks.
#[derive(Clone)]
pub struct Recorder {
    shared: Arc<Shared>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("run", &self.shared.run)
            .field("dropped", &self.dropped())
            .finish_non_exhaustive()
    }
}

impl Recorder {
    fn send(&self, entry: Entry, bytes: usize) -> bool {
        let s = &self.shared;
        if bytes > 0 && s.queued_bytes.load(Ordering::Relaxed) + bytes > s.max_queued_bytes {
            self.drop_one("queue_bytes");
            return false;
        }
        s.queued_bytes.fetch_add(bytes, Ordering::Relaxed);
        match s.tx.try_send(entry) {
            Ok(()) => true,
            Err(e) => {
                s.queued_bytes.fetch_sub(bytes, Ordering::Relaxed);
                self.drop_one(match e {
                    TrySendError::Full(_) => "queue_full",
                    TrySendError::Disconnected(_) => "stopped",
                });
                false
            }
        }
    }

    fn drop_one(&self, reason: &'static str) {
        let n = self.shared.dropped.fetch_add(1, Ordering::Relaxed);
        metrics::counter!("shift_record_dropped_total", "reason" => reason).increment(1);
        if n.is_power_of_two() {
            tracing::warn!(reason, dropped = n + 1, "recording cannot keep up: messages dropped");
        }
    }

    /// Messages dropped so far.
    pub fn dropped(&self) -> u64 {
        self.shared.dropped.load(Ordering::Relaxed)
    }

    /// Records a payload received on an ingest key (topic = `key`).
    pub fn ingest(&self, kind: Kind, key: &str, bytes: Vec<u8>) {
        let n = bytes.len();
        self.send(
            Entry::Ingest {
                kind,
                key: key.to_owned(),
                log_ns: now_ns(),
                bytes,
            },
            n,
        );
    }

    /// Records a liveliness token appearing (`alive`) or going.
    pub fn liveliness(&self, key: &str, alive: bool) {
        self.send(
            Entry::Liveliness {
                key: key.to_owned(),
                alive,
                log_ns: now_ns(),
            },
            0,
        );
    }

    /// Records an event the engine is about to handle at `now_ms`; returns its sequence number.
    pub fn engine_input(&self, event: &Event, now_ms: u64) -> u64 {
        let seq = self.shared.seq.fetch_add(1, Ordering::Relaxed) + 1;
        let grids: Vec<(String, Arc<OccupancyGrid>)> = match event {
            Event::MapUploaded { site } => vec![(site.record.site.clone(), site.map.grid.clone())],
            Event::Restore { sites, .. } => sites
                .iter()
                .map(|s| (s.record.site.clone(), s.map.grid.clone()))
                .collect(),
            _ => Vec::new(),
        };
        if let Ok(mut p) = self.shared.pending_sites.lock() {
            *p = grids;
        }
        self.send(
            Entry::Input {
                seq,
                now_ms,
                log_ns: now_ns(),
                event: Box::new(event.clone()),
            },
            0,
        );
        seq
    }

    /// Records what the engine decided for input `seq`.
    pub fn engine_output(&self, seq: u64, now_ms: u64, result: &Result<Vec<Command>, EngineError>) {
        let pending = self
            .shared
            .pending_sites
            .lock()
            .map(|mut p| std::mem::take(&mut *p))
            .unwrap_or_default();
        let (mut docs, mut statuses) = (Vec::new(), Vec::new());
        if let Ok(cmds) = result {
            if !pending.is_empty()
                && let Ok(mut sites) = self.shared.sites.lock()
            {
                sites.extend(pending);
            }
            for c in cmds {
                match c {
                    Command::StoreResult { doc, .. } | Command::PublishPlan { doc, .. } => docs.push(doc.clone()),
                    Command::Publish(PlanEvent::Status(s)) => statuses.push(s.clone()),
                    Command::CoverageChanged(record) => {
                        let log_ns = now_ns();
                        self.send(
                            Entry::Coverage {
                                log_ns,
                                record: record.clone(),
                            },
                            0,
                        );
                    }
                    _ => {}
                }
            }
        }
        self.send(
            Entry::Output {
                seq,
                now_ms,
                log_ns: now_ns(),
                decisions: shift_engine::recorded::decisions_of(result),
                docs,
                statuses,
            },
            0,
        );
    }
}

impl Recorder {
    /// Records that input `seq`, a client's request, was undone: the store could not commit what it decided.
    pub fn engine_undone(&self, seq: u64, now_ms: u64, error: &str) {
        if let Ok(mut p) = self.shared.pending_sites.lock() {
            p.clear();
        }
        self.send(
            Entry::Output {
                seq,
                now_ms,
                log_ns: now_ns(),
                decisions: vec![Decision::Undone {
                    error: error.to_owned(),
                }],
                docs: Vec::new(),
                statuses: Vec::new(),
            },
            0,
        );
    }
}

/// A running recording: the writer thread and the Zenoh taps.
pub struct Recording {
    recorder: Recorder,
    thread: Option<std::thread::JoinHandle<Result<Vec<std::path::PathBuf>>>>,
    taps: Vec<JoinHandle<()>>,
    stop: CancellationToken,
}

impl Recording {
    /// Starts recording when `[record] dir` is set: the writer thread, and taps on the ingest keys and
    /// liveliness tokens of `zenoh` when a session is open. `None` when recording is off.
    pub async fn start(
        daemon: &crate::Config,
        engine: &EngineConfig,
        zenoh: Option<(&zenoh::Session, &Arc<KeySpace>)>,
        live: Arc<LiveMaps>,
        clock: &SharedClock,
    ) -> Result<Option<Self>> {
        let config = &daemon.record;
        if !config.enabled() {
            return Ok(None);
        }
        std::fs::create_dir_all(&config.dir).with_context(|| format!("creating {}", config.dir.display()))?;
        let run = clock.now_ms();
        let (tx, rx) = sync_channel(config.queue_messages.max(16));
        let queued_bytes = Arc::new(AtomicUsize::new(0));
        let sites = Arc::new(Mutex::new(BTreeMap::new()));
        let recorder = Recorder {
            shared: Arc::new(Shared {
                tx,
                run,
                seq: AtomicU64::new(0),
                queued_bytes: queued_bytes.clone(),
                max_queued_bytes: config.queue_bytes.max(1 << 16),
                dropped: AtomicU64::new(0),
                sites: sites.clone(),
                pending_sites: Mutex::new(Vec::new()),
            }),
        };
        let mut files = RotatingWriter::new(FileSettings {
            dir: config.dir.clone(),
            run,
            max_file_bytes: config.max_file_bytes,
            max_file_age: Duration::from_secs(config.max_file_s),
            chunk_bytes: config.chunk_bytes,
        });
        let engine_config = RecordedEngineConfig::of(run, engine);
        files.set_preamble(
            Kind::EngineConfig,
            channels::ENGINE_CONFIG,
            serde_json::to_vec(&engine_config)?,
        );
        let worker = WriterThread {
            files,
            run,
            queued_bytes,
            sites,
            live,
            grid_every: Duration::from_secs(config.grid_interval_s),
            frame: daemon.zenoh.map_frame.clone(),
        };
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || worker.run(rx))
            .context("starting the recorder thread")?;
        let stop = CancellationToken::new();
        let taps = match zenoh {
            Some((session, keys)) => {
                tap::start(session, keys, &daemon.zenoh.mapping, recorder.clone(), stop.clone()).await?
            }
            None => Vec::new(),
        };
        tracing::info!(dir = %config.dir.display(), run, "recording to MCAP");
        Ok(Some(Self {
            recorder,
            thread: Some(thread),
            taps,
            stop,
        }))
    }

    /// The handle producers record through.
    pub fn recorder(&self) -> Recorder {
        self.recorder.clone()
    }

    /// Stops the taps, lets the writer drain its queue, finishes the open file; returns every file written.
    /// Call after the engine thread stopped, so its last decisions are in.
    pub async fn finish(mut self) -> Result<Vec<std::path::PathBuf>> {
        self.stop.cancel();
        for t in self.taps.drain(..) {
            let _ = t.await;
        }
        let tx = self.recorder.shared.tx.clone();
        let thread = self.thread.take();
        tokio::task::spawn_blocking(move || {
            // A blocking send: the writer drains what is queued before it sees this.
            let _ = tx.send(Entry::Stop);
            match thread {
                Some(t) => t.join().map_err(|_| crate::err!("the recorder thread panicked"))?,
                None => Ok(Vec::new()),
            }
        })
        .await?
    }
}

struct WriterThread {
    files: RotatingWriter,
    run: u64,
    queued_bytes: Arc<AtomicUsize>,
    sites: Arc<Mutex<BTreeMap<String, Arc<OccupancyGrid>>>>,
    live: Arc<LiveMaps>,
    grid_every: Duration,
    frame: String,
}

impl WriterThread {
    fn run(mut self, rx: Receiver<Entry>) -> Result<Vec<std::path::PathBuf>> {
        let mut last_flush = Instant::now();
        let mut last_grid: Option<Instant> = None;
        let mut errors = 0u64;
        loop {
            match rx.recv_timeout(TICK) {
                Ok(Entry::Stop) | Err(RecvTimeoutError::Disconnected) => break,
                Ok(entry) => {
                    if let Err(e) = self.write(entry) {
                        errors += 1;
                        if errors.is_power_of_two() {
                            tracing::error!("recording: {e:#}");
                        }
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
            if !self.grid_every.is_zero() && last_grid.is_none_or(|t| t.elapsed() >= self.grid_every) {
                match self.grids() {
                    // The first grid comes as soon as a site is known.
                    Ok(0) => {}
                    Ok(_) => last_grid = Some(Instant::now()),
                    Err(e) => tracing::warn!("recording the occupancy grids: {e:#}"),
                }
            }
            let housekeeping = if last_flush.elapsed() >= FLUSH_EVERY {
                last_flush = Instant::now();
                self.files.flush()
            } else {
                Ok(())
            };
            if let Err(e) = housekeeping.and_then(|()| self.files.tick()) {
                tracing::error!("recording: {e:#}");
            }
        }
        // Whatever is still queued (the Stop came after it) was written above. The final occupancy, then finish.
        if !self.grid_every.is_zero()
            && let Err(e) = self.grids()
        {
            tracing::warn!("recording the occupancy grids: {e:#}");
        }
        self.files.finish()?;
        Ok(self.files.finished().to_vec())
    }

    fn write(&mut self, entry: Entry) -> Result<()> {
        let run = self.run;
        match entry {
            Entry::Ingest {
                kind,
                key,
                log_ns,
                bytes,
            } => {
                self.queued_bytes.fetch_sub(bytes.len(), Ordering::Relaxed);
                self.files.write(kind, &key, log_ns, &bytes)?;
            }
            Entry::Liveliness { key, alive, log_ns } => {
                let msg = serde_json::json!({"key": key, "alive": alive});
                self.files.write(
                    Kind::Liveliness,
                    channels::LIVELINESS,
                    log_ns,
                    &serde_json::to_vec(&msg)?,
                )?;
            }
            Entry::Input {
                seq,
                now_ms,
                log_ns,
                event,
            } => {
                let input = RecordedInput {
                    run,
                    seq,
                    now_ms,
                    event: *event,
                };
                self.files.write(
                    Kind::EngineInput,
                    channels::ENGINE_INPUT,
                    log_ns,
                    &serde_json::to_vec(&input)?,
                )?;
            }
            Entry::Output {
                seq,
                now_ms,
                log_ns,
                decisions,
                docs,
                statuses,
            } => {
                let out = RecordedDecisions {
                    run,
                    seq,
                    now_ms,
                    decisions,
                };
                self.files.write(
                    Kind::EngineDecisions,
                    channels::ENGINE_DECISIONS,
                    log_ns,
                    &serde_json::to_vec(&out)?,
                )?;
                for d in docs {
                    self.files
                        .write(Kind::PlanDocument, channels::PLANS, log_ns, &serde_json::to_vec(&*d)?)?;
                }
                for s in statuses {
                    self.files.write(
                        Kind::PlanStatus,
                        channels::PLAN_STATUS,
                        log_ns,
                        &serde_json::to_vec(&s)?,
                    )?;
                }
            }
            Entry::Coverage { log_ns, record } => {
                if let CoverageKey::Site(site) = &record.key {
                    let msg = grid::coverage_grid(&record, &self.frame, log_ns);
                    let topic = channels::coverage(site);
                    self.files
                        .write(Kind::Grid, &topic, log_ns, &serde_json::to_vec(&msg)?)?;
                }
            }
            Entry::Stop => {}
        }
        Ok(())
    }

    /// One `foxglove.Grid` per known site; returns how many.
    fn grids(&mut self) -> Result<usize> {
        let sites: Vec<(String, Arc<OccupancyGrid>)> = match self.sites.lock() {
            Ok(s) => s.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
            Err(_) => return Ok(0),
        };
        let n = sites.len();
        for (site, grid) in sites {
            let live: Vec<(f64, f64)> = self
                .live
                .get(&site)
                .and_then(|l| {
                    l.map
                        .read()
                        .ok()
                        .map(|m| m.points().all().iter().map(|p| (p.x, p.y)).collect())
                })
                .unwrap_or_default();
            let stamp = now_ns();
            let msg = grid::occupancy_grid(&grid, &live, &self.frame, stamp);
            self.files.write(
                Kind::Grid,
                &channels::occupancy(&site),
                stamp,
                &serde_json::to_vec(&msg)?,
            )?;
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recorder(capacity: usize, max_bytes: usize) -> (Recorder, Receiver<Entry>) {
        let (tx, rx) = sync_channel(capacity);
        let r = Recorder {
            shared: Arc::new(Shared {
                tx,
                run: 1,
                seq: AtomicU64::new(0),
                queued_bytes: Arc::new(AtomicUsize::new(0)),
                max_queued_bytes: max_bytes,
                dropped: AtomicU64::new(0),
                sites: Arc::new(Mutex::new(BTreeMap::new())),
                pending_sites: Mutex::new(Vec::new()),
            }),
        };
        (r, rx)
    }

    #[test]
    fn a_full_queue_drops_and_counts_instead_of_blocking() {
        let (r, rx) = recorder(2, 1000);
        r.liveliness("k", true);
        r.liveliness("k", false);
        r.liveliness("k", true); // full: dropped
        assert_eq!(r.dropped(), 1);
        // Payload bytes are capped separately from the message count.
        drop(rx.try_recv());
        r.ingest(Kind::PointCloud2, "k", vec![0; 2000]);
        assert_eq!(r.dropped(), 2, "over queue_bytes");
        r.ingest(Kind::PointCloud2, "k", vec![0; 500]);
        assert_eq!(r.dropped(), 2);
        assert_eq!(r.shared.queued_bytes.load(Ordering::Relaxed), 500);
        // Engine inputs get consecutive sequence numbers even when dropped, so a replay sees the gap.
        assert_eq!(r.engine_input(&Event::Shutdown, 5), 1);
        assert_eq!(r.engine_input(&Event::Shutdown, 6), 2);
        assert_eq!(r.dropped(), 4);
        drop(rx);
        r.liveliness("k", true);
        assert_eq!(r.dropped(), 5, "a stopped writer counts as a drop too");
    }
}
