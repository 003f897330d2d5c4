//! The state machine: events in, commands out. The handlers are split by what they decide: plans and the job
//! queue (`plans.rs`), robots — routing, progress, path watching (`fleet.rs`); the vocabulary is in
//! `events.rs`.

mod events;
mod fleet;
mod missions;
mod plans;
mod replan;
mod sweep;

use std::sync::Arc;

use std::collections::{BTreeMap, HashMap, HashSet, VecDeque};

use shift_proto::{PlanEvent, PlanStatus, PoseView, RobotView, SiteSummary};

pub use self::events::{Command, Event, JobOutcome};
use crate::coverage::{CoverageKey, CoverageRecord, Raster};
use crate::error::Result;
use crate::mission::{MissionRecord, MissionState};
use crate::plan::PlanRecord;
use crate::progress::ProgressParams;
use crate::robots::{Assignment, Robot, Robots};
use crate::site::{Site, validate_site_name};
use crate::watch::WatchParams;

/// Sizes of the job machinery, how robots are routed and how paths are watched.
#[derive(Debug, Clone, PartialEq)]
pub struct EngineConfig {
    /// Jobs computed at once (the blocking pool's size).
    pub workers: usize,
    /// Jobs allowed to wait for a worker; one more is refused with [`crate::EngineError::QueueFull`].
    pub queue_capacity: usize,
    /// Path watching and corrections.
    pub watch: WatchParams,
    /// The site unassigned robots' sensor data feeds (`zenoh.site`); `None`: it is dropped as `unrouted`.
    pub default_site: Option<String>,
    /// A watched plan whose site got no robot points for this long while its robot is alive is flagged
    /// `blind`, milliseconds (`zenoh.robot_timeout_s`).
    pub blind_after_ms: u64,
    /// Progress tracking tolerances.
    pub progress: ProgressParams,
    /// Settled plans kept (ready, done, failed, cancelled: not queued, planning or driven); the oldest beyond it
    /// are forgotten — by the engine, the read model and the store — when a new plan is accepted.
    pub retain_plans: usize,
    /// Measured coverage rasters swept since are committed to the store at most this often (and when the
    /// daemon stops), milliseconds: what a kill -9 can lose.
    pub coverage_commit_ms: u64,
}

impl Default for EngineConfig {
    fn default() -> Self {
        Self {
            workers: 2,
            queue_capacity: 64,
            watch: WatchParams::default(),
            default_site: None,
            blind_after_ms: 5_000,
            progress: ProgressParams::default(),
            retain_plans: usize::MAX,
            coverage_commit_ms: 10_000,
        }
    }
}

/// The fleet brain. See the crate docs.
///
/// `Clone` is a snapshot: the daemon takes one before a client's request and puts it back when the store could
/// not commit what the request decided (sites are shared, so a snapshot copies plan and robot records only).
#[derive(Debug, Default, Clone)]
pub struct Engine {
    config: EngineConfig,
    sites: BTreeMap<String, Arc<Site>>,
    plans: HashMap<String, PlanRecord>,
    queue: VecDeque<String>,
    running: HashSet<String>,
    robots: Robots,
    next_seq: u64,
    draining: bool,
    /// Missions by id.
    missions: HashMap<String, MissionState>,
    /// Measured coverage of every plan driven on a site, by site.
    site_coverage: HashMap<String, Arc<Raster>>,
    /// When rasters were last sent to the store and to the read model, milliseconds.
    coverage_stored_ms: u64,
    coverage_viewed_ms: u64,
    /// When every mission was last looked over (robots lost or back, views due), milliseconds.
    missions_scanned_ms: Option<u64>,
}

/// Missions are looked over at most this often, and at every liveliness change (odometry brings thousands of
/// events a second; a robot silent past `robot_timeout_s` is found lost at most this much later).
const MISSION_SCAN_MS: u64 = 250;

impl Engine {
    /// An empty engine.
    pub fn new(config: EngineConfig) -> Self {
        Self {
            config: EngineConfig {
                workers: config.workers.max(1),
                ..config
            },
            next_seq: 1,
            ..Self::default()
        }
    }

    /// The configuration it runs with.
    pub fn config(&self) -> &EngineConfig {
        &self.config
    }

