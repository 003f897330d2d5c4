//! Path watching in the engine: when checks start, one per robot at a time, and how a proposal becomes a
//! versioned correction (checks are fed back by hand; `run_check` itself is tested in `watch.rs`).

use std::sync::Arc;

use proptest::prelude::*;
use shift_proto::{
    CorrectionDoc, CorrectionReason, PlanDocument, PlanEvent, PlanMetricsDoc, WatchHealth, WaypointDoc, WaypointKindDoc,
};

use super::tests::{engine, request};
use super::*;
use crate::robots::Pose2;
use crate::watch::{CheckOutcome, ProposedCorrection};

fn wp(x: f64, y: f64, t: f64) -> WaypointDoc {
    WaypointDoc {
        x,
        y,
        z: 0.0,
        v: 0.5,
        t,
        kind: WaypointKindDoc::Cover,
        region: Some(0),
    }
}

pub(super) fn lane_doc() -> Arc<PlanDocument> {
    Arc::new(PlanDocument {
        plan_id: "p-1".into(),
        version: 1,
        frame: "map".into(),
        waypoints: (0..6).map(|i| wp(0.5 + i as f64 * 0.4, 0.5, i as f64)).collect(),
        regions: vec![],
        metrics: PlanMetricsDoc::default(),
    })
}

/// An engine with plan p-1 ready and assigned to r1.
fn assigned() -> (Engine, Arc<PlanDocument>) {
    assigned_with(engine(1, 4))
}

/// `e` (with site "s") with plan p-1 ready and assigned to r1.
pub(super) fn assigned_with(mut e: Engine) -> (Engine, Arc<PlanDocument>) {
    e.handle(Event::PlanRequested { request: request("s") }, 0)
        .expect("queued");
    let doc = lane_doc();
    e.handle(
        Event::JobFinished {
            plan_id: "p-1".into(),
            outcome: JobOutcome::Planned {
                doc: doc.clone(),
                warnings: vec![],
            },
        },
        1,
    )
    .expect("ready");
    e.handle(
        Event::AssignPlan {
            plan_id: "p-1".into(),
            robot: "r1".into(),
            doc: doc.clone(),
        },
        2,
    )
    .expect("assigned");
    (e, doc)
}

fn pose(x: f64) -> Event {
    Event::RobotPose {
        robot: "r1".into(),
        pose: Pose2 {
            x,
            y: 0.5,
            yaw: 0.0,
            stamp_ns: 0,
        },
    }
}

fn checks(cmds: &[Command]) -> Vec<(String, u64)> {
    cmds.iter()
        .filter_map(|c| match c {
            Command::StartCheck(j) => Some((j.robot.clone(), j.doc.version)),
            _ => None,
        })
        .collect()
}

fn finished(base_version: u64, outcome: CheckOutcome) -> Event {
    Event::CheckFinished {
        robot: "r1".into(),
        plan_id: "p-1".into(),
        base_version,
        outcome,
        compute_us: 250,
    }
}

fn proposal(from: usize, to: usize, n: usize) -> CheckOutcome {
    CheckOutcome::Correct(ProposedCorrection {
        from,
        to,
        waypoints: (0..n).map(|i| wp(1.0 + i as f64 * 0.1, 0.8, 2.0)).collect(),
        reason: CorrectionReason::Obstacle,
        dt_after_s: 0.25,
        skipped: vec![],
        iterations: 4,
    })
}

fn corrections(cmds: &[Command]) -> Vec<Arc<CorrectionDoc>> {
    cmds.iter()
        .filter_map(|c| match c {
            Command::StoreCorrection { correction, .. } => Some(correction.clone()),
            _ => None,
        })
        .collect()
}

#[test]
fn one_check_per_robot_in_flight_and_triggers_coalesce() {
    let (mut e, _) = assigned();
    let c = e.handle(pose(0.5), 1000).expect("pose");
    assert_eq!(checks(&c), vec![("r1".into(), 1)], "the first pose starts a check");
    // While it runs, neither poses nor map changes start another.
    assert!(checks(&e.handle(pose(0.6), 1500).expect("pose")).is_empty());
    let near = Event::MapChanged {
        site: "s".into(),
        min: [1.0, 0.4],
        max: [1.2, 0.6],
    };
    assert!(checks(&e.handle(near.clone(), 1501).expect("map")).is_empty());
    // It ends clear: the change seen meanwhile is checked at once.
    let c = e.handle(finished(1, CheckOutcome::Clear), 1502).expect("done");
    assert_eq!(checks(&c), vec![("r1".into(), 1)]);
    e.handle(finished(1, CheckOutcome::Clear), 1503).expect("done");
    // Nothing pending now; a pose inside the interval does not check, one after it does.
    assert!(checks(&e.handle(pose(0.6), 1600).expect("pose")).is_empty());
    assert_eq!(checks(&e.handle(pose(0.6), 1800).expect("pose")).len(), 1);
    e.handle(finished(1, CheckOutcome::Clear), 1801).expect("done");
    // A change far from the robot (beyond the window radius) does not concern it; another site neither.
    let far = Event::MapChanged {
        site: "s".into(),
        min: [20.0, 20.0],
        max: [21.0, 21.0],
    };
    assert!(checks(&e.handle(far, 1802).expect("map")).is_empty());
    let other = Event::MapChanged {
        site: "elsewhere".into(),
        min: [1.0, 0.4],
        max: [1.2, 0.6],
    };
    assert!(checks(&e.handle(other, 1803).expect("map")).is_empty());
    assert_eq!(checks(&e.handle(near, 1804).expect("map")).len(), 1);
}

