//! Missions: requests, the mission job's end, assignment of every part, cancels, and the mission's view as its
//! plans move; and the measured coverage the robots' tools sweep (per site and per mission), committed at
//! intervals.

use std::sync::Arc;

use shift_proto::{MissionRequest, MissionStatus, PlanDocument, PlanEvent, PlanStatus};

use super::{Command, Engine, JobOutcome};
use crate::coverage::{CoverageKey, CoverageRecord, Raster};
use crate::error::{EngineError, Result};
use crate::mission::{MissionRecord, MissionState, validate_mission};
use crate::mission_job::{MissionJob, MissionOutcome};
use crate::plan::PlanRecord;

/// A mission's view is pushed at most this often while only its progress moves, milliseconds.
pub(super) const VIEW_EVERY_MS: u64 = 1_000;

impl Engine {
    pub(super) fn request_mission(
        &mut self,
        request: MissionRequest,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) -> Result<()> {
        let grid = self.site_taking_jobs(&request.site)?;
        validate_mission(&request, &grid)?;
        self.queue_room()?;
        let seq = self.take_seq();
        let mission_id = format!("m-{seq}");
        let mut plan_ids = Vec::with_capacity(request.robots.len());
        for i in 0..request.robots.len() {
            let Some(plan_request) = MissionRecord::plan_request(&request, i) else {
                continue;
            };
            let seq = self.take_seq();
            let rec = PlanRecord {
                mission: Some(mission_id.clone()),
                ..PlanRecord::queued(format!("p-{seq}"), seq, plan_request, now_ms)
            };
            plan_ids.push(rec.plan_id.clone());
            out.push(Command::StorePlan(rec.clone()));
            out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
            self.plans.insert(rec.plan_id.clone(), rec);
        }
        let record = MissionRecord {
            mission_id: mission_id.clone(),
            seq,
            request,
            status: MissionStatus::Queued,
            progress: 0.0,
            plan_ids,
            planned: None,
            error: None,
            warnings: Vec::new(),
            attempts: 0,
            dropped: Vec::new(),
            replan: None,
            replans: 0,
            created_ms: now_ms,
            updated_ms: now_ms,
        };
        out.push(Command::StoreMission(record.clone()));
        self.queue.push_back(mission_id.clone());
        self.missions.insert(
            mission_id.clone(),
            MissionState {
                record,
                raster: None,
                view_ms: 0,
                dirty: true,
            },
        );
        self.push_mission_view(&mission_id, now_ms, out);
        Ok(())
    }

    /// Missions and rasters read back at start-up (after the plans): missions being planned are queued again,
    /// their plans with them; measured rasters are restored where they still fit their site's map.
    pub(super) fn restore_missions(
        &mut self,
        missions: Vec<MissionRecord>,
        coverage: Vec<CoverageRecord>,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
        let mut missions = missions;
        missions.sort_by_key(|m| m.seq);
        for mut record in missions {
            self.next_seq = self.next_seq.max(record.seq + 1);
            let geometry = self.sites.get(&record.request.site).map(|s| s.map.grid.geometry);
            if matches!(record.status, MissionStatus::Queued | MissionStatus::Planning) {
                record.progress = 0.0;
                record.updated_ms = now_ms;
                if geometry.is_some() {
                    record.status = MissionStatus::Queued;
                    record.warnings.push("re-queued after a restart".into());
                    self.queue.push_back(record.mission_id.clone());
                } else {
                    record.status = MissionStatus::Failed;
                    record.error = Some(format!(
                        "interrupted by a restart and site {:?} no longer exists",
                        record.request.site
                    ));
                }
                out.push(Command::StoreMission(record.clone()));
            }
            // A replan waiting or running when the daemon stopped runs again; a mission under way is replanned
            // from what was swept (its robots drove on, or stopped, while the daemon was away).
            if let Some(order) = record.replan.as_mut() {
                order.running = None;
                self.queue.push_back(record.mission_id.clone());
            } else if record.status == MissionStatus::Active && geometry.is_some() {
                record.replan = Some(crate::mission::ReplanOrder {
                    reason: "the daemon restarted".into(),
                    running: None,
                    again: false,
                });
                self.queue.push_back(record.mission_id.clone());
            }
            let key = CoverageKey::Mission(record.mission_id.clone());
            let raster = match (geometry, &record.planned) {
                (Some(g), Some(planned)) => {
                    let within = planned.coverable.decode(g.len()).ok().map(Arc::new);
                    let saved = coverage.iter().find(|c| c.key == key && c.fits(&g));
                    Some(Arc::new(match saved {
                        Some(c) => Raster::restore(g, within.clone(), c).unwrap_or_else(|_| Raster::new(g, within)),
                        None => Raster::new(g, within),
                    }))
                }
                _ => None,
            };
            let id = record.mission_id.clone();
            self.missions.insert(
                id.clone(),
                MissionState {
                    record,
                    raster,
                    view_ms: 0,
                    dirty: true,
                },
            );
            if self
                .missions
                .get(&id)
                .is_some_and(|m| m.record.status == MissionStatus::Failed)
            {
                self.fail_mission_plans(&id, now_ms, out);
            }
        }
        for c in coverage {
            let CoverageKey::Site(site) = &c.key else { continue };
            if let Some(g) = self.sites.get(site).map(|s| s.map.grid.geometry)
                && c.fits(&g)
                && let Ok(mut r) = Raster::restore(g, None, &c)
            {
                // Not to the store again, but to the read model.
                r.dirty_view = true;
                self.site_coverage.insert(site.clone(), Arc::new(r));
            }
        }
    }