    /// Handles one event at `now_ms` (milliseconds since the Unix epoch). On error nothing changed.
    pub fn handle(&mut self, event: Event, now_ms: u64) -> Result<Vec<Command>> {
        let mut out = Vec::new();
        let liveliness = matches!(event, Event::RobotLiveliness { .. });
        match event {
            Event::Restore {
                sites,
                plans,
                active,
                missions,
                coverage,
            } => {
                self.restore(sites, plans, active, now_ms, &mut out);
                self.restore_missions(missions, coverage, now_ms, &mut out);
            }
            Event::MapUploaded { site } => {
                validate_site_name(&site.record.site)?;
                let site = Site::from(site);
                out.push(Command::StoreSite(site.record.clone()));
                out.push(Command::SiteChanged(site.summary()));
                out.push(Command::SiteStatic {
                    site: site.record.site.clone(),
                    clearance: site.map.clearance.clone(),
                    grid: site.map.grid.clone(),
                    ground: site.map.elevation.clone(),
                });
                let last_fed_ms = self.sites.get(&site.record.site).map_or(0, |s| s.last_fed_ms);
                self.sites
                    .insert(site.record.site.clone(), Arc::new(Site { last_fed_ms, ..site }));
            }
            Event::PlanRequested { request } => self.request(request, now_ms, &mut out)?,
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
            Event::RobotLiveliness { robot, alive } => self.liveliness(&robot, alive, now_ms, &mut out),
            Event::RobotPose { robot, pose } => self.pose(&robot, pose, now_ms, &mut out),
            Event::AssignPlan { plan_id, robot, doc } => self.assign(&plan_id, &robot, doc, now_ms, &mut out)?,
            Event::MapChanged { site, min, max } => self.map_changed(&site, min, max, now_ms, &mut out),
            Event::SiteFed { site } => self.site_fed(&site, now_ms, &mut out),
            Event::CheckFinished {
                robot,
                plan_id,
                base_version,
                outcome,
                compute_us,
            } => self.check_finished(&robot, &plan_id, base_version, outcome, compute_us, now_ms, &mut out),
            Event::MissionRequested { request } => self.request_mission(request, now_ms, &mut out)?,
            Event::MissionCancelRequested { mission_id } => self.cancel_mission(&mission_id, now_ms, &mut out)?,
            Event::MissionAssignRequested { mission_id, docs } => {
                self.assign_mission(&mission_id, docs, now_ms, &mut out)?;
            }
            Event::MissionReplanRequested { mission_id } => {
                self.request_replan(&mission_id, "requested".into(), now_ms, &mut out)?;
            }
            Event::MissionRobotJoined { mission_id, robot } => {
                self.join_mission(&mission_id, robot, now_ms, &mut out)?;
            }
            Event::MissionFinished { mission_id, outcome } => {
                self.mission_finished(&mission_id, outcome, now_ms, &mut out);
            }
            Event::Shutdown => {
                self.draining = true;
                self.flush_coverage(now_ms, true, true, &mut out);
            }
        }
        let scan = !self.missions.is_empty()
            && (liveliness || self.missions_scanned_ms.is_none_or(|t| now_ms >= t + MISSION_SCAN_MS));
        if scan {
            self.missions_scanned_ms = Some(now_ms);
            self.watch_mission_robots(now_ms, &mut out);
        }
        self.pump(now_ms, &mut out);
        if !self.missions.is_empty() {
            self.refresh_touched_missions(now_ms, scan, &mut out);
        }
        let plan_ended = (out.iter()).any(|c| matches!(c, Command::StorePlan(r) if r.status == PlanStatus::Done));
        let restored = out.iter().any(|c| matches!(c, Command::SiteStatic { .. }));
        self.flush_coverage(now_ms, false, plan_ended || restored, &mut out);
        Ok(out)
    }

    /// A plan's record.
    pub fn plan(&self, plan_id: &str) -> Option<&PlanRecord> {
        self.plans.get(plan_id)
    }

    /// A mission's record.
    pub fn mission(&self, mission_id: &str) -> Option<&MissionRecord> {
        self.missions.get(mission_id).map(|m| &m.record)
    }

    /// The measured coverage raster of a site (`CoverageKey::Site`) or a mission.
    pub fn coverage(&self, key: &CoverageKey) -> Option<CoverageRecord> {
        match key {
            CoverageKey::Site(s) => self.site_coverage.get(s).map(|r| r.record(key.clone())),
            CoverageKey::Mission(m) => (self.missions.get(m))
                .and_then(|m| m.raster.as_ref())
                .map(|r| r.record(key.clone())),
        }
    }

    /// A site's summary.
    pub fn site(&self, site: &str) -> Option<SiteSummary> {
        self.sites.get(site).map(|s| s.summary())
    }

    /// A robot's view.
    pub fn robot(&self, id: &str) -> Option<RobotView> {
        self.robots.get(id).map(|r| self.robot_view(r))
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
        let mut counts = PlanStatus::ALL.map(|s| (s, 0));
        for r in self.plans.values() {
            if let Some(c) = counts.iter_mut().find(|(s, _)| *s == r.status) {
                c.1 += 1;
            }
        }
        counts.to_vec()
    }

    /// The site `r`'s sensor data feeds: its plan's site, else the default site.
    fn feed_site(&self, r: &Robot) -> Option<String> {
        r.assignment
            .as_ref()
            .and_then(|a| self.plans.get(&a.plan_id))
            .map(|p| p.request.site.clone())
            .or_else(|| self.config.default_site.clone())
    }

    fn robot_view(&self, r: &Robot) -> RobotView {
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
            site: self.feed_site(r),
            sensors: None,
        }
    }

    /// Pushes the view of robot `id`.
    fn robot_changed(&self, id: &str, out: &mut Vec<Command>) {
        if let Some(r) = self.robots.get(id) {
            out.push(Command::RobotChanged(self.robot_view(r)));
        }
    }
}

#[cfg(test)]
mod fleet_tests;
#[cfg(test)]
mod mission_tests;
#[cfg(test)]
mod replan_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod watch_tests;
