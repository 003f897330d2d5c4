//! Path corrections (DESIGN §5.4, `…/robots/{robot}/corrections`): a small, versioned patch that replaces one
//! stretch of a robot's plan, and the one rule for applying it, shared by the server, the API and robots.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::plan::{PlanDocument, WaypointDoc};

/// Why a correction was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "lowercase")]
pub enum CorrectionReason {
    /// An obstacle broke the path cost; the sliding-window optimiser moved the stretch clear of it.
    Obstacle,
    /// The optimiser could not clear it; a local A* detour replaces the stretch.
    Detour,
    /// No way past within the window: the blocked stretch is left out (see `skipped`) and the robot transits
    /// to the first later point it can reach, or stops when none is reachable.
    Skipped,
}

impl CorrectionReason {
    /// Stable lowercase name (metric labels, logs).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Obstacle => "obstacle",
            Self::Detour => "detour",
            Self::Skipped => "skipped",
        }
    }
}

/// One correction: "replace `waypoints[from..to)` of version `base_version` with `waypoints`", giving version
/// `version` = `base_version + 1`. Waypoints from `to` on keep their place but their `t` moves by `dt_after_s`
/// (the patch is longer or slower than what it replaces).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CorrectionDoc {
    /// Plan id.
    pub plan_id: String,
    /// Robot driving the plan.
    pub robot: String,
    /// Version the patch applies to.
    pub base_version: u64,
    /// Version after applying it (`base_version + 1`).
    pub version: u64,
    /// First replaced waypoint index of `base_version`.
    pub from: usize,
    /// One past the last replaced index (`from == to`: pure insertion).
    pub to: usize,
    /// The new waypoints, map frame, with speeds and times re-profiled.
    pub waypoints: Vec<WaypointDoc>,
    /// Why.
    pub reason: CorrectionReason,
    /// Seconds added to `t` of every waypoint from `to` on.
    #[serde(default)]
    pub dt_after_s: f64,
    /// For `skipped`: the left-out stretch of the old path `[[x, y], …]`, metres, map frame (its cells are
    /// missed until a later revisit).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skipped: Vec<[f64; 2]>,
    /// Time the check that made it took on the server (judgment, optimisation, verification, re-profiling),
    /// microseconds.
    pub compute_us: u64,
}

/// Why a correction does not apply to a document.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum CorrectionError {
    /// The correction is for another plan.
    #[error("correction for plan {correction} applied to plan {document}")]
    WrongPlan {
        /// Plan of the correction.
        correction: String,
        /// Plan of the document.
        document: String,
    },
    /// The document is not at the correction's base version (a robot that sees this re-fetches the plan).
    #[error("correction from version {base} applied to version {have}")]
    VersionGap {
        /// The correction's base version.
        base: u64,
        /// The document's version.
        have: u64,
    },
    /// `version` is not `base_version + 1`.
    #[error("correction version {version} does not follow base version {base}")]
    BadVersion {
        /// The correction's base version.
        base: u64,
        /// Its version.
        version: u64,
    },
    /// `from..to` is not a range of the document's waypoints.
    #[error("correction range {from}..{to} outside a path of {len} waypoints")]
    BadRange {
        /// Start of the range.
        from: usize,
        /// End of the range.
        to: usize,
        /// Waypoints in the document.
        len: usize,
    },
}