    /// Starts a queued mission's job (called by the pump with a free worker).
    pub(super) fn start_mission(&mut self, mission_id: &str, now_ms: u64, out: &mut Vec<Command>) {
        let Some(m) = self.missions.get_mut(mission_id) else {
            return;
        };
        if m.record.replan.is_some() && m.record.status != MissionStatus::Queued {
            self.start_replan(mission_id, now_ms, out);
            return;
        }
        if m.record.status != MissionStatus::Queued {
            return;
        }
        m.record.updated_ms = now_ms;
        let checked = self
            .sites
            .get(&m.record.request.site)
            .ok_or_else(|| EngineError::UnknownSite(m.record.request.site.clone()))
            .and_then(|site| {
                Ok((
                    site.map.grid.clone(),
                    validate_mission(&m.record.request, &site.map.grid)?,
                ))
            });
        match checked {
            Ok((grid, options)) => {
                m.record.status = MissionStatus::Planning;
                m.record.attempts += 1;
                self.running.insert(mission_id.to_owned());
                out.push(Command::StoreMission(m.record.clone()));
                out.push(Command::StartMission(Box::new(MissionJob {
                    mission_id: mission_id.to_owned(),
                    plan_ids: m.record.plan_ids.clone(),
                    grid,
                    request: m.record.request.clone(),
                    options,
                    overlay: Vec::new(),
                    covered: None,
                    previous: Vec::new(),
                    lost: Vec::new(),
                })));
                let plan_ids = m.record.plan_ids.clone();
                for id in plan_ids {
                    if let Some(rec) = self.plans.get_mut(&id)
                        && rec.status == PlanStatus::Queued
                    {
                        rec.status = PlanStatus::Planning;
                        rec.attempts += 1;
                        rec.updated_ms = now_ms;
                        out.push(Command::StorePlan(rec.clone()));
                        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
                    }
                }
            }
            Err(e) => self.fail_mission(mission_id, e.to_string(), now_ms, out),
        }
        self.push_mission_view(mission_id, now_ms, out);
    }

    /// Fails a mission and every plan of it not yet planned.
    fn fail_mission(&mut self, mission_id: &str, reason: String, now_ms: u64, out: &mut Vec<Command>) {
        let Some(m) = self.missions.get_mut(mission_id) else {
            return;
        };
        m.record.status = MissionStatus::Failed;
        m.record.error = Some(reason);
        m.record.updated_ms = now_ms;
        m.dirty = true;
        out.push(Command::StoreMission(m.record.clone()));
        self.fail_mission_plans(mission_id, now_ms, out);
    }

    /// Fails the plans of a failed mission that were not yet planned.
    fn fail_mission_plans(&mut self, mission_id: &str, now_ms: u64, out: &mut Vec<Command>) {
        let Some(m) = self.missions.get(mission_id) else { return };
        let reason = m.record.error.clone().unwrap_or_default();
        for id in m.record.plan_ids.clone() {
            if let Some(rec) = self.plans.get_mut(&id)
                && matches!(rec.status, PlanStatus::Queued | PlanStatus::Planning)
            {
                rec.status = PlanStatus::Failed;
                rec.error = Some(format!("mission {mission_id} failed: {reason}"));
                rec.updated_ms = now_ms;
                out.push(Command::StorePlan(rec.clone()));
                out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
            }
        }
    }

