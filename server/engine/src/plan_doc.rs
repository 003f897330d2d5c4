//! Planner output → the plan document of DESIGN §5.1.

use shift_planner::geom::Point2;
use shift_planner::pipeline::{PlanOutput, Waypoint, WaypointKind};
use shift_planner::space::CoverageSpace;
use shift_planner::speed::SpeedProfile;
use shift_proto::{PlanDocument, PlanMetricsDoc, RegionDoc, WaypointDoc, WaypointKindDoc};

/// Builds the wire document from the plan (regions) and its speed profile (the smoothed, timed waypoints:
/// v in m/s, t in seconds from the start, and the metrics of that path). `with_dwell` adds the dwell
/// uniformity figures (when an attribute map was given). `space` (what was planned in) gives the areas.
pub fn to_document(
    plan_id: &str,
    (space, out): (&CoverageSpace, &PlanOutput),
    profile: &SpeedProfile,
    with_dwell: bool,
    compute_ms: f64,
) -> PlanDocument {
    let waypoints = profile
        .waypoints
        .iter()
        .map(|w| WaypointDoc {
            x: w.waypoint.position.x,
            y: w.waypoint.position.y,
            z: 0.0,
            v: w.speed_mps,
            t: w.time_s,
            kind: match w.waypoint.kind {
                WaypointKind::Cover => WaypointKindDoc::Cover,
                WaypointKind::Transit => WaypointKindDoc::Transit,
            },
            region: w.waypoint.region,
        })
        .collect();
    let m = &profile.metrics;
    PlanDocument {
        plan_id: plan_id.to_owned(),
        version: 1,
        frame: "map".into(),
        waypoints,
        regions: out
            .regions
            .iter()
            .map(|r| RegionDoc {
                id: r.id,
                polygon: r.polygon.iter().map(|p| [p.x, p.y]).collect(),
            })
            .collect(),
        metrics: PlanMetricsDoc {
            coverage_pct: m.coverage_pct,
            overlap_pct: m.overlap_pct,
            length_m: m.length_m,
            turns: m.turns as u64,
            collisions: m.collisions as u64,
            duration_s: profile.dwell.duration_s,
            dwell_cv: with_dwell.then_some(profile.dwell.dwell_cv),
            dwell_cv_const_speed: with_dwell.then_some(profile.dwell.dwell_cv_const_speed),
            compute_ms,
            reachable_area_m2: Some(space.reachable_area_m2()),
            coverable_area_m2: Some(space.coverable_area_m2()),
            free_area_m2: Some(space.free_area_m2()),
        },
    }
}

/// A plan document's waypoint as the planner's (the inverse of the mapping in [`to_document`], z left out).
pub fn waypoint_from_doc(w: &WaypointDoc) -> Waypoint {
    Waypoint {
        position: Point2::new(w.x, w.y),
        kind: match w.kind {
            WaypointKindDoc::Cover => WaypointKind::Cover,
            WaypointKindDoc::Transit => WaypointKind::Transit,
        },
        region: w.region,
    }
}
