//! Replanning a mission's remainder (issue 20): on request, when a robot of an active mission is lost (its
//! liveliness gone, or silent past `robot_timeout_s`) and when it comes back, and after a restart with a
//! mission under way. What the robots' tools swept (the mission's measured raster) is left out; what is left
//! is divided among the robots taking part, each from where it is, and each robot's plan gets a new version
//! (a plan update, not a correction: the whole path is new; the versioning rules are the same, so a robot
//! that missed it finds it by querying its plan).

use std::sync::Arc;

use shift_proto::{MissionRobot, MissionStatus, PlanDocument, PlanEvent, PlanStatus, WatchHealth};

use super::{Command, Engine};
use crate::error::{EngineError, Result};
use crate::mission::{MissionPlanned, ReplanOrder};
use crate::mission_job::{LostPlan, MissionJob, PlannedPart};
use crate::plan::PlanRecord;
use crate::request::ParsedOptions;
use crate::robots::Assignment;

impl Engine {
    /// Asks for a replan of what `mission_id` has left (a worker picks it up; the robots drive on meanwhile).
    pub(super) fn request_replan(
        &mut self,
        mission_id: &str,
        reason: String,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) -> Result<()> {
        let m = self
            .missions
            .get_mut(mission_id)
            .ok_or_else(|| EngineError::UnknownMission(mission_id.to_owned()))?;
        let planned = m.record.planned.is_some() && m.raster.is_some();
        if !planned || matches!(m.record.status, MissionStatus::Cancelled | MissionStatus::Done) {
            return Err(EngineError::MissionState {
                mission_id: mission_id.to_owned(),
                status: m.record.status,
                action: "replan",
            });
        }
        match m.record.replan.as_mut() {
            Some(order) if order.running.is_some() => order.again = true,
            Some(order) => {
                order.reason = format!("{}; {reason}", order.reason);
                // Left waiting when nobody could take part (every robot lost): queued again now.
                if !self.queue.iter().any(|id| id == mission_id) {
                    self.queue.push_back(mission_id.to_owned());
                }
            }
            None => {
                m.record.replan = Some(ReplanOrder {
                    reason,
                    running: None,
                    again: false,
                });
                self.queue.push_back(mission_id.to_owned());
            }
        }
        m.record.updated_ms = now_ms;
        m.dirty = true;
        out.push(Command::StoreMission(m.record.clone()));
        Ok(())
    }

    /// Robot `robot` joins mission `mission_id`: checked as a mission's robots are (`robots[n]` in messages, n
    /// its place after the others), given a plan of the mission, and a replan gives it a balanced share of what
    /// is left (each from where it stands). It drives at once when the mission is under way; a mission not yet
    /// assigned gets it at its assignment; a queued mission simply plans with it.
    pub(super) fn join_mission(
        &mut self,
        mission_id: &str,
        robot: MissionRobot,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) -> Result<()> {
        let m = self
            .missions
            .get(mission_id)
            .ok_or_else(|| EngineError::UnknownMission(mission_id.to_owned()))?;
        let status = m.record.status;
        let planned = m.record.planned.is_some();
        if !(status == MissionStatus::Queued
            || (planned && matches!(status, MissionStatus::Ready | MissionStatus::Active)))
        {
            return Err(EngineError::MissionState {
                mission_id: mission_id.to_owned(),
                status,
                action: "take a robot",
            });
        }
        let mut request = m.record.request.clone();
        request.robots.push(robot.clone());
        let site = self
            .sites
            .get(&request.site)
            .ok_or_else(|| EngineError::UnknownSite(request.site.clone()))?;
        crate::mission::validate_mission(&request, &site.map.grid)?;
        let n = request.robots.len() - 1;
        let plan_request = crate::mission::MissionRecord::plan_request(&request, n)
            .ok_or_else(|| EngineError::InvalidRequest("robots: the new robot is missing".into()))?;
        let seq = self.take_seq();
        let mut rec = PlanRecord {
            mission: Some(mission_id.to_owned()),
            ..PlanRecord::queued(format!("p-{seq}"), seq, plan_request, now_ms)
        };
        if status == MissionStatus::Active {
            // Its share is delivered to it as soon as the replan ends.
            rec.robot = Some(robot.id.clone());
        }
        out.push(Command::StorePlan(rec.clone()));
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        let plan_id = rec.plan_id.clone();
        self.plans.insert(plan_id.clone(), rec);
        let Some(m) = self.missions.get_mut(mission_id) else {
            return Ok(());
        };
        m.record.request = request;
        m.record.plan_ids.push(plan_id);
        m.record.updated_ms = now_ms;
        m.dirty = true;
        out.push(Command::StoreMission(m.record.clone()));
        if status != MissionStatus::Queued {
            // (A queued mission's job plans the robot with the others.)
            self.request_replan(mission_id, format!("robot {} joined", robot.id), now_ms, out)?;
        }
        // The caller's answer shows the robot at once.
        self.push_mission_view(mission_id, now_ms, out);
        Ok(())
    }

