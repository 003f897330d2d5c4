//! The state machine: events in, commands out.

use std::collections::{BTreeMap, HashMap, HashSet, VecDeque};
use std::sync::Arc;

use shift_proto::{
    CorrectionDoc, LastCorrection, PlanDocument, PlanEvent, PlanRequest, PlanStatus, PoseView, RegionReady, RobotView,
    SiteSummary,
};

use crate::error::{EngineError, Result};
use crate::job::PlanJob;
use crate::plan::PlanRecord;
use crate::request::validate;
use crate::robots::{Assignment, Pose2, Robot, Robots};
use crate::site::{Site, SiteMap, SiteRecord, validate_name, validate_site_name};
use crate::watch::{CheckJob, CheckOutcome, PatchLimits, Trigger, WatchParams};

/// Sizes of the job machinery and how paths are watched.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineConfig {
    /// Jobs computed at once (the blocking pool's size).
    pub workers: usize,
    /// Jobs allowed to wait for a worker; one more is refused with [`EngineError::QueueFull`].
    pub queue_capacity: usize,
    /// Path watching and corrections.
    pub watch: WatchParams,
}

impl Default for EngineConfig {
    fn default() -> Self {
        Self {
            workers: 2,
            queue_capacity: 64,
            watch: WatchParams::default(),
        }
    }
}

/// How a job ended.
#[derive(Debug, Clone)]
pub enum JobOutcome {
    /// Computed.
    Planned {
        /// The plan document (version 1).
        doc: Arc<PlanDocument>,
        /// Planner remarks.
        warnings: Vec<String>,
    },
    /// The planner refused or failed; the message says why.
    Failed(String),
    /// Stopped because the plan was cancelled.
    Cancelled,
    /// Stopped because the daemon is shutting down; the plan goes back to the queue for the next start.
    Interrupted,
}

/// Something that happened.
#[derive(Debug, Clone)]
pub enum Event {
    /// State read back from the store at start-up; in-flight plans are re-queued or failed.
    Restore {
        /// Sites with their parsed maps.
        sites: Vec<(SiteRecord, SiteMap)>,
        /// Every plan record.
        plans: Vec<PlanRecord>,
    },
    /// A map was uploaded (already parsed off the async workers).
    MapUploaded {
        /// What to persist.
        record: SiteRecord,
        /// The parsed map.
        map: SiteMap,
    },
    /// A client asks for a plan.
    PlanRequested(PlanRequest),
    /// A client cancels a plan.
    CancelRequested {
        /// Plan id.
        plan_id: String,
    },
    /// A worker reports progress (0–1).
    JobProgress {
        /// Plan id.
        plan_id: String,
        /// Fraction done.
        progress: f64,
    },
    /// A worker linked one region of the plan it computes (in visiting order, before the job finishes).
    JobRegionReady {
        /// Plan id.
        plan_id: String,
        /// The region and its cover path.
        region: RegionReady,
    },
    /// A worker finished.
    JobFinished {
        /// Plan id.
        plan_id: String,
        /// How.
        outcome: JobOutcome,
    },
    /// A robot's liveliness token appeared (`alive`) or disappeared.
    RobotLiveliness {
        /// Robot id.
        robot: String,
        /// Token present.
        alive: bool,
    },
    /// A robot's odometry, map frame.
    RobotPose {
        /// Robot id.
        robot: String,
        /// Its pose.
        pose: Pose2,
    },
    /// A client assigns a ready plan to a robot (the daemon attaches the current document).
    AssignPlan {
        /// Plan id.
        plan_id: String,
        /// Robot id.
        robot: String,
        /// The plan's current document.
        doc: Arc<PlanDocument>,
    },
    /// New obstacle points landed in a site's live map inside the box `[min, max]` (map frame, metres).
    MapChanged {
        /// Site.
        site: String,
        /// Lower corner (x, y).
        min: [f64; 2],
        /// Upper corner (x, y).
        max: [f64; 2],
    },
    /// A path check ended.
    CheckFinished {
        /// Robot checked.
        robot: String,
        /// Plan it drove when the check started.
        plan_id: String,
        /// Version checked.
        base_version: u64,
        /// What the check found.
        outcome: CheckOutcome,
        /// Time the check took, microseconds (measured by the daemon).
        compute_us: u64,
    },
    /// The daemon is stopping: start no more jobs, refuse new plans.
    Shutdown,
}

