//! The engine loop: one thread that owns the [`Engine`], the [`Store`] and the job and check runners; takes
//! events from a bounded channel ([`handle`]: the one way in), persists what the engine says to persist *before*
//! answering, updates the read model, starts and cancels jobs and checks, routes robots' sensor data, publishes
//! plan events (SSE, and on Zenoh through the [`Publisher`]).

pub mod handle;

use std::sync::{Arc, Mutex};

use shift_engine::sensors::SensorHub;
use shift_engine::{Command, Engine, Event, LiveMaps};
use shift_proto::PlanEvent;
use tokio::sync::{broadcast, mpsc, watch};

use self::handle::{EngineHandle, INBOX, LoopError, Msg, Reply};
use crate::clock::SharedClock;
use crate::fleet::publish::Publisher;
use crate::jobs::JobRunner;
use crate::record::Recorder;
use crate::store::Store;
use crate::views::Views;
use crate::watch::CheckRunner;

/// What the engine loop works with besides the engine itself.
pub struct LoopParts {
    /// The durable store (the loop is its only writer).
    pub store: Arc<Store>,
    /// The read model it keeps current.
    pub views: Arc<Views>,
    /// Plan events for SSE subscribers.
    pub events: broadcast::Sender<PlanEvent>,
    /// Plans, corrections and plan status out to Zenoh (none without Zenoh).
    pub publisher: Option<Publisher>,
    /// Every site's live map: path checks read it, and the site's static map is handed to it.
    pub live: Arc<LiveMaps>,
    /// With it, plan jobs see their site's live obstacle points.
    pub overlay: bool,
    /// The fleet's sensor pipeline: the loop routes robots' data to their plan's site.
    pub sensors: Arc<Mutex<SensorHub>>,
    /// The runtime whose blocking pool runs plan jobs and path checks.
    pub runtime: tokio::runtime::Handle,
    /// MCAP recording of the engine's inputs and decisions.
    pub recorder: Option<Recorder>,
    /// The time every event is handled at.
    pub clock: SharedClock,
}

/// Starts the engine loop's thread.
pub fn spawn(engine: Engine, parts: LoopParts) -> std::io::Result<(EngineHandle, std::thread::JoinHandle<()>)> {
    let (tx, rx) = mpsc::channel(INBOX);
    let (running_tx, running_rx) = watch::channel(0);
    let handle = EngineHandle::new(tx, running_rx);
    let checks = CheckRunner::new(parts.runtime.clone(), handle.clone(), parts.live.clone());
    let overlay = parts.overlay.then(|| parts.live.clone());
    let jobs = JobRunner::new(parts.runtime.clone(), handle.clone(), overlay);
    let engine_loop = EngineLoop {
        engine,
        parts,
        jobs,
        checks,
        running: running_tx,
    };
    let thread = std::thread::Builder::new()
        .name("engine".into())
        .spawn(move || engine_loop.run(rx))?;
    Ok((handle, thread))
}

struct EngineLoop {
    engine: Engine,
    parts: LoopParts,
    jobs: JobRunner,
    checks: CheckRunner,
    running: watch::Sender<usize>,
}

impl EngineLoop {
    fn run(mut self, mut rx: mpsc::Receiver<Msg>) {
        while let Some(msg) = rx.blocking_recv() {
            match msg {
                Msg::Stop => break,
                Msg::InterruptJobs => self.jobs.interrupt_all(),
                Msg::Event { event, reply } => {
                    let finished = match event.as_ref() {
                        Event::JobFinished { plan_id, .. } => Some(plan_id.clone()),
                        _ => None,
                    };
                    let now = self.parts.clock.now_ms();
                    // MCAP recording of the engine's inputs and decisions (no-op without a recorder).
                    let recorder = self.parts.recorder.as_ref();
                    let seq = recorder.map_or(0, |r| r.engine_input(&event, now));
                    let handled = self.engine.handle(*event, now);
                    if let Some(r) = recorder {
                        r.engine_output(seq, now, &handled);
                    }
                    let result = handled.map_err(LoopError::from).and_then(|cmds| self.execute(cmds));
                    if let Some(id) = finished {
                        self.jobs.finished(&id);
                    }
                    self.export_gauges();
                    match (reply, result) {
                        (Some(r), res) => {
                            let _ = r.send(res);
                        }
                        (None, Err(e)) => tracing::warn!("engine event failed: {e}"),
                        (None, Ok(_)) => {}
                    }
                }
            }
        }
    }