impl CorrectionDoc {
    /// `doc` with this correction applied: the patched waypoints, the version bumped, later times shifted.
    /// Regions and metrics are kept (metrics describe the plan as computed).
    pub fn apply(&self, doc: &PlanDocument) -> Result<PlanDocument, CorrectionError> {
        if doc.plan_id != self.plan_id {
            return Err(CorrectionError::WrongPlan {
                correction: self.plan_id.clone(),
                document: doc.plan_id.clone(),
            });
        }
        if doc.version != self.base_version {
            return Err(CorrectionError::VersionGap {
                base: self.base_version,
                have: doc.version,
            });
        }
        if self.version != self.base_version + 1 {
            return Err(CorrectionError::BadVersion {
                base: self.base_version,
                version: self.version,
            });
        }
        let len = doc.waypoints.len();
        if self.from > self.to || self.to > len {
            return Err(CorrectionError::BadRange {
                from: self.from,
                to: self.to,
                len,
            });
        }
        let mut waypoints = Vec::with_capacity(len - (self.to - self.from) + self.waypoints.len());
        waypoints.extend_from_slice(&doc.waypoints[..self.from]);
        waypoints.extend_from_slice(&self.waypoints);
        waypoints.extend(doc.waypoints[self.to..].iter().map(|w| WaypointDoc {
            t: w.t + self.dt_after_s,
            ..*w
        }));
        Ok(PlanDocument {
            version: self.version,
            waypoints,
            ..doc.clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::{PlanMetricsDoc, WaypointKindDoc};
    use proptest::prelude::*;

    fn wp(x: f64, t: f64) -> WaypointDoc {
        WaypointDoc {
            x,
            y: 0.0,
            z: 0.0,
            v: 0.5,
            t,
            kind: WaypointKindDoc::Cover,
            region: Some(1),
        }
    }

    fn doc(n: usize) -> PlanDocument {
        PlanDocument {
            plan_id: "p-1".into(),
            version: 1,
            frame: "map".into(),
            waypoints: (0..n).map(|i| wp(i as f64, i as f64 * 2.0)).collect(),
            regions: Vec::new(),
            metrics: PlanMetricsDoc::default(),
        }
    }

    fn correction(base: u64, from: usize, to: usize, new: Vec<WaypointDoc>, dt: f64) -> CorrectionDoc {
        CorrectionDoc {
            plan_id: "p-1".into(),
            robot: "r1".into(),
            base_version: base,
            version: base + 1,
            from,
            to,
            waypoints: new,
            reason: CorrectionReason::Obstacle,
            dt_after_s: dt,
            skipped: Vec::new(),
            compute_us: 10,
        }
    }

    #[test]
    fn replaces_the_range_and_shifts_later_times() {
        let d = doc(5);
        let c = correction(1, 2, 3, vec![wp(1.5, 3.0), wp(2.5, 5.5)], 1.5);
        let out = c.apply(&d).expect("applies");
        assert_eq!(out.version, 2);
        let xs: Vec<f64> = out.waypoints.iter().map(|w| w.x).collect();
        assert_eq!(xs, [0.0, 1.0, 1.5, 2.5, 3.0, 4.0]);
        assert_eq!(out.waypoints[4].t, 6.0 + 1.5);
        assert_eq!(out.waypoints[1].t, 2.0);
    }

    #[test]
    fn refuses_gaps_ranges_and_other_plans() {
        let d = doc(3);
        assert!(matches!(
            correction(2, 0, 1, vec![], 0.0).apply(&d),
            Err(CorrectionError::VersionGap { base: 2, have: 1 })
        ));
        assert!(matches!(
            correction(1, 2, 4, vec![], 0.0).apply(&d),
            Err(CorrectionError::BadRange { .. })
        ));
        let mut c = correction(1, 0, 0, vec![], 0.0);
        c.version = 5;
        assert!(matches!(c.apply(&d), Err(CorrectionError::BadVersion { .. })));
        let mut c = correction(1, 0, 0, vec![], 0.0);
        c.plan_id = "p-2".into();
        assert!(matches!(c.apply(&d), Err(CorrectionError::WrongPlan { .. })));
    }

    #[test]
    fn wire_names() {
        let c = correction(1, 0, 1, vec![], 0.0);
        let v = serde_json::to_value(&c).expect("ser");
        for k in [
            "plan_id",
            "base_version",
            "version",
            "from",
            "to",
            "waypoints",
            "reason",
            "compute_us",
        ] {
            assert!(v.get(k).is_some(), "{k} missing");
        }
        assert_eq!(v["reason"], "obstacle");
        let back: CorrectionDoc = serde_json::from_value(v).expect("de");
        assert_eq!(back, c);
    }

    proptest! {
        /// Applying a chain of random corrections in order keeps everything outside each patch untouched and
        /// lands at the last version; the lengths add up.
        #[test]
        fn chains_apply_in_order(ops in prop::collection::vec((0usize..20, 0usize..6, 0usize..5, -2.0f64..5.0), 1..8)) {
            let mut cur = doc(12);
            for (k, (a, span, n, dt)) in ops.into_iter().enumerate() {
                let len = cur.waypoints.len();
                let from = a.min(len);
                let to = (from + span).min(len);
                let new: Vec<WaypointDoc> = (0..n).map(|i| wp(100.0 + k as f64 + i as f64 * 0.1, 0.0)).collect();
                let c = correction(cur.version, from, to, new.clone(), dt);
                let next = c.apply(&cur).expect("in range");
                prop_assert_eq!(next.version, cur.version + 1);
                prop_assert_eq!(next.waypoints.len(), len - (to - from) + n);
                prop_assert_eq!(&next.waypoints[..from], &cur.waypoints[..from]);
                prop_assert_eq!(&next.waypoints[from..from + n], &new[..]);
                for (a, b) in next.waypoints[from + n..].iter().zip(&cur.waypoints[to..]) {
                    prop_assert_eq!(a.x, b.x);
                    prop_assert!((a.t - (b.t + dt)).abs() < 1e-12);
                }
                // A stale copy refuses the next correction.
                prop_assert!(c.apply(&next).is_err());
                cur = next;
            }
        }
    }
}