/// Something the daemon must do, in the order given.
#[derive(Debug, Clone)]
pub enum Command {
    /// Persist a site (before acknowledging the upload).
    StoreSite(SiteRecord),
    /// The read model's site summary changed.
    SiteChanged(SiteSummary),
    /// A site's static map is (now) this one: its clearance field tells the live map which points are known
    /// obstacles seen again.
    SiteStatic {
        /// Site.
        site: String,
        /// Distance to the static map's non-free cells, metres.
        clearance: Arc<shift_planner::map::DistanceField>,
    },
    /// Persist a plan record (a status change) and update the read model.
    StorePlan(PlanRecord),
    /// Update the read model only (progress, not worth a disk write).
    UpdatePlan(PlanRecord),
    /// Persist a computed plan document.
    StoreResult {
        /// Plan id.
        plan_id: String,
        /// The document.
        doc: Arc<PlanDocument>,
    },
    /// Run this job on the worker pool.
    StartJob(PlanJob),
    /// Raise the cancel flag of a running job.
    CancelJob {
        /// Plan id.
        plan_id: String,
    },
    /// Send to event subscribers.
    Publish(PlanEvent),
    /// Deliver a plan to a robot (its plan key, the ROS Path key; the queryable serves it from now on).
    PublishPlan {
        /// Robot id.
        robot: String,
        /// The plan.
        doc: Arc<PlanDocument>,
    },
    /// The read model's robot view changed.
    RobotChanged(RobotView),
    /// Check this robot's path (off the engine thread, with the site's live map); answer with
    /// [`Event::CheckFinished`].
    StartCheck(Box<CheckJob>),
    /// Persist a correction together with the plan record it bumps (one transaction), then show `doc` (the
    /// corrected current version) in the read model.
    StoreCorrection {
        /// The plan's record at the new version.
        record: PlanRecord,
        /// The correction.
        correction: Arc<CorrectionDoc>,
        /// The current document after it.
        doc: Arc<PlanDocument>,
    },
    /// Send a correction to its robot (its corrections key; the plan queryable serves the new version).
    PublishCorrection(Arc<CorrectionDoc>),
}

/// Odometry within this distance of a waypoint counts as reaching it, metres.
const REACH_TOLERANCE_M: f64 = 0.5;
/// Waypoints searched ahead of the last one reached.
const REACH_WINDOW: usize = 200;

fn robot_view(r: &Robot) -> RobotView {
    RobotView {
        robot: r.id.clone(),
        alive: r.alive,
        last_seen_ms: r.last_seen_ms,
        pose: r.pose.map(|p| PoseView {
            x: p.x,
            y: p.y,
            yaw: p.yaw,
            stamp_ns: p.stamp_ns,
        }),
        plan_id: r.assignment.as_ref().map(|a| a.plan_id.clone()),
        driven_fraction: r.assignment.as_ref().map(Assignment::fraction),
        driven_m: r.assignment.as_ref().map(Assignment::driven_m),
        last_correction: r.last_correction.clone(),
    }
}

/// The fleet brain. See the crate docs.
#[derive(Debug, Default)]
pub struct Engine {
    config: EngineConfig,
    sites: BTreeMap<String, Site>,
    plans: HashMap<String, PlanRecord>,
    queue: VecDeque<String>,
    running: HashSet<String>,
    robots: Robots,
    next_seq: u64,
    draining: bool,
}

impl Engine {
    /// An empty engine.
    pub fn new(config: EngineConfig) -> Self {
        Self {
            config: EngineConfig {
                workers: config.workers.max(1),
                queue_capacity: config.queue_capacity,
                watch: config.watch,
            },
            next_seq: 1,
            ..Self::default()
        }
    }

