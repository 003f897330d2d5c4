//! Measured coverage in the engine: the tool's swath stamped between two poses of a robot driving a plan,
//! into its site's raster and its mission's, and the rasters sent to the read model and the store when due.

use std::sync::Arc;

use shift_planner::geom::Point2;
use shift_proto::{PlanStatus, WaypointKindDoc};

use super::{Command, Engine};
use crate::coverage::{CoverageKey, Raster};
use crate::robots::Pose2;

/// A site's raster goes to the read model at most this often, milliseconds.
const COVERAGE_VIEW_EVERY_MS: u64 = 1_000;
/// Motion longer than this between two poses is a jump (relocalisation), not a sweep, metres.
const MAX_SWEEP_M: f64 = 2.0;

impl Engine {
    /// Stamps the tool's swath between two poses of `robot` into its site's raster and its mission's, when it
    /// drives a plan and the stretch it is on sweeps (a `cover` waypoint behind or ahead of it).
    pub(super) fn sweep(&mut self, robot: &str, prev: Option<Pose2>, pose: Pose2, now_ms: u64) {
        let Some(prev) = prev else { return };
        let (a, b) = (Point2::new(prev.x, prev.y), Point2::new(pose.x, pose.y));
        if (b - a).norm() > MAX_SWEEP_M {
            return;
        }
        let Some(asg) = self.robots.get(robot).and_then(|r| r.assignment.as_ref()) else {
            return;
        };
        let kind = |i: usize| asg.doc.waypoints.get(i).map(|w| w.kind);
        let tool_on =
            kind(asg.index) == Some(WaypointKindDoc::Cover) || kind(asg.index + 1) == Some(WaypointKindDoc::Cover);
        let Some(rec) = self.plans.get(&asg.plan_id) else {
            return;
        };
        if !tool_on || rec.status != PlanStatus::Active {
            return;
        }
        let half = rec.request.robot.tool_width / 2.0;
        let site = rec.request.site.clone();
        if let Some(m) = rec.mission.as_ref().and_then(|id| self.missions.get_mut(id))
            && let Some(raster) = m.raster.as_mut()
            && Arc::make_mut(raster).stamp(a, b, half, now_ms) > 0
        {
            m.dirty = true;
        }
        if let Some(g) = self.sites.get(&site).map(|s| s.map.grid.geometry) {
            let raster = self
                .site_coverage
                .entry(site)
                .or_insert_with(|| Arc::new(Raster::new(g, None)));
            Arc::make_mut(raster).stamp(a, b, half, now_ms);
        }
    }

    /// Pushes the rasters due: to the read model about once a second (and at once with `view_now`: a plan
    /// ended, so the last of its sweep shows), to the store every `coverage_commit_ms` (every dirty
    /// one at once with `store_now`).
    pub(super) fn flush_coverage(&mut self, now_ms: u64, store_now: bool, view_now: bool, out: &mut Vec<Command>) {
        let store_due = store_now || now_ms >= self.coverage_stored_ms + self.config.coverage_commit_ms;
        let view_due = view_now || store_now || now_ms >= self.coverage_viewed_ms + COVERAGE_VIEW_EVERY_MS;
        if !(store_due || view_due) {
            return;
        }
        let mut dirty: Vec<(CoverageKey, &mut Arc<Raster>)> = Vec::new();
        for (site, r) in &mut self.site_coverage {
            dirty.push((CoverageKey::Site(site.clone()), r));
        }
        for (id, m) in &mut self.missions {
            if let Some(r) = m.raster.as_mut() {
                dirty.push((CoverageKey::Mission(id.clone()), r));
            }
        }
        for (key, raster) in dirty {
            let (to_store, to_view) = (
                store_due && raster.dirty_store,
                view_due && raster.dirty_view && matches!(key, CoverageKey::Site(_)),
            );
            if !(to_store || to_view) {
                continue;
            }
            let r = Arc::make_mut(raster);
            let record = Arc::new(r.record(key));
            if to_store {
                r.dirty_store = false;
                out.push(Command::StoreCoverage(record.clone()));
            }
            if to_view {
                r.dirty_view = false;
                out.push(Command::CoverageChanged(record));
            }
        }
        if store_due {
            self.coverage_stored_ms = now_ms;
        }
        if view_due {
            self.coverage_viewed_ms = now_ms;
        }
    }
}
