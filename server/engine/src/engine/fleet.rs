//! Robots: presence, assignment and the routing of their sensor data that follows it, progress along the plan
//! (with re-acquisition), whether a watched plan is blind, and when a robot's path is checked.

use std::sync::Arc;

use shift_proto::{
    CorrectionDoc, CorrectionReason, LastCorrection, PlanDocument, PlanEvent, PlanStatus, ProgressJump, WatchHealth,
};

use super::{Command, Engine};
use crate::error::{EngineError, Result};
use crate::plan::MAX_JUMPS;
use crate::progress::Advance;
use crate::robots::{Assignment, Pose2};
use crate::site::validate_name;
use crate::watch::{CheckJob, CheckOutcome, PatchLimits, ProposedCorrection, Trigger};

/// Motion shorter than this between two poses says nothing about the heading, metres.
const MIN_MOTION_M: f64 = 0.05;
/// Motion longer than this between two poses is a jump (relocalisation), not driving, metres.
const MAX_MOTION_M: f64 = 2.0;

impl Engine {
    pub(super) fn liveliness(&mut self, robot: &str, alive: bool, now_ms: u64, out: &mut Vec<Command>) {
        let r = self.robots.entry(robot, now_ms);
        r.gone = !alive && (r.alive || r.gone);
        r.alive = alive;
        // Lost keeps the time of its last message; a robot that comes back was seen now.
        if alive {
            r.last_seen_ms = now_ms;
        }
        self.robot_changed(robot, out);
    }

    /// Tells the daemon which site `robot`'s sensor data feeds now.
    pub(super) fn route(&mut self, robot: &str, out: &mut Vec<Command>) {
        let site = self
            .robots
            .get(robot)
            .and_then(|r| r.assignment.as_ref())
            .and_then(|a| self.plans.get(&a.plan_id))
            .map(|p| p.request.site.clone());
        out.push(Command::FeedSite {
            robot: robot.to_owned(),
            site,
        });
    }

