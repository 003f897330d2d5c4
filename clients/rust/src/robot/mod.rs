//! For robots: follow a plan and its corrections by version ([`FollowedPlan`], transport-free), and — with
//! the `robot` feature — receive them over Zenoh on the keys of DESIGN §5.4 ([`RobotLink`]), fetching the
//! plan with a Zenoh `get` when a correction shows a version gap.

#[cfg(feature = "robot")]
mod link;

#[cfg(feature = "robot")]
pub use link::{RobotLink, RobotMessage, peer_config};

use shift_proto::{CorrectionDoc, CorrectionError, PlanDocument, PlanStatusResponse, WatchHealth};

/// What [`FollowedPlan`] did with a plan or correction.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Applied {
    /// The plan document was taken: the robot now follows this plan at this version.
    Plan {
        /// Plan id.
        plan_id: String,
        /// Its version.
        version: u64,
    },
    /// The correction was applied (and any held corrections that follow it): now at `version`.
    Correction {
        /// The version reached.
        version: u64,
    },
    /// The plan's watch health changed (its status said so): `blocked` means the path is blocked to its end
    /// and the server holds the plan's end for a while in case the blockage moves on; wait before it.
    Watch {
        /// The health now.
        health: WatchHealth,
    },
    /// Old news: a plan or correction at or below the version held, or a status of another plan or with
    /// nothing new; nothing changed.
    Stale,
    /// The correction does not follow the version held (`have`: none when no plan of its id is held): fetch
    /// the plan. The correction is kept and applied if a fetched plan is at its base version.
    Gap {
        /// The plan the correction is for.
        plan_id: String,
        /// The correction's base version.
        base: u64,
        /// The version held of that plan.
        have: Option<u64>,
    },
}

/// Most corrections held while waiting for the plan a gap asks for.
const MAX_HELD: usize = 64;

/// The plan a robot follows: the current document, kept up to date by plans and corrections received in any
/// order. A correction applies only to the version it was made from ([`CorrectionDoc::apply`]); one from
/// further ahead reports a [`Applied::Gap`] and waits for the plan.
///
/// ```
/// use shift_client::robot::{Applied, FollowedPlan};
/// use shift_client::proto::{CorrectionDoc, CorrectionReason, PlanDocument, PlanMetricsDoc, WaypointDoc,
///     WaypointKindDoc};
/// let wp = |x: f64| WaypointDoc { x, y: 0.0, z: 0.0, v: 0.5, t: 2.0 * x, kind: WaypointKindDoc::Cover,
///     region: Some(0) };
/// let plan = PlanDocument { plan_id: "p-1".into(), version: 1, frame: "map".into(),
///     waypoints: (0..5).map(|i| wp(f64::from(i))).collect(), regions: vec![],
///     metrics: PlanMetricsDoc::default() };
/// let fix = |base: u64| CorrectionDoc { plan_id: "p-1".into(), robot: "r1".into(), base_version: base,
///     version: base + 1, from: 1, to: 2, waypoints: vec![wp(1.5)], reason: CorrectionReason::Obstacle,
///     dt_after_s: 0.0, skipped: vec![], compute_us: 10 };
/// let mut followed = FollowedPlan::default();
/// assert_eq!(followed.on_plan(plan.clone()), Applied::Plan { plan_id: "p-1".into(), version: 1 });
/// // Version 3 cannot apply to version 1: a gap, the correction is held.
/// assert!(matches!(followed.on_correction(fix(2)), Ok(Applied::Gap { base: 2, have: Some(1), .. })));
/// assert_eq!(followed.on_correction(fix(1)), Ok(Applied::Correction { version: 3 }));
/// assert_eq!(followed.version(), Some(3));
/// assert_eq!(followed.on_correction(fix(1)), Ok(Applied::Stale));
/// ```
#[derive(Debug, Clone, Default)]
pub struct FollowedPlan {
    doc: Option<PlanDocument>,
    held: Vec<CorrectionDoc>,
    watch: Option<WatchHealth>,
}

impl FollowedPlan {
    /// Starts from a plan document.
    pub fn new(doc: PlanDocument) -> Self {
        Self {
            doc: Some(doc),
            held: Vec::new(),
            watch: None,
        }
    }

