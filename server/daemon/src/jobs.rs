//! Plan jobs on the plan pool ([`crate::pools`]): run the engine's job function with a monitor wired to the cancel flags and
//! the engine thread, turn the planner's output into the plan document, and report back. The engine bounds
//! how many run at once, so this never queues work of its own.

use std::collections::HashMap;
use std::panic::AssertUnwindSafe;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use shift_engine::{
    Event, JobOutcome, LiveMaps, MissionJob, MissionOutcome, PlanJob, planned_outcome, run_job,
    run_mission_job_monitored, to_document,
};
use shift_planner::PlannerError;
use shift_planner::geom::Point2;
use shift_planner::pipeline::{PlanMonitor, RegionSummary};
use shift_proto::RegionReady;

use crate::engine_loop::handle::{EngineHandle, Msg};

/// A mission job's view of its stop flags: cancelled by the operator or interrupted by a shutdown.
struct StopFlags<'a> {
    cancel: &'a AtomicBool,
    interrupt: &'a AtomicBool,
}

impl PlanMonitor for StopFlags<'_> {
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed) || self.interrupt.load(Ordering::Relaxed)
    }
}

/// Spawns jobs and holds their cancel flags.
#[derive(Debug)]
pub struct JobRunner {
    pool: Arc<rayon::ThreadPool>,
    to_engine: EngineHandle,
    cancels: HashMap<String, Arc<AtomicBool>>,
    interrupt: Arc<AtomicBool>,
    overlay: Option<Arc<LiveMaps>>,
}

struct Monitor {
    plan_id: String,
    cancel: Arc<AtomicBool>,
    interrupt: Arc<AtomicBool>,
    to_engine: EngineHandle,
    last_sent: f64,
}

impl PlanMonitor for Monitor {
    fn progress(&mut self, fraction: f64) {
        if fraction >= self.last_sent + 0.01 {
            self.last_sent = fraction;
            // Progress is lossy on purpose: a full channel drops it rather than stall the planner.
            let _ = self.to_engine.try_tell(Msg::event(Event::JobProgress {
                plan_id: self.plan_id.clone(),
                progress: fraction,
            }));
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed) || self.interrupt.load(Ordering::Relaxed)
    }

    fn region_ready(&mut self, region: &RegionSummary, path: &[Point2]) {
        // Not lossy: a client may start a robot on it. Regions are few; waiting for room is cheap.
        let _ = self.to_engine.blocking_tell(Msg::event(Event::JobRegionReady {
            plan_id: self.plan_id.clone(),
            region: RegionReady {
                region: region.id,
                polygon: region.polygon.iter().map(|p| [p.x, p.y]).collect(),
                path: path.iter().map(|p| [p.x, p.y]).collect(),
            },
        }));
    }
}

impl JobRunner {
    /// A runner spawning on `pool` and reporting to the engine thread; with `overlay`, each job sees its
    /// site's live obstacle points (see [`live_overlay`]).
    pub fn new(pool: Arc<rayon::ThreadPool>, to_engine: EngineHandle, overlay: Option<Arc<LiveMaps>>) -> Self {
        Self {
            pool,
            to_engine,
            cancels: HashMap::new(),
            interrupt: Arc::new(AtomicBool::new(false)),
            overlay,
        }
    }

    /// Starts a job (its live overlay is read on the plan pool, not on the engine thread).
    pub fn start(&mut self, mut job: PlanJob) {
        let cancel = Arc::new(AtomicBool::new(false));
        self.cancels.insert(job.plan_id.clone(), cancel.clone());
        let interrupt = self.interrupt.clone();
        let to_engine = self.to_engine.clone();
        let overlay = self.overlay.clone();
        self.pool.spawn(move || {
            if let Some(live) = overlay {
                job.overlay = live_overlay(&live, &job.request.site);
            }
            let plan_id = job.plan_id.clone();
            let mut monitor = Monitor {
                plan_id: plan_id.clone(),
                cancel,
                interrupt: interrupt.clone(),
                to_engine: to_engine.clone(),
                last_sent: 0.0,
            };
            let t = Instant::now();
            let result = std::panic::catch_unwind(AssertUnwindSafe(|| run_job(&job, &mut monitor)));
            let compute_ms = t.elapsed().as_secs_f64() * 1e3;
            let outcome = match result {
                Ok(Ok(res)) => {
                    metrics::histogram!("shift_plan_compute_seconds").record(compute_ms / 1e3);
                    let doc = to_document(
                        &plan_id,
                        (&res.space, &res.output),
                        &res.profile,
                        res.with_attribute,
                        compute_ms,
                    );
                    JobOutcome::Planned {
                        doc: Arc::new(doc),
                        warnings: res.output.warnings,
                    }
                }
                Ok(Err(PlannerError::Cancelled)) if interrupt.load(Ordering::Relaxed) => JobOutcome::Interrupted,
                Ok(Err(PlannerError::Cancelled)) => JobOutcome::Cancelled,
                Ok(Err(e)) => JobOutcome::Failed { reason: e.to_string() },
                Err(_) => {
                    tracing::error!(plan_id, "planner panicked");
                    JobOutcome::Failed {
                        reason: "internal planner error (logged)".into(),
                    }
                }
            };
            // The engine must learn of every end, so this one waits for room.
            let _ = to_engine.blocking_tell(Msg::event(Event::JobFinished { plan_id, outcome }));
        });
    }