    /// Handles one event at `now_ms` (milliseconds since the Unix epoch). On error nothing changed.
    pub fn handle(&mut self, event: Event, now_ms: u64) -> Result<Vec<Command>> {
        let mut out = Vec::new();
        match event {
            Event::Restore { sites, plans } => self.restore(sites, plans, now_ms, &mut out),
            Event::MapUploaded { record, map } => {
                validate_site_name(&record.site)?;
                let site = Site { record, map };
                out.push(Command::StoreSite(site.record.clone()));
                out.push(Command::SiteChanged(site.summary()));
                out.push(Command::SiteStatic {
                    site: site.record.site.clone(),
                    clearance: site.map.clearance.clone(),
                });
                self.sites.insert(site.record.site.clone(), site);
            }
            Event::PlanRequested(request) => self.request(request, now_ms, &mut out)?,
            Event::CancelRequested { plan_id } => self.cancel(&plan_id, now_ms, &mut out)?,
            Event::JobProgress { plan_id, progress } => {
                if let Some(rec) = self.plans.get_mut(&plan_id)
                    && rec.status == PlanStatus::Planning
                    && progress.is_finite()
                    && progress > rec.progress
                {
                    // Monotone: a portfolio re-runs stages, the client only sees the furthest point reached.
                    rec.progress = progress.min(0.99);
                    out.push(Command::UpdatePlan(rec.clone()));
                    out.push(Command::Publish(PlanEvent::Progress {
                        plan_id,
                        progress: rec.progress,
                    }));
                }
            }
            Event::JobRegionReady { plan_id, region } => {
                if let Some(rec) = self.plans.get_mut(&plan_id)
                    && rec.status == PlanStatus::Planning
                {
                    rec.regions_ready += 1;
                    out.push(Command::UpdatePlan(rec.clone()));
                    out.push(Command::Publish(PlanEvent::RegionReady { plan_id, region }));
                }
            }
            Event::JobFinished { plan_id, outcome } => self.finished(&plan_id, outcome, now_ms, &mut out),
            Event::RobotLiveliness { robot, alive } => {
                let r = self.robots.entry(&robot, now_ms);
                r.alive = alive;
                r.last_seen_ms = now_ms;
                out.push(Command::RobotChanged(robot_view(r)));
            }
            Event::RobotPose { robot, pose } => self.pose(&robot, pose, now_ms, &mut out),
            Event::AssignPlan { plan_id, robot, doc } => self.assign(&plan_id, &robot, doc, now_ms, &mut out)?,
            Event::MapChanged { site, min, max } => self.map_changed(&site, min, max, now_ms, &mut out),
            Event::CheckFinished {
                robot,
                plan_id,
                base_version,
                outcome,
                compute_us,
            } => self.check_finished(&robot, &plan_id, base_version, outcome, compute_us, now_ms, &mut out),
            Event::Shutdown => self.draining = true,
        }
        self.pump(now_ms, &mut out);
        Ok(out)
    }

    /// A plan's record.
    pub fn plan(&self, plan_id: &str) -> Option<&PlanRecord> {
        self.plans.get(plan_id)
    }

    /// A site's summary.
    pub fn site(&self, site: &str) -> Option<SiteSummary> {
        self.sites.get(site).map(Site::summary)
    }

    /// A robot's view.
    pub fn robot(&self, id: &str) -> Option<RobotView> {
        self.robots.get(id).map(robot_view)
    }

    /// Jobs waiting for a worker.
    pub fn queue_depth(&self) -> usize {
        self.queue.len()
    }

    /// Jobs being computed.
    pub fn running(&self) -> usize {
        self.running.len()
    }

    /// Number of plans per status.
    pub fn status_counts(&self) -> Vec<(PlanStatus, usize)> {
        PlanStatus::ALL
            .iter()
            .map(|&s| (s, self.plans.values().filter(|r| r.status == s).count()))
            .collect()
    }

    fn request(&mut self, request: PlanRequest, now_ms: u64, out: &mut Vec<Command>) -> Result<()> {
        if self.draining {
            return Err(EngineError::ShuttingDown);
        }
        let site = self
            .sites
            .get(&request.site)
            .ok_or_else(|| EngineError::UnknownSite(request.site.clone()))?;
        validate(&request, &site.map.grid)?;
        if self.queue.len() >= self.config.queue_capacity {
            return Err(EngineError::QueueFull {
                capacity: self.config.queue_capacity,
            });
        }
        let seq = self.next_seq;
        self.next_seq += 1;
        let rec = PlanRecord {
            plan_id: format!("p-{seq}"),
            seq,
            request,
            status: PlanStatus::Queued,
            progress: 0.0,
            version: 0,
            regions_ready: 0,
            metrics: None,
            error: None,
            warnings: Vec::new(),
            robot: None,
            driven_fraction: 0.0,
            missed: Vec::new(),
            attempts: 0,
            created_ms: now_ms,
            updated_ms: now_ms,
        };
        self.queue.push_back(rec.plan_id.clone());
        out.push(Command::StorePlan(rec.clone()));
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        self.plans.insert(rec.plan_id.clone(), rec);
        Ok(())
    }

