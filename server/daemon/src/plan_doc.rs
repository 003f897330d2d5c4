//! Planner output → the plan document of DESIGN §5.1.

use shift_planner::pipeline::{PlanOutput, WaypointKind};
use shift_proto::{PlanDocument, PlanMetricsDoc, RegionDoc, WaypointDoc, WaypointKindDoc};

/// Builds the wire document. Until speed profiles land, every waypoint gets the constant `speed_mps` and `t`
/// is the arc length divided by it.
pub fn to_document(plan_id: &str, out: &PlanOutput, speed_mps: f64, compute_ms: f64) -> PlanDocument {
    let mut s = 0.0;
    let mut prev: Option<shift_planner::geom::Point2> = None;
    let waypoints = out
        .waypoints
        .iter()
        .map(|w| {
            if let Some(p) = prev {
                s += (w.position - p).norm();
            }
            prev = Some(w.position);
            WaypointDoc {
                x: w.position.x,
                y: w.position.y,
                z: 0.0,
                v: speed_mps,
                t: s / speed_mps,
                kind: match w.kind {
                    WaypointKind::Cover => WaypointKindDoc::Cover,
                    WaypointKind::Transit => WaypointKindDoc::Transit,
                },
                region: w.region,
            }
        })
        .collect();
    let m = &out.metrics;
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
            duration_s: m.length_m / speed_mps,
            compute_ms,
        },
    }
}
