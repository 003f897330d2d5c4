//! The read model: what HTTP handlers answer from without asking the engine thread. Only the engine thread
//! writes it (after the store committed), handlers take short read locks and clone `Arc`s.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::{Arc, RwLock};

use shift_engine::{CoverageKey, CoverageRecord, PlanRecord};
use shift_planner::map::OccupancyGrid;
use shift_proto::{
    CorrectionDoc, MissionView, PlanDocument, PlanStatus, PlanStatusResponse, RegionReady, RobotView, SiteSummary,
};

/// One plan as the API shows it.
#[derive(Debug, Clone)]
pub struct PlanView {
    /// The record (status, progress, metrics…).
    pub record: Arc<PlanRecord>,
    /// The current plan document once computed.
    pub doc: Option<Arc<PlanDocument>>,
}

/// Corrections kept per plan for `GET /v1/plans/{id}/corrections`.
pub const CORRECTIONS_KEPT: usize = 200;

/// Snapshots of plans and sites.
#[derive(Debug, Default)]
pub struct Views {
    plans: RwLock<HashMap<String, PlanView>>,
    /// Regions streamed so far by plans that are still planning (for SSE clients that connect late); dropped
    /// when the plan leaves `planning` (its document then holds everything).
    regions: RwLock<HashMap<String, Vec<RegionReady>>>,
    sites: RwLock<BTreeMap<String, SiteSummary>>,
    site_maps: RwLock<HashMap<String, Arc<OccupancyGrid>>>,
    robots: RwLock<BTreeMap<String, RobotView>>,
    missions: RwLock<HashMap<String, MissionView>>,
    /// Each site's measured coverage raster, as the engine last sent it (about once a second while robots sweep).
    coverage: RwLock<HashMap<String, Arc<CoverageRecord>>>,
    /// The corrections that made each plan's current document, oldest first (at most [`CORRECTIONS_KEPT`]),
    /// so a page that opens late can draw where the path was replaced.
    corrections: RwLock<HashMap<String, VecDeque<Arc<CorrectionDoc>>>>,
    /// Why the store does not write now (`/readyz` tells).
    store_fault: RwLock<Option<crate::store::fault::StoreError>>,
}

impl Views {
    /// A plan's view.
    pub fn plan(&self, plan_id: &str) -> Option<PlanView> {
        self.plans.read().ok()?.get(plan_id).cloned()
    }

    /// A site's summary.
    pub fn site(&self, site: &str) -> Option<SiteSummary> {
        self.sites.read().ok()?.get(site).cloned()
    }

    /// Every site's summary, in name order.
    pub fn sites(&self) -> Vec<SiteSummary> {
        self.sites
            .read()
            .map(|s| s.values().cloned().collect())
            .unwrap_or_default()
    }

    /// A site's thresholded map.
    pub fn site_map(&self, site: &str) -> Option<Arc<OccupancyGrid>> {
        self.site_maps.read().ok()?.get(site).cloned()
    }

    /// Sets a site's map (at upload and restore).
    pub fn set_site_map(&self, site: &str, grid: Arc<OccupancyGrid>) {
        if let Ok(mut maps) = self.site_maps.write() {
            maps.insert(site.to_owned(), grid);
        }
    }

    /// The acceptance number of a plan (its place in listings).
    pub fn plan_seq(&self, plan_id: &str) -> Option<u64> {
        Some(self.plans.read().ok()?.get(plan_id)?.record.seq)
    }

    /// Up to `limit` plans accepted before `before_seq` (all when `None`) that `keep` accepts, newest first,
    /// and whether more such plans follow.
    pub fn plans_page(
        &self,
        before_seq: Option<u64>,
        limit: usize,
        keep: impl Fn(&PlanRecord) -> bool,
    ) -> (Vec<PlanStatusResponse>, bool) {
        let Ok(plans) = self.plans.read() else {
            return (Vec::new(), false);
        };
        let mut hits: Vec<&Arc<PlanRecord>> = plans
            .values()
            .map(|v| &v.record)
            .filter(|r| before_seq.is_none_or(|b| r.seq < b) && keep(r))
            .collect();
        hits.sort_unstable_by_key(|r| std::cmp::Reverse(r.seq));
        let more = hits.len() > limit;
        (hits.into_iter().take(limit).map(|r| r.to_response()).collect(), more)
    }

    /// Regions a planning plan has streamed so far, in order.
    pub fn regions_ready(&self, plan_id: &str) -> Vec<RegionReady> {
        self.regions
            .read()
            .ok()
            .and_then(|r| r.get(plan_id).cloned())
            .unwrap_or_default()
    }

    /// Keeps a streamed region of a planning plan.
    pub fn push_region(&self, plan_id: &str, region: RegionReady) {
        if let Ok(mut r) = self.regions.write() {
            r.entry(plan_id.to_owned()).or_default().push(region);
        }
    }