    /// True when robot `id` was seen and is gone: its token left (for robots without one, the daemon's
    /// presence tracking says the same when their messages stop), or it sent odometry and has been silent past
    /// `robot_timeout_s`. A robot never heard of is not lost: it may not have connected yet.
    fn robot_lost(&self, id: &str, now_ms: u64) -> bool {
        self.robots.get(id).is_some_and(|r| {
            r.gone || (r.pose.is_some() && now_ms.saturating_sub(r.last_seen_ms) > self.config.blind_after_ms)
        })
    }

    /// Robots of active missions lost while driving, and dropped robots back: replans.
    pub(super) fn watch_mission_robots(&mut self, now_ms: u64, out: &mut Vec<Command>) {
        let mut orders: Vec<(String, String, Option<String>, Option<String>)> = Vec::new();
        for (id, m) in &self.missions {
            // Active, or failed because every robot was lost (one coming back picks the mission up again).
            let lost_all = m.record.status == MissionStatus::Failed && !m.record.dropped.is_empty();
            if !(m.record.status == MissionStatus::Active || lost_all) {
                continue;
            }
            for (plan_id, r) in m.record.plan_ids.iter().zip(&m.record.request.robots) {
                let dropped = m.record.dropped.contains(&r.id);
                let lost = self.robot_lost(&r.id, now_ms);
                let driving = self
                    .plans
                    .get(plan_id)
                    .is_some_and(|p| p.status == PlanStatus::Active && p.robot.as_deref() == Some(r.id.as_str()));
                if !dropped && lost && driving {
                    orders.push((id.clone(), format!("robot {} lost", r.id), Some(r.id.clone()), None));
                } else if dropped && !lost && self.robots.get(&r.id).is_some_and(|x| x.alive) {
                    orders.push((
                        id.clone(),
                        format!("robot {} came back", r.id),
                        None,
                        Some(r.id.clone()),
                    ));
                }
            }
        }
        for (mission_id, reason, drop, back) in orders {
            if let Some(m) = self.missions.get_mut(&mission_id) {
                if let Some(r) = drop {
                    m.record.dropped.push(r);
                }
                if let Some(r) = back {
                    m.record.dropped.retain(|d| *d != r);
                }
            }
            // A mission with nobody left keeps its state; the next robot back replans it.
            let _ = self.request_replan(&mission_id, reason, now_ms, out);
        }
    }

    /// The plan `plan_id` robot `robot` drives (when it does) and the last waypoint it reached on it. Without
    /// odometry since a restart, progress is still at the start: the record's driven fraction (committed with
    /// the plan) says where along the plan the robot was.
    fn driven_on(&self, robot: &str, plan_id: &str) -> Option<(Arc<PlanDocument>, usize)> {
        let fraction = self.plans.get(plan_id).map_or(0.0, |p| p.driven_fraction);
        let a = (self.robots.get(robot))
            .and_then(|x| x.assignment.as_ref())
            .filter(|a| a.plan_id == plan_id && !a.doc.waypoints.is_empty())?;
        let total = a.arc_m.last().copied().unwrap_or(0.0);
        let at = a.arc_m.partition_point(|&s| s < fraction * total).max(a.index);
        Some((a.doc.clone(), at.min(a.doc.waypoints.len() - 1)))
    }