    fn assign(
        &mut self,
        plan_id: &str,
        robot: &str,
        doc: Arc<PlanDocument>,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) -> Result<()> {
        validate_name("robot", robot)?;
        let rec = self
            .plans
            .get_mut(plan_id)
            .ok_or_else(|| EngineError::UnknownPlan(plan_id.to_owned()))?;
        if !matches!(rec.status, PlanStatus::Ready | PlanStatus::Active) {
            return Err(EngineError::InvalidState {
                plan_id: plan_id.to_owned(),
                status: rec.status,
                action: "assign",
            });
        }
        // A plan drives one robot: re-assigning moves it.
        if let Some(prev) = rec.robot.clone()
            && prev != robot
        {
            let r = self.robots.entry(&prev, now_ms);
            r.assignment = None;
            out.push(Command::RobotChanged(robot_view(r)));
        }
        rec.status = PlanStatus::Active;
        rec.robot = Some(robot.to_owned());
        rec.driven_fraction = 0.0;
        rec.updated_ms = now_ms;
        out.push(Command::StorePlan(rec.clone()));
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        let r = self.robots.entry(robot, now_ms);
        if let Some(old) = r.assignment.take()
            && old.plan_id != plan_id
            && let Some(old_rec) = self.plans.get_mut(&old.plan_id)
            && old_rec.status == PlanStatus::Active
        {
            // The robot drops its previous plan; that plan is ready to be assigned again.
            old_rec.status = PlanStatus::Ready;
            old_rec.robot = None;
            old_rec.updated_ms = now_ms;
            out.push(Command::StorePlan(old_rec.clone()));
            out.push(Command::Publish(PlanEvent::Status(old_rec.to_response())));
        }
        r.assignment = Some(Assignment::new(plan_id.to_owned(), doc.clone()));
        out.push(Command::PublishPlan {
            robot: robot.to_owned(),
            doc,
        });
        out.push(Command::RobotChanged(robot_view(r)));
        self.check(robot, Trigger::MapChange, now_ms, out);
        Ok(())
    }

    fn pose(&mut self, robot: &str, pose: Pose2, now_ms: u64, out: &mut Vec<Command>) {
        if !(pose.x.is_finite() && pose.y.is_finite() && pose.yaw.is_finite()) {
            return;
        }
        let r = self.robots.entry(robot, now_ms);
        r.pose = Some(pose);
        r.last_seen_ms = now_ms;
        if let Some(a) = r.assignment.as_mut()
            && a.advance(pose.x, pose.y, REACH_TOLERANCE_M, REACH_WINDOW)
            && let Some(rec) = self.plans.get_mut(&a.plan_id)
        {
            rec.driven_fraction = a.fraction();
            rec.updated_ms = now_ms;
            if a.finished() && rec.status == PlanStatus::Active {
                rec.status = PlanStatus::Done;
                out.push(Command::StorePlan(rec.clone()));
                out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
            } else {
                out.push(Command::UpdatePlan(rec.clone()));
            }
        }
        out.push(Command::RobotChanged(robot_view(r)));
        let due = r.watch.last_check_ms + self.config.watch.check_interval_ms <= now_ms;
        if due {
            self.check(robot, Trigger::Pose, now_ms, out);
        }
    }

    /// Robots of `site` whose detection window reaches the changed box get checked now.
    fn map_changed(&mut self, site: &str, min: [f64; 2], max: [f64; 2], now_ms: u64, out: &mut Vec<Command>) {
        let reach = self.config.watch.window_radius_m;
        let near: Vec<String> = self
            .robots
            .iter()
            .filter(|r| {
                let Some(a) = &r.assignment else { return false };
                let on_site = self.plans.get(&a.plan_id).is_some_and(|p| p.request.site == site);
                let Some(p) = r.pose else { return on_site };
                let dx = (min[0] - p.x).max(p.x - max[0]).max(0.0);
                let dy = (min[1] - p.y).max(p.y - max[1]).max(0.0);
                on_site && dx.hypot(dy) <= reach
            })
            .map(|r| r.id.clone())
            .collect();
        for robot in near {
            self.check(&robot, Trigger::MapChange, now_ms, out);
        }
    }