#[test]
fn a_proposal_becomes_the_next_version_and_stale_ones_are_dropped() {
    let (mut e, doc) = assigned();
    e.handle(pose(0.5), 1000).expect("pose");
    let c = e.handle(finished(1, proposal(2, 4, 3)), 1001).expect("done");
    let cs = corrections(&c);
    assert_eq!(cs.len(), 1);
    let k = &cs[0];
    assert_eq!((k.base_version, k.version, k.from, k.to), (1, 2, 2, 4));
    assert_eq!(k.compute_us, 250);
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::PublishCorrection(x) if x.version == 2))
    );
    assert!(
        c.iter()
            .any(|c| matches!(c, Command::Publish(PlanEvent::Correction(x)) if x.version == 2))
    );
    // The stored record is at version 2, and the document shown is the corrected one.
    let shown = c.iter().find_map(|c| match c {
        Command::StoreCorrection { record, doc, .. } => Some((record.version, doc.clone())),
        _ => None,
    });
    let (version, current) = shown.expect("stored");
    assert_eq!(version, 2);
    assert_eq!(current.version, 2);
    assert_eq!(current.waypoints.len(), doc.waypoints.len() + 1);
    assert_eq!(e.plan("p-1").map(|r| r.version), Some(2));
    // The robot view names the correction.
    let view = e.robot("r1").and_then(|r| r.last_correction).expect("last correction");
    assert_eq!((view.version, view.reason), (2, CorrectionReason::Obstacle));
    // A re-check of the new version started at once.
    assert_eq!(checks(&c), vec![("r1".into(), 2)]);
    // A late answer for version 1 is stale: dropped, and the robot is looked at again.
    let c = e.handle(finished(1, proposal(0, 1, 1)), 1002).expect("stale");
    assert!(corrections(&c).is_empty());
    assert_eq!(checks(&c), vec![("r1".into(), 2)]);
}

#[test]
fn skipped_stretches_are_listed_as_missed() {
    let (mut e, _) = assigned();
    e.handle(pose(0.5), 1000).expect("pose");
    let CheckOutcome::Correct(mut p) = proposal(2, 5, 1) else {
        unreachable!()
    };
    p.reason = CorrectionReason::Skipped;
    p.skipped = vec![[1.3, 0.5], [2.5, 0.5]];
    e.handle(finished(1, CheckOutcome::Correct(p)), 1001).expect("done");
    let status = e.plan("p-1").map(PlanRecord::to_response).expect("plan");
    assert_eq!(status.missed, vec![vec![[1.3, 0.5], [2.5, 0.5]]]);
}

/// The skip that ends the plan where the robot stands (nothing beyond the blockage reachable).
fn ending_skip() -> CheckOutcome {
    CheckOutcome::Correct(ProposedCorrection {
        from: 1,
        to: 6,
        waypoints: vec![wp(0.9, 0.5, 1.0)],
        reason: CorrectionReason::Skipped,
        dt_after_s: 0.0,
        skipped: vec![[0.9, 0.5], [2.5, 0.5]],
        iterations: 0,
    })
}

fn published(cmds: &[Command]) -> usize {
    cmds.iter()
        .filter(|c| matches!(c, Command::PublishCorrection(_)))
        .count()
}

