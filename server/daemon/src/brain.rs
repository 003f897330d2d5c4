//! The engine thread: owns the [`Engine`], the [`Store`] and the [`JobRunner`]; takes events from a bounded
//! channel, persists what the engine says to persist *before* answering, updates the read model, starts and
//! cancels jobs, and publishes plan events. Handlers talk to it through [`BrainHandle`].

use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};

use shift_engine::{Command, Engine, EngineError, Event, PlanRecord};
use shift_proto::{PlanEvent, SiteSummary};
use tokio::sync::{broadcast, mpsc, oneshot, watch};

use crate::fleet::PlanPublisher;
use crate::fleet::live::LiveMaps;
use crate::jobs::JobRunner;
use crate::store::Store;
use crate::views::Views;
use crate::watch::CheckRunner;

/// Capacity of the engine's inbox; handlers wait for room (back-pressure), progress reports are dropped.
pub const INBOX: usize = 1024;

/// What the engine thread answers a handler.
#[derive(Debug, Default)]
pub struct Reply {
    /// Plan records changed by the event (the accepted plan first).
    pub plans: Vec<PlanRecord>,
    /// Site summaries changed by the event.
    pub sites: Vec<SiteSummary>,
}

/// Why an event was not carried out.
#[derive(Debug, thiserror::Error)]
pub enum BrainError {
    /// The engine refused it.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// The store could not commit it: nothing is acknowledged.
    #[error("store: {0}")]
    Store(String),
    /// The engine thread has stopped.
    #[error("the engine has stopped")]
    Stopped,
}

/// A message to the engine thread.
#[derive(Debug)]
pub enum Msg {
    /// Handle an event; answer on `reply` when given.
    Event {
        /// The event (boxed: messages stay small in the channel).
        event: Box<Event>,
        /// Where to answer.
        reply: Option<oneshot::Sender<Result<Reply, BrainError>>>,
    },
    /// Stop every running job (shutdown after the grace period); they go back to the queue.
    InterruptJobs,
    /// Leave the loop.
    Stop,
}

impl Msg {
    /// An event nobody waits for.
    pub fn event(event: Event) -> Self {
        Self::Event {
            event: Box::new(event),
            reply: None,
        }
    }
}

/// A cheap, cloneable handle to the engine thread.
#[derive(Debug, Clone)]
pub struct BrainHandle {
    tx: mpsc::Sender<Msg>,
    running: watch::Receiver<usize>,
}

impl BrainHandle {
    /// Sends an event and waits for the engine's answer (after the store committed).
    pub async fn call(&self, event: Event) -> Result<Reply, BrainError> {
        let (reply, rx) = oneshot::channel();
        self.tx
            .send(Msg::Event {
                event: Box::new(event),
                reply: Some(reply),
            })
            .await
            .map_err(|_| BrainError::Stopped)?;
        rx.await.map_err(|_| BrainError::Stopped)?
    }

    /// Sends an event without waiting.
    pub async fn tell(&self, msg: Msg) -> Result<(), BrainError> {
        self.tx.send(msg).await.map_err(|_| BrainError::Stopped)
    }

    /// Sends without waiting for room; fails when the inbox is full (callers drop lossy data then).
    pub fn try_tell(&self, msg: Msg) -> Result<(), BrainError> {
        self.tx.try_send(msg).map_err(|_| BrainError::Stopped)
    }

    /// Watches the number of running jobs.
    pub fn running(&self) -> watch::Receiver<usize> {
        self.running.clone()
    }

    /// True while the engine thread takes events.
    pub fn is_alive(&self) -> bool {
        !self.tx.is_closed()
    }

    /// The inbox, for the job runner.
    pub fn sender(&self) -> mpsc::Sender<Msg> {
        self.tx.clone()
    }
}

/// Milliseconds since the Unix epoch.
pub fn now_ms() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

/// What the engine thread works with besides the engine itself.
pub struct BrainParts {
    /// The durable store (the engine thread is its only writer).
    pub store: Arc<Store>,
    /// The read model it keeps current.
    pub views: Arc<Views>,
    /// Plan events for SSE subscribers.
    pub events: broadcast::Sender<PlanEvent>,
    /// Plans and corrections out to robots (none without Zenoh).
    pub publisher: Option<PlanPublisher>,
    /// Every site's live map: path checks read it, and the site's static map is handed to it.
    pub live: Arc<LiveMaps>,
    /// With it, plan jobs see their site's live obstacle points.
    pub overlay: Option<Arc<LiveMaps>>,
    /// The runtime whose blocking pool runs plan jobs and path checks.
    pub runtime: tokio::runtime::Handle,
    /// MCAP recording of the engine's inputs and decisions.
    pub recorder: Option<crate::record::Recorder>,
}