    /// Starts a mission job: the site divided among the fleet and every part planned, as one job on the plan
    /// pool. A cancel (its flag is the mission id's) or a shutdown stops it between and within the parts' plans;
    /// the engine ignores the outcome of a cancelled mission.
    pub fn start_mission(&mut self, mut job: MissionJob) {
        let to_engine = self.to_engine.clone();
        let overlay = self.overlay.clone();
        let interrupt = self.interrupt.clone();
        let cancel = Arc::new(AtomicBool::new(false));
        self.cancels.insert(job.mission_id.clone(), cancel.clone());
        self.pool.spawn(move || {
            if let Some(live) = overlay {
                job.overlay = live_overlay(&live, &job.request.site);
            }
            let mission_id = job.mission_id.clone();
            let t = Instant::now();
            let mut monitor = StopFlags {
                cancel: &cancel,
                interrupt: &interrupt,
            };
            let result = std::panic::catch_unwind(AssertUnwindSafe(|| run_mission_job_monitored(&job, &mut monitor)));
            let compute_ms = t.elapsed().as_secs_f64() * 1e3;
            let outcome = match result {
                _ if interrupt.load(Ordering::Relaxed) => MissionOutcome::Interrupted,
                Ok(Ok(fleet)) => {
                    metrics::histogram!("shift_mission_compute_seconds").record(compute_ms / 1e3);
                    planned_outcome(&job, &fleet, compute_ms)
                }
                // The engine has marked the mission cancelled and ignores this.
                Ok(Err(PlannerError::Cancelled)) => MissionOutcome::Failed {
                    reason: "cancelled".into(),
                },
                Ok(Err(e)) => MissionOutcome::Failed { reason: e.to_string() },
                Err(_) => {
                    tracing::error!(mission_id, "mission job panicked");
                    MissionOutcome::Failed {
                        reason: "internal planner error (logged)".into(),
                    }
                }
            };
            let _ = to_engine.blocking_tell(Msg::event(Event::MissionFinished { mission_id, outcome }));
        });
    }

    /// Raises a job's cancel flag.
    pub fn cancel(&mut self, plan_id: &str) {
        if let Some(flag) = self.cancels.get(plan_id) {
            flag.store(true, Ordering::Relaxed);
        }
    }

    /// Forgets a finished job's flag.
    pub fn finished(&mut self, plan_id: &str) {
        self.cancels.remove(plan_id);
    }

    /// Stops every running job; they report [`JobOutcome::Interrupted`] and stay queued in the store.
    pub fn interrupt_all(&self) {
        self.interrupt.store(true, Ordering::Relaxed);
    }
}

/// The site's live obstacle points as (x, y) in the map frame, metres (empty without a live map). Every point
/// of the live map is already an obstacle: the height band was applied when it was ingested.
pub fn live_overlay(live: &LiveMaps, site: &str) -> Vec<[f64; 2]> {
    let Some(site_live) = live.get(site) else {
        return Vec::new();
    };
    let Ok(map) = site_live.map.read() else {
        return Vec::new();
    };
    let points: Vec<[f64; 2]> = map.points().all().iter().map(|p| [p.x, p.y]).collect();
    drop(map);
    tracing::debug!(site, points = points.len(), "live overlay for a plan job");
    metrics::histogram!("shift_plan_overlay_points").record(points.len() as f64);
    points
}
