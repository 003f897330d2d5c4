//! Plans and the job queue: requests, cancels, job ends, restore after a restart, and starting queued jobs.

use std::sync::Arc;

use shift_planner::map::OccupancyGrid;
use shift_proto::{PlanDocument, PlanEvent, PlanRequest, PlanStatus};

use super::{Command, Engine, JobOutcome};
use crate::error::{EngineError, Result};
use crate::job::PlanJob;
use crate::plan::PlanRecord;
use crate::request::validate;
use crate::robots::Assignment;
use crate::site::{LoadedSite, Site};

impl Engine {
    pub(super) fn request(&mut self, request: PlanRequest, now_ms: u64, out: &mut Vec<Command>) -> Result<()> {
        let grid = self.site_taking_jobs(&request.site)?;
        validate(&request, &grid)?;
        self.queue_room()?;
        let seq = self.take_seq();
        let rec = PlanRecord::queued(format!("p-{seq}"), seq, request, now_ms);
        self.queue.push_back(rec.plan_id.clone());
        out.push(Command::StorePlan(rec.clone()));
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        self.plans.insert(rec.plan_id.clone(), rec);
        self.retain(out);
        Ok(())
    }

    /// The grid of `site` when the engine takes new jobs there: not draining, a valid name (a name that breaks
    /// the rule is a bad request, not an unknown site), a known site.
    pub(super) fn site_taking_jobs(&self, site: &str) -> Result<Arc<OccupancyGrid>> {
        if self.draining {
            return Err(EngineError::ShuttingDown);
        }
        crate::site::validate_site_name(site)?;
        let s = self
            .sites
            .get(site)
            .ok_or_else(|| EngineError::UnknownSite(site.to_owned()))?;
        Ok(s.map.grid.clone())
    }

    /// Room for one more job in the queue.
    pub(super) fn queue_room(&self) -> Result<()> {
        if self.queue.len() >= self.config.queue_capacity {
            return Err(EngineError::QueueFull {
                capacity: self.config.queue_capacity,
            });
        }
        Ok(())
    }

    /// The next acceptance number (plan and mission ids come from it).
    pub(super) fn take_seq(&mut self) -> u64 {
        let seq = self.next_seq;
        self.next_seq += 1;
        seq
    }

    /// Forgets the oldest settled plans beyond `retain_plans` (settled: not queued, planning or driven).
    pub(super) fn retain(&mut self, out: &mut Vec<Command>) {
        if self.plans.len() <= self.config.retain_plans {
            return;
        }
        let mut settled: Vec<(u64, String)> = self
            .plans
            .values()
            .filter(|r| !matches!(r.status, PlanStatus::Queued | PlanStatus::Planning | PlanStatus::Active))
            // A part of a mission still under way stays with it.
            .filter(|r| {
                (r.mission.as_ref())
                    .and_then(|m| self.missions.get(m))
                    .is_none_or(|m| m.record.status.is_settled())
            })
            .map(|r| (r.seq, r.plan_id.clone()))
            .collect();
        let excess = settled.len().saturating_sub(self.config.retain_plans);
        if excess == 0 {
            return;
        }
        settled.sort_unstable();
        for (_, plan_id) in settled.into_iter().take(excess) {
            self.plans.remove(&plan_id);
            out.push(Command::ForgetPlan { plan_id });
        }
    }

    pub(super) fn cancel(&mut self, plan_id: &str, now_ms: u64, out: &mut Vec<Command>) -> Result<()> {
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

    pub(super) fn finished(&mut self, plan_id: &str, outcome: JobOutcome, now_ms: u64, out: &mut Vec<Command>) {
        self.running.remove(plan_id);
        let Some(rec) = self.plans.get_mut(plan_id) else { return };
        if rec.status != PlanStatus::Planning {
            return; // cancelled meanwhile: the outcome is moot
        }
        rec.updated_ms = now_ms;
        match outcome {
            JobOutcome::Planned { mut doc, warnings } => {
                // Terrain sites: each waypoint's z is the ground under it.
                if let Some(e) = self.sites.get(&rec.request.site).and_then(|s| s.map.elevation.as_ref()) {
                    crate::terrain_site::set_ground_height(e, &mut Arc::make_mut(&mut doc).waypoints);
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
            JobOutcome::Failed { reason } => {
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

    pub(super) fn restore(
        &mut self,
        sites: Vec<LoadedSite>,
        plans: Vec<PlanRecord>,
        active: Vec<Arc<PlanDocument>>,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
        for site in sites {
            let site = Site::from(site);
            out.push(Command::SiteChanged(site.summary()));
            out.push(Command::SiteStatic {
                site: site.record.site.clone(),
                clearance: site.map.clearance.clone(),
                grid: site.map.grid.clone(),
                ground: site.map.elevation.clone(),
            });
            self.sites.insert(site.record.site.clone(), Arc::new(site));
        }
        let mut plans = plans;
        plans.sort_by_key(|r| r.seq);
        for mut rec in plans {
            self.next_seq = self.next_seq.max(rec.seq + 1);
            if matches!(rec.status, PlanStatus::Queued | PlanStatus::Planning) {
                rec.updated_ms = now_ms;
                rec.progress = 0.0;
                if rec.mission.is_some() {
                    // Its mission's job plans it again (restore_missions re-queues the mission).
                    rec.status = PlanStatus::Queued;
                } else if self.sites.contains_key(&rec.request.site) {
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
        // Robots get back the plans they were driving, at the version last committed; their first odometry
        // finds them along it (progress re-acquisition).
        for doc in active {
            let Some(rec) = self.plans.get(&doc.plan_id) else {
                continue;
            };
            let (PlanStatus::Active, Some(robot)) = (rec.status, rec.robot.clone()) else {
                continue;
            };
            let plan_id = doc.plan_id.clone();
            let r = self.robots.entry(&robot, now_ms);
            r.assignment = Some(Assignment::new(plan_id, doc));
            r.assigned_ms = now_ms;
            self.route(&robot, out);
        }
        // A smaller `retain_plans` than the last run's takes effect at once.
        self.retain(out);
    }

    /// Starts queued jobs while workers are free.
    pub(super) fn pump(&mut self, now_ms: u64, out: &mut Vec<Command>) {
        while !self.draining && self.running.len() < self.config.workers {
            let Some(id) = self.queue.pop_front() else { break };
            if self.missions.contains_key(&id) {
                self.start_mission(&id, now_ms, out);
                continue;
            }
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