    /// Starts a queued replan's job (called by the pump with a free worker).
    pub(super) fn start_replan(&mut self, mission_id: &str, now_ms: u64, out: &mut Vec<Command>) {
        let lost: Vec<String> = self.missions.get(mission_id).map_or_else(Vec::new, |m| {
            (m.record.request.robots.iter())
                .filter(|r| m.record.dropped.contains(&r.id))
                .map(|r| r.id.clone())
                .collect()
        });
        let Some(m) = self.missions.get(mission_id) else { return };
        let Some(order) = m.record.replan.clone() else { return };
        if order.running.is_some() {
            return;
        }
        let Some(site) = self.sites.get(&m.record.request.site) else {
            return;
        };
        let options: Option<ParsedOptions> = crate::mission::validate_mission(&m.record.request, &site.map.grid).ok();
        let (Some(options), Some(raster)) = (options, m.raster.as_ref()) else {
            return;
        };
        // The robots taking part, each from where it is: its last pose when it is driving, else where its plan
        // says it is (after a restart, before its first odometry), else its dock.
        let mut request = m.record.request.clone();
        let mut plan_ids = Vec::new();
        let mut taking = Vec::new();
        let mut previous = Vec::new();
        request.robots.clear();
        for (plan_id, r) in m.record.plan_ids.iter().zip(&m.record.request.robots) {
            if lost.contains(&r.id) {
                continue;
            }
            let mut r = r.clone();
            let at_pose = self.robots.get(&r.id).and_then(|x| x.pose).map(|p| [p.x, p.y]);
            let driving = self.driven_on(&r.id, plan_id);
            let on_plan = driving
                .as_ref()
                .map(|(doc, at)| [doc.waypoints[*at].x, doc.waypoints[*at].y]);
            if let Some(p) = at_pose.or(on_plan).filter(|p| p[0].is_finite() && p[1].is_finite()) {
                r.start = p;
            }
            previous.push(driving);
            taking.push(r.id.clone());
            plan_ids.push(plan_id.clone());
            request.robots.push(r);
        }
        if request.robots.is_empty() {
            return;
        }
        // A robot lost with its plan unfinished: the plan it was driving and where it was on it, so that its
        // lanes go to the others with their own plans resumed; without that plan (not driving it when lost),
        // only a new division gives its ground out.
        let unfinished = |plan_id: &String| {
            self.plans
                .get(plan_id)
                .is_some_and(|p| matches!(p.status, PlanStatus::Active | PlanStatus::Ready))
        };
        let mut lost_plans = Vec::new();
        let mut whole = true;
        for (plan_id, r) in m.record.plan_ids.iter().zip(&m.record.request.robots) {
            if !(lost.contains(&r.id) && unfinished(plan_id)) {
                continue;
            }
            match self.driven_on(&r.id, plan_id) {
                Some((doc, reached)) => lost_plans.push(LostPlan {
                    robot: r.clone(),
                    doc,
                    reached,
                }),
                None => whole = false,
            }
        }
        if !whole {
            previous.clear();
            lost_plans.clear();
        }
        let covered = Arc::new(raster.covered().to_vec());
        let grid = site.map.grid.clone();
        let Some(m) = self.missions.get_mut(mission_id) else {
            return;
        };
        if let Some(o) = m.record.replan.as_mut() {
            o.running = Some(taking);
        }
        m.record.attempts += 1;
        m.record.updated_ms = now_ms;
        self.running.insert(mission_id.to_owned());
        out.push(Command::StoreMission(m.record.clone()));
        out.push(Command::StartMission(Box::new(MissionJob {
            mission_id: mission_id.to_owned(),
            plan_ids,
            grid,
            request,
            options,
            overlay: Vec::new(),
            covered: Some(covered),
            previous,
            lost: lost_plans,
        })));
    }