    /// Starts a check of `robot`'s path unless one is running (then it runs again when that one ends).
    fn check(&mut self, robot: &str, trigger: Trigger, now_ms: u64, out: &mut Vec<Command>) {
        if !self.config.watch.enabled {
            return;
        }
        let Some(r) = self.robots.get_mut(robot) else { return };
        let (Some(a), Some(pose)) = (&r.assignment, r.pose) else {
            return;
        };
        if r.watch.in_flight {
            r.watch.pending = true;
            return;
        }
        let Some(rec) = self.plans.get(&a.plan_id) else { return };
        if rec.status != PlanStatus::Active {
            return;
        }
        let Some(site) = self.sites.get(&rec.request.site) else {
            return;
        };
        let spec = rec.request.robot;
        r.watch.in_flight = true;
        r.watch.pending = false;
        r.watch.last_check_ms = now_ms;
        out.push(Command::StartCheck(Box::new(CheckJob {
            robot: robot.to_owned(),
            plan_id: a.plan_id.clone(),
            site: rec.request.site.clone(),
            doc: a.doc.clone(),
            ahead_from: a.index,
            pose,
            map: site.map.clone(),
            params: self.config.watch.correct_params(spec.radius),
            limits: PatchLimits {
                v_min_mps: spec.v_min,
                v_max_mps: spec.v_max,
                a_max_mps2: spec.a_max,
            },
            trigger,
        })));
    }

    /// A check ended: a proposal for the version still driven becomes the next version; anything else is
    /// dropped, and a robot whose world changed meanwhile is checked again.
    #[allow(clippy::too_many_arguments)]
    fn check_finished(
        &mut self,
        robot: &str,
        plan_id: &str,
        base_version: u64,
        outcome: CheckOutcome,
        compute_us: u64,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
        let Some(r) = self.robots.get_mut(robot) else { return };
        r.watch.in_flight = false;
        let mut again = std::mem::take(&mut r.watch.pending);
        let current = r
            .assignment
            .as_ref()
            .is_some_and(|a| a.plan_id == plan_id && a.doc.version == base_version);
        match outcome {
            CheckOutcome::Correct(p) if current => {
                let Some(a) = r.assignment.as_mut() else { return };
                let Some(rec) = self.plans.get_mut(plan_id) else { return };
                let correction = CorrectionDoc {
                    plan_id: plan_id.to_owned(),
                    robot: robot.to_owned(),
                    base_version,
                    version: base_version + 1,
                    from: p.from,
                    to: p.to,
                    waypoints: p.waypoints,
                    reason: p.reason,
                    dt_after_s: p.dt_after_s,
                    skipped: p.skipped,
                    compute_us,
                };
                let doc = match correction.apply(&a.doc) {
                    Ok(d) => Arc::new(d),
                    Err(e) => {
                        // A check proposes against the document it was given; this is a bug, not input.
                        debug_assert!(false, "proposed correction does not apply: {e}");
                        return;
                    }
                };
                a.corrected(doc.clone(), correction.from, correction.to, correction.waypoints.len());
                rec.version = correction.version;
                rec.updated_ms = now_ms;
                if !correction.skipped.is_empty() {
                    rec.missed.push(correction.skipped.clone());
                }
                r.last_correction = Some(LastCorrection {
                    plan_id: plan_id.to_owned(),
                    version: correction.version,
                    reason: correction.reason,
                    at_ms: now_ms,
                    compute_us,
                });
                let correction = Arc::new(correction);
                out.push(Command::StoreCorrection {
                    record: rec.clone(),
                    correction: correction.clone(),
                    doc,
                });
                out.push(Command::PublishCorrection(correction.clone()));
                out.push(Command::Publish(PlanEvent::Correction((*correction).clone())));
                out.push(Command::RobotChanged(robot_view(r)));
                // The window may hold another breach: look again at once.
                again = true;
            }
            // Stale (the plan moved on meanwhile): the new version needs its own look.
            CheckOutcome::Correct(_) => again = true,
            CheckOutcome::Clear | CheckOutcome::Failed(_) => {}
        }
        if again {
            self.check(robot, Trigger::MapChange, now_ms, out);
        }
    }

    fn cancel(&mut self, plan_id: &str, now_ms: u64, out: &mut Vec<Command>) -> Result<()> {
        let rec = self
            .plans
            .get_mut(plan_id)
            .ok_or_else(|| EngineError::UnknownPlan(plan_id.to_owned()))?;
        match rec.status {
            PlanStatus::Queued => self.queue.retain(|id| id != plan_id),
            PlanStatus::Planning => out.push(Command::CancelJob {
                plan_id: plan_id.to_owned(),
            }),
            status => {
                return Err(EngineError::InvalidState {
                    plan_id: plan_id.to_owned(),
                    status,
                    action: "cancel",
                });
            }
        }
        rec.status = PlanStatus::Cancelled;
        rec.updated_ms = now_ms;
        out.push(Command::StorePlan(rec.clone()));
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        Ok(())
    }