    /// The watch health the plan's last status gave (`None` before one came, or after a new plan).
    pub fn watch(&self) -> Option<WatchHealth> {
        self.watch
    }

    /// Takes a plan status (the server publishes every plan's on `plans/{id}/status`): the followed plan's
    /// watch health is kept; other plans' statuses are [`Applied::Stale`].
    ///
    /// ```
    /// use shift_client::robot::{Applied, FollowedPlan};
    /// use shift_client::proto::{PlanDocument, PlanMetricsDoc, PlanStatusResponse, WatchHealth};
    /// let doc = PlanDocument { plan_id: "p-1".into(), version: 1, frame: "map".into(), waypoints: vec![],
    ///     regions: vec![], metrics: PlanMetricsDoc::default() };
    /// let status = |plan_id: &str, watch: WatchHealth| -> PlanStatusResponse {
    ///     serde_json::from_value(serde_json::json!({ "plan_id": plan_id, "site": "s", "status": "active",
    ///         "progress": 1.0, "version": 1, "regions_ready": 1, "watch": watch, "created_ms": 0,
    ///         "updated_ms": 0 })).unwrap()
    /// };
    /// let mut followed = FollowedPlan::new(doc);
    /// assert_eq!(followed.on_status(&status("p-1", WatchHealth::Blocked)), Applied::Watch { health: WatchHealth::Blocked });
    /// assert_eq!(followed.on_status(&status("p-1", WatchHealth::Blocked)), Applied::Stale);
    /// assert_eq!(followed.on_status(&status("p-2", WatchHealth::Watching)), Applied::Stale);
    /// assert_eq!(followed.watch(), Some(WatchHealth::Blocked));
    /// ```
    pub fn on_status(&mut self, status: &PlanStatusResponse) -> Applied {
        let ours = self.doc.as_ref().is_some_and(|d| d.plan_id == status.plan_id);
        match status.watch {
            Some(health) if ours && self.watch != Some(health) => {
                self.watch = Some(health);
                Applied::Watch { health }
            }
            _ => Applied::Stale,
        }
    }

    /// The current document.
    pub fn doc(&self) -> Option<&PlanDocument> {
        self.doc.as_ref()
    }

    /// The current version.
    pub fn version(&self) -> Option<u64> {
        self.doc.as_ref().map(|d| d.version)
    }

    /// Corrections received ahead of the version held, waiting for the plan.
    pub fn held(&self) -> usize {
        self.held.len()
    }

    /// Takes a plan document: a new plan replaces the old one; the same plan replaces it when at least as
    /// new. Held corrections that follow it are applied.
    pub fn on_plan(&mut self, doc: PlanDocument) -> Applied {
        let newer = match &self.doc {
            Some(d) if d.plan_id == doc.plan_id => doc.version > d.version,
            _ => true,
        };
        if !newer {
            return Applied::Stale;
        }
        self.held
            .retain(|c| c.plan_id == doc.plan_id && c.version > doc.version);
        let plan_id = doc.plan_id.clone();
        if self.doc.as_ref().is_none_or(|d| d.plan_id != plan_id) {
            self.watch = None;
        }
        self.doc = Some(doc);
        self.apply_held();
        Applied::Plan {
            plan_id,
            version: self.version().unwrap_or(0),
        }
    }

    /// Takes a correction. `Err` when it cannot apply to the version it names (a range outside the path, a
    /// version that does not follow its base): the server broke the contract, the plan should be fetched.
    pub fn on_correction(&mut self, c: CorrectionDoc) -> Result<Applied, CorrectionError> {
        let Some(doc) = &self.doc else {
            return Ok(self.hold(c, None));
        };
        if doc.plan_id != c.plan_id {
            return Ok(self.hold(c, None));
        }
        if c.version <= doc.version {
            return Ok(Applied::Stale);
        }
        if c.base_version != doc.version {
            let have = Some(doc.version);
            return Ok(self.hold(c, have));
        }
        self.doc = Some(c.apply(doc)?);
        self.apply_held();
        Ok(Applied::Correction {
            version: self.version().unwrap_or(0),
        })
    }