    /// Sets a plan's record, keeping its document. A record that is not planning drops the regions streamed
    /// before.
    pub fn set_record(&self, rec: PlanRecord) {
        if rec.status != PlanStatus::Planning
            && let Ok(mut r) = self.regions.write()
        {
            r.remove(&rec.plan_id);
        }
        if let Ok(mut plans) = self.plans.write() {
            let id = rec.plan_id.clone();
            let doc = plans.get(&id).and_then(|v| v.doc.clone());
            plans.insert(
                id,
                PlanView {
                    record: Arc::new(rec),
                    doc,
                },
            );
        }
    }

    /// Forgets a plan (`retain_plans`): the API answers 404 for it after.
    pub fn forget_plan(&self, plan_id: &str) {
        self.clear_corrections(plan_id);
        if let Ok(mut plans) = self.plans.write() {
            plans.remove(plan_id);
        }
        if let Ok(mut r) = self.regions.write() {
            r.remove(plan_id);
        }
    }

    /// Sets a plan's document (the record follows in the same engine step).
    pub fn set_doc(&self, plan_id: &str, doc: Arc<PlanDocument>) {
        if let Ok(mut plans) = self.plans.write()
            && let Some(v) = plans.get_mut(plan_id)
        {
            v.doc = Some(doc);
        }
    }

    /// Keeps a correction of a plan (the oldest goes past [`CORRECTIONS_KEPT`]).
    pub fn push_correction(&self, correction: &CorrectionDoc) {
        if let Ok(mut c) = self.corrections.write() {
            let kept = c.entry(correction.plan_id.clone()).or_default();
            if kept.len() == CORRECTIONS_KEPT {
                kept.pop_front();
            }
            kept.push_back(Arc::new(correction.clone()));
        }
    }

    /// A plan's corrections, oldest first.
    pub fn corrections(&self, plan_id: &str) -> Vec<Arc<CorrectionDoc>> {
        self.corrections
            .read()
            .ok()
            .and_then(|c| c.get(plan_id).map(|k| k.iter().cloned().collect()))
            .unwrap_or_default()
    }

    /// Drops a plan's corrections (a replan replaced its document: they patched a line no longer driven).
    pub fn clear_corrections(&self, plan_id: &str) {
        if let Ok(mut c) = self.corrections.write() {
            c.remove(plan_id);
        }
    }

    /// A robot's view.
    pub fn robot(&self, robot: &str) -> Option<RobotView> {
        self.robots.read().ok()?.get(robot).cloned()
    }

    /// Every robot.
    pub fn robots(&self) -> Vec<RobotView> {
        self.robots
            .read()
            .map(|r| r.values().cloned().collect())
            .unwrap_or_default()
    }

    /// The document of the plan a robot drives.
    pub fn robot_plan(&self, robot: &str) -> Option<Arc<PlanDocument>> {
        let plan_id = self.robot(robot)?.plan_id?;
        self.plan(&plan_id)?.doc
    }

    /// Every plan's status, oldest first.
    pub fn statuses(&self) -> Vec<shift_proto::PlanStatusResponse> {
        let Ok(plans) = self.plans.read() else {
            return Vec::new();
        };
        let mut v: Vec<_> = plans.values().map(|p| (p.record.seq, p.record.to_response())).collect();
        v.sort_by_key(|(seq, _)| *seq);
        v.into_iter().map(|(_, s)| s).collect()
    }

    /// Sets a robot's view.
    pub fn set_robot(&self, view: RobotView) {
        if let Ok(mut robots) = self.robots.write() {
            robots.insert(view.robot.clone(), view);
        }
    }

    /// Sets a site's summary.
    pub fn set_site(&self, summary: SiteSummary) {
        if let Ok(mut sites) = self.sites.write() {
            sites.insert(summary.site.clone(), summary);
        }
    }

    /// A mission's view.
    pub fn mission(&self, mission_id: &str) -> Option<MissionView> {
        self.missions.read().ok()?.get(mission_id).cloned()
    }

    /// Sets a mission's view.
    pub fn set_mission(&self, view: MissionView) {
        if let Ok(mut m) = self.missions.write() {
            m.insert(view.mission_id.clone(), view);
        }
    }

    /// A site's measured coverage raster.
    pub fn coverage(&self, site: &str) -> Option<Arc<CoverageRecord>> {
        self.coverage.read().ok()?.get(site).cloned()
    }

    /// Sets a site's measured coverage raster (mission rasters are not served whole; their figure is in the
    /// mission's view).
    pub fn set_coverage(&self, record: Arc<CoverageRecord>) {
        if let CoverageKey::Site(site) = &record.key
            && let Ok(mut c) = self.coverage.write()
        {
            c.insert(site.clone(), record.clone());
        }
    }

    /// Why the store does not write now, if it does not.
    pub fn store_fault(&self) -> Option<crate::store::fault::StoreError> {
        self.store_fault.read().ok().and_then(|f| f.clone())
    }

    /// Sets (or clears) why the store does not write.
    pub fn set_store_fault(&self, fault: Option<crate::store::fault::StoreError>) {
        if let Ok(mut f) = self.store_fault.write() {
            *f = fault;
        }
    }
}