    /// A replan's plans: each robot taking part gets its plan's next version, delivered at once to a robot
    /// driving it (or that finished it); the plans of dropped robots are cancelled.
    pub(super) fn replanned(
        &mut self,
        mission_id: &str,
        parts: Vec<PlannedPart>,
        planned: MissionPlanned,
        warnings: Vec<String>,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
        let Some(m) = self.missions.get_mut(mission_id) else {
            return;
        };
        let Some(order) = m.record.replan.take() else { return };
        let taking = order.running.clone().unwrap_or_default();
        m.record.replans += 1;
        m.record.warnings.extend(warnings);
        m.record.warnings.push(format!(
            "replanned what was left ({}) for {}",
            order.reason,
            taking.join(", ")
        ));
        if let Some(p) = m.record.planned.as_mut() {
            // Coverage still counts against the mission's first division; the parts' areas are the new ones.
            p.areas_m2.resize(m.record.request.robots.len(), 0.0);
            for (i, r) in m.record.request.robots.iter().enumerate() {
                let k = taking.iter().position(|t| *t == r.id);
                if let Some(a) = p.areas_m2.get_mut(i) {
                    *a = k.and_then(|k| planned.areas_m2.get(k)).copied().unwrap_or(0.0);
                }
            }
        }
        let pairs: Vec<(String, String)> = (m.record.plan_ids.iter().zip(&m.record.request.robots))
            .map(|(p, r)| (p.clone(), r.id.clone()))
            .collect();
        let dropped = m.record.dropped.clone();
        let again = order.again;
        let reason = order.reason;
        let mut parts = parts.into_iter();
        for (plan_id, robot) in pairs {
            if taking.contains(&robot) {
                let Some(part) = parts.next() else { break };
                // Lost while the replan ran: its share waits for the replan that loss asked for.
                if dropped.contains(&robot) {
                    self.drop_plan(&plan_id, &robot, now_ms, out);
                } else {
                    self.replace_plan(&plan_id, &robot, part, &reason, now_ms, out);
                }
            } else if dropped.contains(&robot) {
                self.drop_plan(&plan_id, &robot, now_ms, out);
            }
        }
        if let Some(m) = self.missions.get_mut(mission_id) {
            let next = m.record.status_from_plans(&self.plans);
            if matches!(
                m.record.status,
                MissionStatus::Ready | MissionStatus::Active | MissionStatus::Failed
            ) {
                m.record.status = next;
                m.record.error = None;
            }
            m.record.updated_ms = now_ms;
            out.push(Command::StoreMission(m.record.clone()));
        }
        if again {
            let _ = self.request_replan(mission_id, "the fleet changed while replanning".into(), now_ms, out);
        }
    }

    /// Gives plan `plan_id` of `robot` the replan's document as its next version.
    fn replace_plan(
        &mut self,
        plan_id: &str,
        robot: &str,
        part: PlannedPart,
        reason: &str,
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
        let Some(rec) = self.plans.get_mut(plan_id) else { return };
        let version = rec.version + 1;
        let mut doc = (*part.doc).clone();
        doc.plan_id = plan_id.to_owned();
        doc.version = version;
        let doc = Arc::new(doc);
        rec.version = version;
        rec.metrics = Some(doc.metrics);
        rec.driven_fraction = 0.0;
        rec.missed.clear();
        rec.updated_ms = now_ms;
        rec.warnings
            .push(format!("version {version} replans what was left ({reason})"));
        // Assigned to it once (driving it, finished it, or its plan was cancelled when it was lost and it came
        // back): the new version goes to it. A plan never assigned stays ready.
        let driven_by_it = rec.robot.as_deref() == Some(robot);
        if driven_by_it {
            rec.status = PlanStatus::Active;
            rec.watch = Some(WatchHealth::Watching);
        } else if rec.status != PlanStatus::Ready {
            // Never driven (a robot that joined a mission not yet assigned), or ended: ready for assignment.
            rec.status = PlanStatus::Ready;
            rec.robot = None;
        }
        out.push(Command::ReplacePlanDoc {
            record: rec.clone(),
            doc: doc.clone(),
        });
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        if driven_by_it {
            let r = self.robots.entry(robot, now_ms);
            let mut a = Assignment::new(plan_id.to_owned(), doc.clone());
            a.await_start = true;
            r.assignment = Some(a);
            r.assigned_ms = now_ms;
            r.watch.end_proposed_since_ms = None;
            out.push(Command::PublishPlan {
                robot: robot.to_owned(),
                doc,
            });
            self.route(robot, out);
            self.robot_changed(robot, out);
        }
    }

    /// Ends the plan of a robot whose part went to the others.
    fn drop_plan(&mut self, plan_id: &str, robot: &str, now_ms: u64, out: &mut Vec<Command>) {
        let Some(rec) = self.plans.get_mut(plan_id) else { return };
        if !matches!(rec.status, PlanStatus::Active | PlanStatus::Ready) {
            return;
        }
        rec.status = PlanStatus::Cancelled;
        rec.watch = None;
        rec.updated_ms = now_ms;
        rec.warnings
            .push(format!("robot {robot} was lost; what it had left went to the others"));
        out.push(Command::StorePlan(rec.clone()));
        out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        if let Some(r) = self.robots.get_mut(robot)
            && r.assignment.as_ref().is_some_and(|a| a.plan_id == plan_id)
        {
            r.assignment = None;
            self.route(robot, out);
            self.robot_changed(robot, out);
        }
    }
}