    pub(super) fn mission_finished(
        &mut self,
        mission_id: &str,
        outcome: MissionOutcome,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
        self.running.remove(mission_id);
        let geometry = (self.missions.get(mission_id))
            .and_then(|m| self.sites.get(&m.record.request.site))
            .map(|s| s.map.grid.geometry);
        let Some(m) = self.missions.get_mut(mission_id) else {
            return;
        };
        if m.record.replan.as_ref().is_some_and(|o| o.running.is_some()) {
            match outcome {
                MissionOutcome::Planned {
                    parts,
                    planned,
                    warnings,
                } if m.record.status != MissionStatus::Cancelled => {
                    self.replanned(mission_id, parts, planned, warnings, now_ms, out);
                }
                MissionOutcome::Interrupted => {
                    if let Some(o) = m.record.replan.as_mut() {
                        o.running = None;
                    }
                    out.push(Command::StoreMission(m.record.clone()));
                    self.queue.push_front(mission_id.to_owned());
                }
                MissionOutcome::Failed { reason } => {
                    m.record.replan = None;
                    m.record
                        .warnings
                        .push(format!("the replan failed: {reason}; the plans stand"));
                    out.push(Command::StoreMission(m.record.clone()));
                }
                MissionOutcome::Planned { .. } => m.record.replan = None,
            }
            self.push_mission_view(mission_id, now_ms, out);
            return;
        }
        if m.record.status != MissionStatus::Planning {
            return; // cancelled meanwhile
        }
        m.record.updated_ms = now_ms;
        m.dirty = true;
        match outcome {
            MissionOutcome::Planned {
                parts,
                planned,
                warnings,
            } => {
                let within = geometry.and_then(|g| planned.coverable.decode(g.len()).ok());
                m.raster = geometry.map(|g| Arc::new(Raster::new(g, within.map(Arc::new))));
                m.record.planned = Some(planned);
                m.record.warnings.extend(warnings);
                m.record.progress = 1.0;
                let plan_ids = m.record.plan_ids.clone();
                for (plan_id, part) in plan_ids.iter().zip(parts) {
                    // Each part is settled as an ordinary plan's job end.
                    if self
                        .plans
                        .get(plan_id)
                        .is_some_and(|r| r.status == PlanStatus::Planning)
                    {
                        self.finished(
                            plan_id,
                            JobOutcome::Planned {
                                doc: part.doc,
                                warnings: part.warnings,
                            },
                            now_ms,
                            out,
                        );
                    }
                }
                if let Some(m) = self.missions.get_mut(mission_id) {
                    m.record.status = m.record.status_from_plans(&self.plans);
                    out.push(Command::StoreMission(m.record.clone()));
                }
            }
            MissionOutcome::Failed { reason } => self.fail_mission(mission_id, reason, now_ms, out),
            MissionOutcome::Interrupted => {
                m.record.status = MissionStatus::Queued;
                m.record.progress = 0.0;
                out.push(Command::StoreMission(m.record.clone()));
                for id in m.record.plan_ids.clone() {
                    if let Some(rec) = self.plans.get_mut(&id)
                        && rec.status == PlanStatus::Planning
                    {
                        rec.status = PlanStatus::Queued;
                        out.push(Command::StorePlan(rec.clone()));
                    }
                }
                self.queue.push_front(mission_id.to_owned());
            }
        }
        self.push_mission_view(mission_id, now_ms, out);
    }

    pub(super) fn assign_mission(
        &mut self,
        mission_id: &str,
        docs: Vec<Arc<PlanDocument>>,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) -> Result<()> {
        let m = self
            .missions
            .get(mission_id)
            .ok_or_else(|| EngineError::UnknownMission(mission_id.to_owned()))?;
        if !matches!(m.record.status, MissionStatus::Ready | MissionStatus::Active) {
            return Err(EngineError::MissionState {
                mission_id: mission_id.to_owned(),
                status: m.record.status,
                action: "assign",
            });
        }
        // Robots lost and divided away have no part to take.
        let pairs: Vec<(String, String)> = (m.record.plan_ids.iter().zip(&m.record.request.robots))
            .filter(|(_, r)| !m.record.dropped.contains(&r.id))
            .map(|(p, r)| (p.clone(), r.id.clone()))
            .collect();
        // All or nothing: every plan must take its robot before any does.
        for (plan_id, _) in &pairs {
            let status = self.plans.get(plan_id).map(|r| r.status);
            if !matches!(status, Some(PlanStatus::Ready | PlanStatus::Active)) {
                return Err(EngineError::InvalidState {
                    plan_id: plan_id.clone(),
                    status: status.unwrap_or(PlanStatus::Cancelled),
                    action: "assign",
                });
            }
            if !docs.iter().any(|d| &d.plan_id == plan_id) {
                return Err(EngineError::InvalidRequest(format!(
                    "no document of plan {plan_id} to assign"
                )));
            }
        }
        for (plan_id, robot) in pairs {
            let already = self
                .robots
                .get(&robot)
                .and_then(|r| r.assignment.as_ref())
                .is_some_and(|a| a.plan_id == plan_id);
            if already {
                continue;
            }
            if let Some(doc) = docs.iter().find(|d| d.plan_id == plan_id) {
                self.assign(&plan_id, &robot, doc.clone(), now_ms, out)?;
            }
        }
        self.refresh_mission(mission_id, now_ms, out);
        Ok(())
    }