/// Starts the engine thread.
pub fn spawn(engine: Engine, parts: BrainParts) -> std::io::Result<(BrainHandle, std::thread::JoinHandle<()>)> {
    let BrainParts {
        store,
        views,
        events,
        publisher,
        live,
        overlay,
        runtime,
        recorder,
    } = parts;
    let (tx, rx) = mpsc::channel(INBOX);
    let (running_tx, running_rx) = watch::channel(0);
    let checks = CheckRunner::new(runtime.clone(), tx.clone(), live.clone());
    let jobs = JobRunner::new(runtime, tx.clone(), overlay);
    let brain = Brain {
        engine,
        store,
        views,
        events,
        jobs,
        checks,
        live,
        publisher,
        running: running_tx,
        recorder,
    };
    let thread = std::thread::Builder::new()
        .name("engine".into())
        .spawn(move || brain.run(rx))?;
    Ok((
        BrainHandle {
            tx,
            running: running_rx,
        },
        thread,
    ))
}

struct Brain {
    engine: Engine,
    store: Arc<Store>,
    views: Arc<Views>,
    events: broadcast::Sender<PlanEvent>,
    jobs: JobRunner,
    checks: CheckRunner,
    live: Arc<LiveMaps>,
    publisher: Option<PlanPublisher>,
    running: watch::Sender<usize>,
    recorder: Option<crate::record::Recorder>,
}

impl Brain {
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
                    let now = now_ms();
                    // MCAP recording of the engine's inputs and decisions (no-op without a recorder).
                    let seq = crate::record::input(self.recorder.as_ref(), &event, now);
                    let handled = self.engine.handle(*event, now);
                    crate::record::output(self.recorder.as_ref(), seq, now, &handled);
                    let result = handled.map_err(BrainError::from).and_then(|cmds| self.execute(cmds));
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
    fn execute(&mut self, cmds: Vec<Command>) -> Result<Reply, BrainError> {
        let mut reply = Reply::default();
        let store_err = |e: anyhow::Error| {
            tracing::error!("store write failed: {e:#}");
            BrainError::Store(format!("{e:#}"))
        };
        for cmd in cmds {
            match cmd {
                Command::StoreSite(rec) => self.store.put_site(&rec).map_err(store_err)?,
                Command::SiteChanged(summary) => {
                    self.views.set_site(summary.clone());
                    reply.sites.push(summary);
                }
                Command::StorePlan(rec) => {
                    self.store.put_plan(&rec).map_err(store_err)?;
                    self.views.set_record(rec.clone());
                    reply.plans.push(rec);
                }
                Command::UpdatePlan(rec) => self.views.set_record(rec),
                Command::StoreResult { plan_id, doc } => {
                    self.store.put_result(&plan_id, &doc).map_err(store_err)?;
                    self.views.set_doc(&plan_id, doc);
                }
                Command::StartJob(job) => self.jobs.start(job),
                Command::CancelJob { plan_id } => self.jobs.cancel(&plan_id),
                Command::PublishPlan { robot, doc } => match &self.publisher {
                    Some(p) => p.publish(&robot, doc),
                    None => tracing::warn!(robot, "zenoh is disabled: the plan is only served over HTTP"),
                },
                Command::RobotChanged(view) => self.views.set_robot(view),
                Command::SiteStatic { site, clearance } => self.live.set_static(&site, clearance),
                Command::StartCheck(job) => self.checks.start(*job),
                Command::StoreCorrection {
                    record,
                    correction,
                    doc,
                } => {
                    self.store.put_correction(&record, &correction).map_err(store_err)?;
                    self.views.set_doc(&record.plan_id, doc);
                    self.views.set_record(record.clone());
                    reply.plans.push(record);
                }
                Command::PublishCorrection(correction) => match &self.publisher {
                    Some(p) => p.publish_correction(correction),
                    None => tracing::debug!("zenoh is disabled: the correction is only served over HTTP"),
                },
                Command::Publish(event) => {
                    if let PlanEvent::RegionReady { plan_id, region } = &event {
                        self.views.push_region(plan_id, region.clone());
                    }
                    // No subscriber is not an error.
                    let _ = self.events.send(event);
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