    /// Carries out commands in order. A failed store write stops the rest: nothing after it is acknowledged.
    fn execute(&mut self, cmds: Vec<Command>) -> Result<Reply, LoopError> {
        let mut reply = Reply::default();
        let store_err = |e: crate::error::DaemonError| {
            tracing::error!("store write failed: {e}");
            LoopError::Store(e.to_string())
        };
        let p = &self.parts;
        for cmd in cmds {
            match cmd {
                Command::StoreSite(rec) => p.store.put_site(&rec).map_err(store_err)?,
                Command::SiteChanged(summary) => {
                    p.views.set_site(summary.clone());
                    reply.sites.push(summary);
                }
                Command::StorePlan(rec) => {
                    p.store.put_plan(&rec).map_err(store_err)?;
                    p.views.set_record(rec.clone());
                    reply.plans.push(rec);
                }
                Command::UpdatePlan(rec) => p.views.set_record(rec),
                Command::StoreResult { plan_id, doc } => {
                    p.store.put_result(&plan_id, &doc).map_err(store_err)?;
                    p.views.set_doc(&plan_id, doc);
                }
                Command::StartJob(job) => self.jobs.start(job),
                Command::CancelJob { plan_id } => self.jobs.cancel(&plan_id),
                Command::PublishPlan { robot, doc } => match &p.publisher {
                    Some(publisher) => publisher.plan(&robot, doc),
                    None => tracing::warn!(robot, "zenoh is disabled: the plan is only served over HTTP"),
                },
                Command::RobotChanged(view) => p.views.set_robot(view),
                Command::SiteStatic { site, clearance, grid } => {
                    p.views.set_site_map(&site, grid);
                    p.live.set_static(&site, clearance);
                }
                Command::StartCheck(job) => self.checks.start(*job),
                Command::StoreCorrection {
                    record,
                    correction,
                    doc,
                } => {
                    p.store.put_correction(&record, &correction).map_err(store_err)?;
                    p.views.set_doc(&record.plan_id, doc);
                    p.views.set_record(record.clone());
                    reply.plans.push(record);
                }
                Command::PublishCorrection(correction) => {
                    if let Some(publisher) = &p.publisher {
                        publisher.correction(correction);
                    }
                }
                Command::FeedSite { robot, site } => {
                    let change = p.sensors.lock().ok().and_then(|mut hub| hub.route(&robot, site));
                    if let Some((from, to)) = change {
                        tracing::info!(robot, from = ?from, to = ?to, "robot's sensor data now feeds another site");
                    }
                }
                Command::Publish(event) => {
                    match &event {
                        PlanEvent::RegionReady { plan_id, region } => p.views.push_region(plan_id, region.clone()),
                        PlanEvent::Status(status) => {
                            if let Some(publisher) = &p.publisher {
                                publisher.status(status.clone());
                            }
                        }
                        _ => {}
                    }
                    // No subscriber is not an error.
                    let _ = p.events.send(event);
                }
            }
        }
        Ok(reply)
    }

    fn export_gauges(&mut self) {
        for (status, n) in self.engine.status_counts() {
            metrics::gauge!("shift_plans", "status" => status.as_str()).set(n as f64);
        }
        metrics::gauge!("shift_plan_queue_depth").set(self.engine.queue_depth() as f64);
        metrics::gauge!("shift_plan_jobs_running").set(self.engine.running() as f64);
        let running = self.engine.running();
        self.running.send_if_modified(|r| {
            let changed = *r != running;
            *r = running;
            changed
        });
    }
}