    pub(super) fn cancel_mission(&mut self, mission_id: &str, now_ms: u64, out: &mut Vec<Command>) -> Result<()> {
        let m = self
            .missions
            .get_mut(mission_id)
            .ok_or_else(|| EngineError::UnknownMission(mission_id.to_owned()))?;
        if m.record.status.is_settled() {
            return Err(EngineError::MissionState {
                mission_id: mission_id.to_owned(),
                status: m.record.status,
                action: "cancel",
            });
        }
        match m.record.status {
            MissionStatus::Queued => self.queue.retain(|id| id != mission_id),
            MissionStatus::Planning => out.push(Command::CancelJob {
                plan_id: mission_id.to_owned(),
            }),
            _ => {}
        }
        m.record.status = MissionStatus::Cancelled;
        m.record.updated_ms = now_ms;
        m.dirty = true;
        out.push(Command::StoreMission(m.record.clone()));
        for id in m.record.plan_ids.clone() {
            let Some(rec) = self.plans.get_mut(&id) else { continue };
            match rec.status {
                PlanStatus::Queued | PlanStatus::Planning | PlanStatus::Ready => {
                    rec.status = PlanStatus::Cancelled;
                    rec.updated_ms = now_ms;
                    out.push(Command::StorePlan(rec.clone()));
                    out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
                }
                // A robot driving its part finishes it: stopping a robot mid-floor is the backend's call.
                _ => {}
            }
        }
        self.push_mission_view(mission_id, now_ms, out);
        Ok(())
    }

    /// Re-derives a planned mission's status from its plans and pushes its view when due.
    pub(super) fn refresh_mission(&mut self, mission_id: &str, now_ms: u64, out: &mut Vec<Command>) {
        let Some(m) = self.missions.get_mut(mission_id) else {
            return;
        };
        let status = m.record.status;
        let mut changed = false;
        if matches!(status, MissionStatus::Ready | MissionStatus::Active) {
            let next = m.record.status_from_plans(&self.plans);
            if next != status {
                m.record.status = next;
                m.record.updated_ms = now_ms;
                if next == MissionStatus::Failed {
                    m.record.error = Some("every plan ended and some were not driven to their end".into());
                }
                out.push(Command::StoreMission(m.record.clone()));
                changed = true;
            }
        }
        if changed || now_ms >= m.view_ms + VIEW_EVERY_MS {
            self.push_mission_view(mission_id, now_ms, out);
        }
    }

    pub(super) fn push_mission_view(&mut self, mission_id: &str, now_ms: u64, out: &mut Vec<Command>) {
        let Some(m) = self.missions.get_mut(mission_id) else {
            return;
        };
        let measured = m.raster.as_ref().map_or(0.0, |r| r.pct());
        m.view_ms = now_ms;
        m.dirty = false;
        out.push(Command::MissionChanged(m.record.to_view(&self.plans, measured)));
    }

    /// Missions whose plans changed in `out`, and with `scan_all` every mission swept since (its view's
    /// measured coverage moved): refresh them.
    pub(super) fn refresh_touched_missions(&mut self, now_ms: u64, scan_all: bool, out: &mut Vec<Command>) {
        let mut touched: Vec<String> = out
            .iter()
            .filter_map(|c| match c {
                Command::StorePlan(r) | Command::UpdatePlan(r) => r.mission.clone(),
                Command::StoreCorrection { record, .. } => record.mission.clone(),
                _ => None,
            })
            .collect();
        if scan_all {
            touched.extend(self.missions.iter().filter(|(_, m)| m.dirty).map(|(id, _)| id.clone()));
        }
        touched.sort_unstable();
        touched.dedup();
        for id in touched {
            self.refresh_mission(&id, now_ms, out);
        }
    }
}