    fn finished(&mut self, plan_id: &str, outcome: JobOutcome, now_ms: u64, out: &mut Vec<Command>) {
        self.running.remove(plan_id);
        let Some(rec) = self.plans.get_mut(plan_id) else { return };
        if rec.status != PlanStatus::Planning {
            return; // cancelled meanwhile: the outcome is moot
        }
        rec.updated_ms = now_ms;
        match outcome {
            JobOutcome::Planned { doc, warnings } => {
                rec.status = PlanStatus::Ready;
                rec.progress = 1.0;
                rec.version = doc.version;
                rec.metrics = Some(doc.metrics);
                rec.warnings.extend(warnings);
                out.push(Command::StoreResult {
                    plan_id: plan_id.to_owned(),
                    doc,
                });
            }
            JobOutcome::Failed(reason) => {
                rec.status = PlanStatus::Failed;
                rec.error = Some(reason);
            }
            JobOutcome::Cancelled => rec.status = PlanStatus::Cancelled,
            JobOutcome::Interrupted => {
                rec.status = PlanStatus::Queued;
                rec.progress = 0.0;
                rec.regions_ready = 0; // the next run streams them again
                self.queue.push_front(plan_id.to_owned());
            }
        }
        out.push(Command::StorePlan(rec.clone()));
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
    }

    fn restore(
        &mut self,
        sites: Vec<(SiteRecord, SiteMap)>,
        plans: Vec<PlanRecord>,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
        for (record, map) in sites {
            let site = Site { record, map };
            out.push(Command::SiteChanged(site.summary()));
            out.push(Command::SiteStatic {
                site: site.record.site.clone(),
                clearance: site.map.clearance.clone(),
            });
            self.sites.insert(site.record.site.clone(), site);
        }
        let mut plans = plans;
        plans.sort_by_key(|r| r.seq);
        for mut rec in plans {
            self.next_seq = self.next_seq.max(rec.seq + 1);
            if matches!(rec.status, PlanStatus::Queued | PlanStatus::Planning) {
                rec.updated_ms = now_ms;
                rec.progress = 0.0;
                if self.sites.contains_key(&rec.request.site) {
                    rec.status = PlanStatus::Queued;
                    rec.warnings.push("re-queued after a restart".into());
                    self.queue.push_back(rec.plan_id.clone());
                } else {
                    rec.status = PlanStatus::Failed;
                    rec.error = Some(format!(
                        "interrupted by a restart and site {:?} no longer exists",
                        rec.request.site
                    ));
                }
                out.push(Command::StorePlan(rec.clone()));
            } else {
                out.push(Command::UpdatePlan(rec.clone()));
            }
            self.plans.insert(rec.plan_id.clone(), rec);
        }
    }

    /// Starts queued jobs while workers are free.
    fn pump(&mut self, now_ms: u64, out: &mut Vec<Command>) {
        while !self.draining && self.running.len() < self.config.workers {
            let Some(id) = self.queue.pop_front() else { break };
            let Some(rec) = self.plans.get_mut(&id) else { continue };
            if rec.status != PlanStatus::Queued {
                continue;
            }
            rec.updated_ms = now_ms;
            let checked = self
                .sites
                .get(&rec.request.site)
                .ok_or_else(|| EngineError::UnknownSite(rec.request.site.clone()))
                .and_then(|site| Ok((site.map.grid.clone(), validate(&rec.request, &site.map.grid)?)));
            match checked {
                Ok((grid, options)) => {
                    rec.status = PlanStatus::Planning;
                    rec.attempts += 1;
                    self.running.insert(id.clone());
                    out.push(Command::StorePlan(rec.clone()));
                    out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
                    out.push(Command::StartJob(PlanJob {
                        plan_id: id,
                        grid,
                        request: rec.request.clone(),
                        options,
                        overlay: Vec::new(),
                    }));
                }
                Err(e) => {
                    // The site's map changed under a queued request and it no longer fits.
                    rec.status = PlanStatus::Failed;
                    rec.error = Some(e.to_string());
                    out.push(Command::StorePlan(rec.clone()));
                    out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod watch_tests;