    pub(super) fn assign(
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
        if let Some(prev) = rec.robot.clone().filter(|prev| prev != robot) {
            self.robots.entry(&prev, now_ms).assignment = None;
            self.route(&prev, out);
            self.robot_changed(&prev, out);
        }
        let Some(rec) = self.plans.get_mut(plan_id) else {
            return Err(EngineError::UnknownPlan(plan_id.to_owned()));
        };
        rec.status = PlanStatus::Active;
        rec.robot = Some(robot.to_owned());
        rec.driven_fraction = 0.0;
        rec.watch = Some(WatchHealth::Watching);
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
            old_rec.watch = None;
            old_rec.updated_ms = now_ms;
            out.push(Command::StorePlan(old_rec.clone()));
            out.push(Command::Publish(PlanEvent::Status(old_rec.to_response())));
        }
        r.assignment = Some(Assignment::new(plan_id.to_owned(), doc.clone()));
        r.assigned_ms = now_ms;
        // A blockage held on the old plan says nothing of the new one.
        r.watch.end_proposed_since_ms = None;
        out.push(Command::PublishPlan {
            robot: robot.to_owned(),
            doc,
        });
        self.route(robot, out);
        self.robot_changed(robot, out);
        self.check(robot, Trigger::MapChange, now_ms, out);
        Ok(())
    }

    pub(super) fn pose(&mut self, robot: &str, pose: Pose2, now_ms: u64, out: &mut Vec<Command>) {
        if !(pose.x.is_finite() && pose.y.is_finite() && pose.yaw.is_finite()) {
            return;
        }
        let params = self.config.progress;
        let r = self.robots.entry(robot, now_ms);
        // The direction of motion where the robot moved enough to tell, else its yaw.
        let heading = match r.pose {
            Some(prev) => {
                let d = (pose.x - prev.x).hypot(pose.y - prev.y);
                if (MIN_MOTION_M..=MAX_MOTION_M).contains(&d) {
                    (pose.y - prev.y).atan2(pose.x - prev.x)
                } else {
                    pose.yaw
                }
            }
            None => pose.yaw,
        };
        let prev = r.pose.replace(pose);
        r.last_seen_ms = now_ms;
        let mut reacquired = false;
        if let Some(a) = r.assignment.as_mut() {
            let advance = a.advance(pose.x, pose.y, Some(heading), &params);
            if advance != Advance::Stayed
                && let Some(rec) = self.plans.get_mut(&a.plan_id)
            {
                rec.driven_fraction = a.fraction();
                rec.updated_ms = now_ms;
                let mut changed = false;
                if let Advance::Reacquired { from, to } = advance {
                    rec.progress_jumps.push(ProgressJump {
                        from_m: a.arc_at(from),
                        to_m: a.arc_at(to),
                        backwards: to < from,
                        at_ms: now_ms,
                    });
                    let excess = rec.progress_jumps.len().saturating_sub(MAX_JUMPS);
                    rec.progress_jumps.drain(..excess);
                    changed = true;
                    reacquired = true;
                }
                if a.finished() && rec.status == PlanStatus::Active {
                    rec.status = PlanStatus::Done;
                    rec.watch = None;
                    out.push(Command::StorePlan(rec.clone()));
                    changed = true;
                } else {
                    out.push(Command::UpdatePlan(rec.clone()));
                }
                if changed {
                    out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
                }
            }
        }
        self.sweep(robot, prev, pose, now_ms);
        self.watch_health(robot, now_ms, out);
        self.robot_changed(robot, out);
        let Some(r) = self.robots.get(robot) else { return };
        // A robot found elsewhere on its plan has a new window ahead: look at it now.
        let due = reacquired || r.watch.last_check_ms + self.config.watch.check_interval_ms <= now_ms;
        if due {
            self.check(robot, Trigger::Pose, now_ms, out);
        }
    }

    /// Robots' points reached `site`'s live map: plans watched there see again.
    pub(super) fn site_fed(&mut self, site: &str, now_ms: u64, out: &mut Vec<Command>) {
        let Some(s) = self.sites.get_mut(site) else { return };
        Arc::make_mut(s).last_fed_ms = now_ms;
        let robots: Vec<String> = self
            .robots
            .iter()
            .filter(|r| r.assignment.is_some())
            .map(|r| r.id.clone())
            .collect();
        for robot in robots {
            self.watch_health(&robot, now_ms, out);
        }
    }

    /// Flags `robot`'s plan `blind` when its site's live map got no points for `blind_after_ms` while the robot
    /// is alive, `blocked` while a check's proposal to end the plan is held, and `watching` otherwise.
    fn watch_health(&mut self, robot: &str, now_ms: u64, out: &mut Vec<Command>) {
        let Some(r) = self.robots.get(robot) else { return };
        let Some(a) = &r.assignment else { return };
        let Some(rec) = self.plans.get_mut(&a.plan_id) else {
            return;
        };
        if rec.status != PlanStatus::Active {
            return;
        }
        let fed_ms = self.sites.get(&rec.request.site).map_or(0, |s| s.last_fed_ms);
        let since = fed_ms.max(r.assigned_ms);
        let blind = r.alive && now_ms.saturating_sub(since) > self.config.blind_after_ms;
        let want = if blind {
            WatchHealth::Blind
        } else if r.watch.end_proposed_since_ms.is_some() {
            WatchHealth::Blocked
        } else {
            WatchHealth::Watching
        };
        if rec.watch != Some(want) {
            rec.watch = Some(want);
            rec.updated_ms = now_ms;
            out.push(Command::UpdatePlan(rec.clone()));
            out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
        }
    }

    /// Robots of `site` whose detection window reaches the changed box get checked now.
    pub(super) fn map_changed(
        &mut self,
        site: &str,
        min: [f64; 2],
        max: [f64; 2],
        now_ms: u64,
        out: &mut Vec<Command>,
    ) {
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
    pub(super) fn check(&mut self, robot: &str, trigger: Trigger, now_ms: u64, out: &mut Vec<Command>) {
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
        let spec = &rec.request.robot;
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
            params: self.config.watch.correct_params_for(spec),
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
    pub(super) fn check_finished(
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
        let held = match &outcome {
            CheckOutcome::Correct(p) if current => {
                let len = r.assignment.as_ref().map_or(0, |a| a.doc.waypoints.len());
                if ends_plan(p, len) {
                    let since = *r.watch.end_proposed_since_ms.get_or_insert(now_ms);
                    let hold_ms = (self.config.watch.end_hold_s.max(0.0) * 1e3) as u64;
                    now_ms.saturating_sub(since) < hold_ms
                } else {
                    r.watch.end_proposed_since_ms = None;
                    false
                }
            }
            CheckOutcome::Clear => {
                r.watch.end_proposed_since_ms = None;
                false
            }
            _ => false,
        };
        match outcome {
            // Held: the blockage may walk on; the next check looks again.
            CheckOutcome::Correct(_) if held => {}
            CheckOutcome::Correct(p) if current => {
                r.watch.end_proposed_since_ms = None;
                let Some(a) = r.assignment.as_mut() else { return };
                let Some(rec) = self.plans.get_mut(plan_id) else { return };
                // No longer held: the record stored and published with the correction says so.
                if rec.watch == Some(WatchHealth::Blocked) {
                    rec.watch = Some(WatchHealth::Watching);
                }
                let mut waypoints = p.waypoints;
                if let Some(e) = self.sites.get(&rec.request.site).and_then(|s| s.map.elevation.as_ref()) {
                    crate::terrain_site::set_ground_height(e, &mut waypoints);
                }
                let correction = CorrectionDoc {
                    plan_id: plan_id.to_owned(),
                    robot: robot.to_owned(),
                    base_version,
                    version: base_version + 1,
                    from: p.from,
                    to: p.to,
                    waypoints,
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
                // The plan's status (version, corrections, missed) changed too.
                out.push(Command::Publish(PlanEvent::Status(rec.to_response())));
                self.robot_changed(robot, out);
                // The window may hold another breach: look again at once.
                again = true;
            }
            // Stale (the plan moved on meanwhile): the new version needs its own look.
            CheckOutcome::Correct(_) => again = true,
            CheckOutcome::Clear | CheckOutcome::Failed(_) => {}
        }
        // A hold began or ended: the plan's status says so.
        self.watch_health(robot, now_ms, out);
        if again {
            self.check(robot, Trigger::MapChange, now_ms, out);
        }
    }
}

/// A proposal that ends the plan where the robot is: a skip with nothing beyond the blockage to rejoin (the
/// rest of the plan replaced by the anchor alone).
fn ends_plan(p: &ProposedCorrection, len: usize) -> bool {
    p.reason == CorrectionReason::Skipped && p.to == len && p.waypoints.len() <= 1
}