#[test]
fn an_end_of_plan_at_a_blockage_waits_until_the_blockage_has_stood_its_hold() {
    let (mut e, _) = assigned();
    let hold_ms = (WatchParams::default().end_hold_s * 1e3) as u64;
    // Blocked at 1 s and still at 5 s: held; cleared at 6 s (the walker went): the hold starts again.
    // While held the plan's status says `blocked` (published when it begins and ends), else `watching`.
    use WatchHealth::{Blocked, Watching};
    for (t, outcome, expect, health, health_published) in [
        (1_000, ending_skip(), 0, Blocked, true),
        (5_000, ending_skip(), 0, Blocked, false),
        (6_000, CheckOutcome::Clear, 0, Watching, true),
        (7_000, ending_skip(), 0, Blocked, true),
        (7_000 + hold_ms - 300, ending_skip(), 0, Blocked, false),
        (7_000 + hold_ms, ending_skip(), 1, Watching, true),
    ] {
        assert_eq!(
            checks(&e.handle(pose(0.5), t).expect("pose")).len(),
            1,
            "a check at {t}"
        );
        let cmds = e.handle(finished(1, outcome), t).expect("done");
        assert_eq!(published(&cmds), expect, "at {t} ms");
        assert_eq!(e.plan("p-1").and_then(|p| p.watch), Some(health), "at {t} ms");
        let said = cmds
            .iter()
            .any(|c| matches!(c, Command::Publish(PlanEvent::Status(s)) if s.watch == Some(health)));
        assert_eq!(said, health_published, "status {health:?} published at {t} ms");
    }
    assert_eq!(
        e.plan("p-1").map(|p| p.version),
        Some(2),
        "the end was sent once it had stood"
    );
}

#[test]
fn a_new_assignment_starts_its_own_hold() {
    let (mut e, doc) = assigned();
    e.handle(pose(0.5), 1_000).expect("pose");
    assert_eq!(
        published(&e.handle(finished(1, ending_skip()), 1_000).expect("done")),
        0
    );
    // The same plan assigned again much later: a blockage now is new, not one that has stood since 1 s.
    let later = 1_000 + 2 * (WatchParams::default().end_hold_s * 1e3) as u64;
    e.handle(
        Event::AssignPlan {
            plan_id: "p-1".into(),
            robot: "r1".into(),
            doc,
        },
        later,
    )
    .expect("assigned again");
    e.handle(pose(0.5), later + 300).expect("pose");
    assert_eq!(
        published(&e.handle(finished(1, ending_skip()), later + 300).expect("done")),
        0
    );
}

#[test]
fn a_zero_hold_ends_the_plan_at_once_and_other_corrections_are_never_held() {
    let mut e = Engine::new(EngineConfig {
        watch: WatchParams {
            end_hold_s: 0.0,
            ..WatchParams::default()
        },
        ..EngineConfig::default()
    });
    e.handle(super::tests::site_event("s"), 0).expect("site");
    let (mut e, _) = assigned_with(e);
    e.handle(pose(0.5), 1000).expect("pose");
    assert_eq!(published(&e.handle(finished(1, ending_skip()), 1001).expect("done")), 1);
    let (mut e, _) = assigned();
    e.handle(pose(0.5), 1000).expect("pose");
    assert_eq!(
        published(&e.handle(finished(1, proposal(2, 5, 1)), 1001).expect("done")),
        1
    );
}

#[test]
fn watching_can_be_switched_off() {
    let mut e = Engine::new(EngineConfig {
        watch: WatchParams {
            enabled: false,
            ..WatchParams::default()
        },
        ..EngineConfig::default()
    });
    e.handle(super::tests::site_event("s"), 0).expect("site");
    let (mut e, _) = assigned_with(e);
    assert!(checks(&e.handle(pose(0.5), 1000).expect("pose")).is_empty());
}

proptest! {
    /// Whatever proposals arrive (stale or current), the corrections the engine stores, applied in order to
    /// the assigned document, give exactly the document it shows as current.
    #[test]
    fn stored_corrections_replay_to_the_current_version(
        ops in prop::collection::vec((any::<bool>(), 0usize..8, 0usize..4, 0usize..4), 1..12)
    ) {
        let (mut e, assigned_doc) = assigned();
        e.handle(pose(0.5), 1000).expect("pose");
        let mut version = 1;
        let mut len = assigned_doc.waypoints.len();
        let mut stored = Vec::new();
        let mut shown = assigned_doc.clone();
        for (k, (stale, a, span, n)) in ops.into_iter().enumerate() {
            let from = a.min(len);
            let to = (from + span).min(len);
            let base = if stale && version > 1 { version - 1 } else { version };
            let c = e.handle(finished(base, proposal(from, to, n)), 1001 + k as u64).expect("done");
            for cmd in &c {
                if let Command::StoreCorrection { correction, doc, .. } = cmd {
                    stored.push(correction.clone());
                    shown = doc.clone();
                    version = doc.version;
                    len = doc.waypoints.len();
                }
            }
        }
        let mut replayed = (*assigned_doc).clone();
        for c in &stored {
            replayed = c.apply(&replayed).expect("applies in order");
        }
        prop_assert_eq!(&replayed, &*shown);
        prop_assert_eq!(e.plan("p-1").map(|r| r.version), Some(shown.version));
    }
}
