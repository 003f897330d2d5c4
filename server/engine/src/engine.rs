//! The state machine: events in, commands out.

use std::collections::{BTreeMap, HashMap, HashSet, VecDeque};
use std::sync::Arc;

use shift_proto::{PlanDocument, PlanEvent, PlanRequest, PlanStatus, PoseView, RegionReady, RobotView, SiteSummary};

use crate::error::{EngineError, Result};
use crate::job::PlanJob;
use crate::plan::PlanRecord;
use crate::request::validate;
use crate::robots::{Assignment, Pose2, Robot, Robots};
use crate::site::{Site, SiteMap, SiteRecord, validate_name, validate_site_name};

/// Sizes of the job machinery.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EngineConfig {
    /// Jobs computed at once (the blocking pool's size).
    pub workers: usize,
    /// Jobs allowed to wait for a worker; one more is refused with [`EngineError::QueueFull`].
    pub queue_capacity: usize,
}

impl Default for EngineConfig {
    fn default() -> Self {
        Self {
            workers: 2,
            queue_capacity: 64,
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
        /// Per-region cover paths in visiting order.
        regions: Vec<RegionReady>,
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
            Event::JobFinished { plan_id, outcome } => self.finished(&plan_id, outcome, now_ms, &mut out),
            Event::RobotLiveliness { robot, alive } => {
                let r = self.robots.entry(&robot, now_ms);
                r.alive = alive;
                r.last_seen_ms = now_ms;
                out.push(Command::RobotChanged(robot_view(r)));
            }
            Event::RobotPose { robot, pose } => self.pose(&robot, pose, now_ms, &mut out),
            Event::AssignPlan { plan_id, robot, doc } => self.assign(&plan_id, &robot, doc, now_ms, &mut out)?,
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
            JobOutcome::Planned { doc, warnings, regions } => {
                for region in regions {
                    rec.regions_ready += 1;
                    out.push(Command::Publish(PlanEvent::RegionReady {
                        plan_id: plan_id.to_owned(),
                        region,
                    }));
                }
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
