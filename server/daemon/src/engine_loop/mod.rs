//! The engine loop: one thread that owns the [`Engine`], the [`Store`] and the job and check runners; takes
//! events from a bounded channel ([`handle`]: the one way in), persists what the engine says to persist *before*
//! answering (an event's writes in one transaction), updates the read model, starts and cancels jobs and checks,
//! routes robots' sensor data, publishes plan events (SSE, and on Zenoh through the [`Publisher`]). When the
//! store cannot write, [`durability`] says what is undone, what waits and what runs.

pub mod durability;
pub mod handle;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use shift_engine::sensors::SensorHub;
use shift_engine::{Command, Engine, Event, LiveMaps};
use shift_proto::{MissionView, PlanEvent};
use tokio::sync::{broadcast, mpsc, watch};

use self::durability::Durability;
use self::handle::{EngineHandle, INBOX, LoopError, Msg, Reply};
use crate::clock::SharedClock;
use crate::fleet::publish::Publisher;
use crate::jobs::JobRunner;
use crate::pools::Pools;
use crate::record::Recorder;
use crate::store::{Store, Write};
use crate::views::Views;
use crate::watch::CheckRunner;

/// The loop's gauges are set at most this often (a scrape every few seconds sees them fresh).
const GAUGES_EVERY: Duration = Duration::from_millis(250);