    fn hold(&mut self, c: CorrectionDoc, have: Option<u64>) -> Applied {
        let gap = Applied::Gap {
            plan_id: c.plan_id.clone(),
            base: c.base_version,
            have,
        };
        if !self
            .held
            .iter()
            .any(|h| h.plan_id == c.plan_id && h.version == c.version)
        {
            if self.held.len() == MAX_HELD {
                self.held.remove(0);
            }
            self.held.push(c);
        }
        gap
    }

    /// Applies held corrections while one follows the current version.
    fn apply_held(&mut self) {
        while let Some(doc) = &self.doc {
            let Some(i) = self
                .held
                .iter()
                .position(|c| c.plan_id == doc.plan_id && c.base_version == doc.version)
            else {
                break;
            };
            let c = self.held.swap_remove(i);
            match c.apply(doc) {
                Ok(next) => self.doc = Some(next),
                Err(_) => continue,
            }
        }
        if let Some(doc) = &self.doc {
            let (id, v) = (doc.plan_id.clone(), doc.version);
            self.held.retain(|c| c.plan_id != id || c.version > v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shift_proto::{CorrectionReason, PlanMetricsDoc, WaypointDoc, WaypointKindDoc};

    fn wp(x: f64) -> WaypointDoc {
        WaypointDoc {
            x,
            y: 0.0,
            z: 0.0,
            v: 0.5,
            t: 2.0 * x,
            kind: WaypointKindDoc::Cover,
            region: Some(0),
        }
    }

    fn plan(id: &str, version: u64) -> PlanDocument {
        PlanDocument {
            plan_id: id.into(),
            version,
            frame: "map".into(),
            waypoints: (0..6).map(|i| wp(f64::from(i))).collect(),
            regions: Vec::new(),
            metrics: PlanMetricsDoc::default(),
        }
    }

    fn fix(id: &str, base: u64, x: f64) -> CorrectionDoc {
        CorrectionDoc {
            plan_id: id.into(),
            robot: "r1".into(),
            base_version: base,
            version: base + 1,
            from: 1,
            to: 2,
            waypoints: vec![wp(x)],
            reason: CorrectionReason::Obstacle,
            dt_after_s: 0.5,
            skipped: Vec::new(),
            compute_us: 1,
        }
    }

    #[test]
    fn a_fetched_plan_releases_held_corrections() {
        let mut f = FollowedPlan::new(plan("p", 1));
        // v2 was missed; v3 (from v2) and v4 (from v3) arrive.
        assert!(matches!(
            f.on_correction(fix("p", 2, 1.2)),
            Ok(Applied::Gap { base: 2, .. })
        ));
        assert!(matches!(
            f.on_correction(fix("p", 3, 1.3)),
            Ok(Applied::Gap { base: 3, .. })
        ));
        assert_eq!(f.held(), 2);
        // The fetched plan is at v2: both apply, in order.
        let mut v2 = plan("p", 2);
        v2.waypoints[1].x = 1.1;
        assert_eq!(
            f.on_plan(v2),
            Applied::Plan {
                plan_id: "p".into(),
                version: 4
            }
        );
        assert_eq!(f.held(), 0);
        assert_eq!(f.doc().map(|d| d.waypoints[1].x), Some(1.3));
        // An older copy of the plan changes nothing.
        assert_eq!(f.on_plan(plan("p", 3)), Applied::Stale);
    }

    #[test]
    fn a_new_plan_replaces_and_foreign_corrections_are_gaps() {
        let mut f = FollowedPlan::default();
        assert!(matches!(
            f.on_correction(fix("q", 1, 1.5)),
            Ok(Applied::Gap { have: None, .. })
        ));
        f.on_plan(plan("p", 5));
        assert!(matches!(
            f.on_correction(fix("q", 1, 1.5)),
            Ok(Applied::Gap { have: None, .. })
        ));
        // Plan q arrives at v1: the held correction for it applies.
        assert_eq!(
            f.on_plan(plan("q", 1)),
            Applied::Plan {
                plan_id: "q".into(),
                version: 2
            }
        );
        let mut bad = fix("q", 2, 0.0);
        bad.to = 99;
        assert!(f.on_correction(bad).is_err());
        assert_eq!(f.version(), Some(2));
    }
}