/// What the engine loop works with besides the engine itself.
pub struct LoopParts {
    /// The durable store (the loop is its only writer).
    pub store: Arc<Store>,
    /// The read model it keeps current.
    pub views: Arc<Views>,
    /// Plan events for SSE subscribers.
    pub events: broadcast::Sender<PlanEvent>,
    /// Mission views for SSE subscribers.
    pub mission_events: broadcast::Sender<MissionView>,
    /// Plans, corrections and plan status out to Zenoh (none without Zenoh).
    pub publisher: Option<Publisher>,
    /// Every site's live map: path checks read it, and the site's static map is handed to it.
    pub live: Arc<LiveMaps>,
    /// With it, plan jobs see their site's live obstacle points.
    pub overlay: bool,
    /// The fleet's sensor pipeline: the loop routes robots' data to their plan's site.
    pub sensors: Arc<Mutex<SensorHub>>,
    /// The threads that run plan jobs and path checks.
    pub pools: Pools,
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
    let checks = CheckRunner::new(parts.pools.checks.clone(), handle.clone(), parts.live.clone());
    let overlay = parts.overlay.then(|| parts.live.clone());
    let jobs = JobRunner::new(parts.pools.plans.clone(), handle.clone(), overlay);
    let engine_loop = EngineLoop {
        engine,
        parts,
        jobs,
        checks,
        running: running_tx,
        durability: Durability::default(),
        gauges_at: None,
        plans_changed: false,
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
    durability: Durability,
    /// When the gauges were last set.
    gauges_at: Option<Instant>,
    /// A plan record was stored since (its status, the queue or the running jobs may have changed).
    plans_changed: bool,
}

impl EngineLoop {
    fn run(mut self, mut rx: mpsc::Receiver<Msg>) {
        while let Some(msg) = rx.blocking_recv() {
            match msg {
                Msg::Stop => break,
                Msg::InterruptJobs => self.jobs.interrupt_all(),
                Msg::Event { event, reply, sent } => {
                    let kind = event.kind();
                    let started = Instant::now();
                    metrics::histogram!("shift_engine_wait_seconds")
                        .record(started.saturating_duration_since(sent).as_secs_f64());
                    let finished = match event.as_ref() {
                        Event::JobFinished { plan_id, .. } => Some(plan_id.clone()),
                        Event::MissionFinished { mission_id, .. } => Some(mission_id.clone()),
                        _ => None,
                    };
                    let result = self.on_event(*event);
                    if let Some(id) = finished {
                        self.jobs.finished(&id);
                    }
                    self.export_gauges();
                    metrics::histogram!("shift_engine_event_seconds", "event" => kind)
                        .record(started.elapsed().as_secs_f64());
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

    /// Handles one event: the engine decides, the store commits the event's writes in one transaction, then
    /// the rest is carried out. See [`durability`] for a store that cannot write.
    fn on_event(&mut self, event: Event) -> Result<Reply, LoopError> {
        let now = self.parts.clock.now_ms();
        if self.durability.fault().is_some() {
            let (store, views) = (self.parts.store.clone(), self.parts.views.clone());
            let mut waited = Vec::new();
            if self.durability.retry(&store, now, |batch| waited.push(batch)) {
                views.set_store_fault(None);
            }
            for batch in waited {
                self.execute(batch);
            }
        }
        let request = event.is_request();
        if request && let Some(fault) = self.durability.fault() {
            return Err(LoopError::Store(fault.clone()));
        }
        let snapshot = request.then(|| self.engine.clone());
        // MCAP recording of the engine's inputs and decisions (no-op without a recorder).
        let recorder = self.parts.recorder.clone();
        let seq = recorder.as_ref().map_or(0, |r| r.engine_input(&event, now));
        let cmds = match self.engine.handle(event, now) {
            Ok(cmds) => cmds,
            Err(e) => {
                if let Some(r) = &recorder {
                    r.engine_output(seq, now, &Err(e.clone()));
                }
                return Err(e.into());
            }
        };
        let committed = if !request && self.durability.must_wait() {
            Err(None)
        } else {
            let writes: Vec<Write<'_>> = cmds.iter().filter_map(Write::of).collect();
            match writes.is_empty() {
                true => Ok(()),
                false => self.parts.store.commit(&writes).map_err(Some),
            }
        };
        match (committed, snapshot) {
            (Err(Some(e)), Some(snapshot)) => {
                // A request whose writes did not commit: as if it never reached the engine.
                self.engine = snapshot;
                if let Some(r) = &recorder {
                    r.engine_undone(seq, now, &e.to_string());
                }
                self.durability.failed(&e, now);
                self.parts.views.set_store_fault(Some(e.clone()));
                Err(LoopError::Store(e))
            }
            (Ok(()), _) => {
                if let Some(r) = &recorder {
                    r.engine_output(seq, now, &Ok(cmds.clone()));
                }
                Ok(self.execute(cmds))
            }
            (Err(e), _) => {
                // A fact: the engine's decision stands; its durable part waits for the store.
                if let Some(r) = &recorder {
                    r.engine_output(seq, now, &Ok(cmds.clone()));
                }
                if let Some(e) = e {
                    self.durability.failed(&e, now);
                    self.parts.views.set_store_fault(Some(e));
                }
                let (run_now, later) = durability::split_durable(cmds);
                self.durability.defer(later);
                Ok(self.execute(run_now))
            }
        }
    }

    /// Carries out commands in order, once their writes are committed (the store commands update the views).
    fn execute(&mut self, cmds: Vec<Command>) -> Reply {
        let mut reply = Reply::default();
        let p = &self.parts;
        for cmd in cmds {
            match cmd {
                Command::StoreSite(_) => {}
                Command::SiteChanged(summary) => {
                    p.views.set_site(summary.clone());
                    reply.sites.push(summary);
                }
                Command::StorePlan(rec) => {
                    self.plans_changed = true;
                    p.views.set_record(rec.clone());
                    reply.plans.push(rec);
                }
                Command::UpdatePlan(rec) => p.views.set_record(rec),
                Command::StoreResult { plan_id, doc } => {
                    p.views.set_doc(&plan_id, doc);
                }
                Command::StartJob(job) => {
                    self.plans_changed = true;
                    self.jobs.start(job);
                }
                Command::StartMission(job) => {
                    self.plans_changed = true;
                    self.jobs.start_mission(*job);
                }
                Command::StoreMission(_) | Command::StoreCoverage(_) => {}
                Command::ReplacePlanDoc { record, doc } => {
                    self.plans_changed = true;
                    p.views.set_record(record.clone());
                    p.views.set_doc(&record.plan_id, doc);
                    p.views.clear_corrections(&record.plan_id);
                    reply.plans.push(record);
                }
                Command::MissionChanged(view) => {
                    p.views.set_mission(view.clone());
                    // No subscriber is not an error.
                    let _ = p.mission_events.send(view.clone());
                    reply.missions.push(view);
                }
                Command::CoverageChanged(record) => p.views.set_coverage(record),
                Command::CancelJob { plan_id } => {
                    self.plans_changed = true;
                    self.jobs.cancel(&plan_id);
                }
                Command::PublishPlan { robot, doc } => match &p.publisher {
                    Some(publisher) => publisher.plan(&robot, doc),
                    None => tracing::warn!(robot, "zenoh is disabled: the plan is only served over HTTP"),
                },
                Command::RobotChanged(view) => p.views.set_robot(view),
                Command::ForgetPlan { plan_id } => {
                    self.plans_changed = true;
                    p.views.forget_plan(&plan_id);
                }
                Command::SiteStatic {
                    site,
                    clearance,
                    grid,
                    ground,
                } => {
                    p.views.set_site_map(&site, grid);
                    p.live.set_static(&site, clearance, ground);
                }
                Command::StartCheck(job) => self.checks.start(*job),
                Command::StoreCorrection {
                    record,
                    doc,
                    correction,
                } => {
                    // A check's proposal became a version (proposals held or stale are not counted).
                    metrics::counter!("shift_corrections_total", "reason" => correction.reason.as_str()).increment(1);
                    tracing::info!(
                        robot = correction.robot,
                        plan_id = correction.plan_id,
                        version = correction.version,
                        reason = correction.reason.as_str(),
                        from = correction.from,
                        to = correction.to,
                        compute_us = correction.compute_us,
                        "path corrected"
                    );
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
                        PlanEvent::Correction(correction) => p.views.push_correction(correction),
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
        reply
    }

    /// The running-jobs watch after every event; the gauges when a plan record changed, else at most every
    /// [`GAUGES_EVERY`] (counting plans by status walks every plan held, and odometry brings thousands of events
    /// a second, most of which change no plan's status).
    fn export_gauges(&mut self) {
        if std::mem::take(&mut self.plans_changed) || self.gauges_at.is_none_or(|t| t.elapsed() >= GAUGES_EVERY) {
            self.gauges_at = Some(Instant::now());
            for (status, n) in self.engine.status_counts() {
                metrics::gauge!("shift_plans", "status" => status.as_str()).set(n as f64);
            }
            metrics::gauge!("shift_plan_queue_depth").set(self.engine.queue_depth() as f64);
            metrics::gauge!("shift_plan_jobs_running").set(self.engine.running() as f64);
            metrics::gauge!("shift_store_ok").set(if self.durability.fault().is_none() { 1.0 } else { 0.0 });
            metrics::gauge!("shift_store_deferred").set(self.durability.deferred() as f64);
        }
        let running = self.engine.running();
        self.running.send_if_modified(|r| {
            let changed = *r != running;
            *r = running;
            changed
        });
    }
}
