//! Coverage with a footprint polygon (issue 23), the simplest sound way: the disc pipeline on the space
//! built for the footprint's *inscribed* planning radius ([`Footprint::planning_radius_m`]: every place the
//! body could stand at some heading, doorways it passes lengthwise open), then the path made feasible for the
//! polygon ([`repair`]): every stretch where the polygon at the path's heading, or the turn in place at a
//! vertex, overlaps a blocked cell is replaced by a heading-lattice path, and cover it skips is missed (the
//! metrics count it against the inscribed space's coverable cells).
//!
//! Patterns go where the robot can turn at their ends ([`lanes`]): a body turning in place sweeps its
//! circumscribed disc, so lanes laid right up to the walls of the inscribed space lose their ends to the
//! repair (measured: 60 % of a 4 m room for a 1.2 × 0.8 m body, against 72 % with lanes where it turns).
//! Transits still use the whole inscribed space, and the repair takes the body through a doorway heading
//! through it.
//!
//! The result is checked pose by pose: `metrics.collisions` is DESIGN §6's footprint form
//! ([`FootprintCheck::count_collisions`]), and the planner's own checks keep an eighth of a cell to spare so
//! the motion between samples is clear too. Corner rounding (`speed::profile_path`) keeps a curve only where
//! the polygon clears it; should the profiled path still overlap a cell, it is profiled again with sharp
//! corners (turns in place, as repaired).

pub mod lanes;
pub mod repair;

pub use lanes::{LaneSpace, lane_space};

use crate::error::{PlannerError, Result};
use crate::footprint::poses::segment_heading;
use crate::footprint::{FOOTPRINT_FIELD, Footprint, FootprintCheck, LatticeParams};
use crate::geom::Point2;
use crate::metrics::evaluate;
use crate::space::CoverageSpace;
use crate::speed::attribute::AttributeMap;
use crate::speed::{SpeedParams, SpeedProfile, profile_path, profile_path_where};

use super::{PlanMonitor, PlanOutput, PlanParams, RegionSummary, Waypoint, WaypointKind, plan, plan_shaped};

/// Headings tried for the robot at its start.
const START_HEADINGS: usize = 72;

/// Plans a coverage of `space_for_inscribed` (a space whose robot radius is at least the footprint's
/// inscribed radius, normally [`Footprint::planning_radius_m`]) for a robot of `footprint`, profiled with
/// `attribute` and `speed` as [`plan_shaped`] does. The metrics' `collisions` count footprint collisions.
/// Errors name `robot.footprint` when the robot does not fit at its start at any heading, when it can reach
/// nothing to cover, or cannot get back to its start.
pub fn plan_footprinted(
    space_for_inscribed: &CoverageSpace,
    footprint: &Footprint,
    params: &PlanParams,
    attribute: Option<&AttributeMap>,
    speed: &SpeedParams,
    monitor: &mut dyn PlanMonitor,
) -> Result<(PlanOutput, SpeedProfile)> {
    plan_footprinted_with(
        space_for_inscribed,
        footprint,
        LaneSpace::Auto,
        params,
        attribute,
        speed,
        monitor,
    )
}

/// [`plan_footprinted`] with the patterns laid in the space `lanes` names ([`LaneSpace`]).
pub fn plan_footprinted_with(
    space_for_inscribed: &CoverageSpace,
    footprint: &Footprint,
    lanes: LaneSpace,
    params: &PlanParams,
    attribute: Option<&AttributeMap>,
    speed: &SpeedParams,
    monitor: &mut dyn PlanMonitor,
) -> Result<(PlanOutput, SpeedProfile)> {
    let space = space_for_inscribed;
    let refuse = |reason: String| PlannerError::InvalidParam {
        name: FOOTPRINT_FIELD,
        reason,
    };
    if space.robot.radius_m + 1e-9 < footprint.inscribed_radius_m() {
        return Err(refuse(format!(
            "the coverage space's robot radius {} m is under the footprint's inscribed radius {:.3} m",
            space.robot.radius_m,
            footprint.inscribed_radius_m()
        )));
    }
    let res = space.geometry().resolution;
    let exact = FootprintCheck::new(&space.grid, &space.clearance, footprint)?;
    let check = exact.clone().with_margin(FootprintCheck::planning_margin_m(res));
    let s = space.start;
    let fits = (0..START_HEADINGS).any(|k| {
        let yaw = k as f64 / START_HEADINGS as f64 * std::f64::consts::TAU;
        check.pose_free(s.x, s.y, yaw)
    });
    if !fits {
        return Err(refuse(format!(
            "the robot does not fit at its start ({:.2}, {:.2}) at any heading (circumscribed radius {:.2} m)",
            s.x,
            s.y,
            footprint.circumscribed_radius_m()
        )));
    }
    let (lanes_in, chosen) = lane_space(space, &check, lanes);
    let mut held = Held { outer: monitor };
    let mut out = match attribute {
        None => plan(&lanes_in, params, &mut held)?,
        Some(_) => plan_shaped(&lanes_in, params, attribute, speed, &mut held)?.0,
    };
    if monitor.cancelled() {
        return Err(PlannerError::Cancelled);
    }
    // The disc's space may have moved its start: the robot drives there from the dock and back.
    if lanes_in.start != s {
        let dock = Waypoint {
            position: s,
            kind: WaypointKind::Transit,
            region: None,
        };
        out.waypoints.insert(0, dock);
        out.waypoints.push(dock);
    }
    let (waypoints, stats) = repair::repair(&check, &out.waypoints, &LatticeParams::default())?;
    if !waypoints.iter().any(|w| w.kind == WaypointKind::Cover) {
        return Err(refuse(format!(
            "the robot reaches nothing to cover from its start ({:.2}, {:.2}): its footprint (circumscribed \
             radius {:.2} m) fits through none of the ways out",
            s.x,
            s.y,
            footprint.circumscribed_radius_m()
        )));
    }
    monitor.progress(0.9);
    let points: Vec<Point2> = waypoints.iter().map(|w| w.position).collect();
    let mut metrics = evaluate(space, &points);
    metrics.collisions = exact.count_collisions(&points);
    let (mut cover_m, mut transit_m) = (0.0, 0.0);
    for w in waypoints.windows(2) {
        let d = (w[1].position - w[0].position).norm();
        if w[1].kind == WaypointKind::Transit {
            transit_m += d;
        } else {
            cover_m += d;
        }
    }
    out.stats.transit_m = transit_m;
    out.stats.steps_m = (cover_m - out.stats.pattern_m - out.stats.passes_m).max(0.0);
    out.metrics = metrics;
    out.warnings.push(format!(
        "footprint: patterns laid {}; {} stretch(es) the polygon could not drive as planned bridged by {:.1} m \
         of lattice path, {:.1} m of the planned path left out; coverage {:.1} %",
        match chosen {
            LaneSpace::Disc => "for the circumscribed disc",
            LaneSpace::Turning => "where the circumscribed disc fits",
            _ => "for the inscribed disc",
        },
        stats.bridges,
        stats.bridge_m,
        stats.skipped_m,
        metrics.coverage_pct
    ));
    out.waypoints = waypoints;
    // A rounded corner stays only where the polygon clears it along the curve's headings.
    let corner_ok = |curve: &[Point2]| {
        let n = curve.len();
        n < 2
            || check.path_free(
                curve,
                segment_heading(curve[0], curve[1]),
                segment_heading(curve[n - 2], curve[n - 1]),
            )
    };
    let mut profile = profile_path_where(space, &out.waypoints, attribute, speed, &corner_ok)?;
    let mut collisions = exact.count_collisions(&profile.points());
    if collisions > 0 && speed.smooth.is_some() {
        let sharp = SpeedParams { smooth: None, ..*speed };
        profile = profile_path(space, &out.waypoints, attribute, &sharp)?;
        collisions = exact.count_collisions(&profile.points());
    }
    profile.metrics.collisions = collisions;
    announce(&out, monitor);
    monitor.progress(1.0);
    Ok((out, profile))
}

/// Announces each region of the repaired path: from the end of the transit into it to its last cover
/// waypoint (regions whose cover was all left out are not announced).
fn announce(out: &PlanOutput, monitor: &mut dyn PlanMonitor) {
    for region in &out.regions {
        let mut on = out
            .waypoints
            .iter()
            .enumerate()
            .filter(|(_, w)| w.region == Some(region.id) && w.kind == WaypointKind::Cover)
            .map(|(i, _)| i);
        let Some(first) = on.next() else { continue };
        let last = on.next_back().unwrap_or(first);
        let path: Vec<Point2> = out.waypoints[first.saturating_sub(1)..=last]
            .iter()
            .map(|w| w.position)
            .collect();
        monitor.region_ready(region, &path);
    }
}

/// A monitor that passes progress (scaled into the first 90 %) and cancellation through and holds back the
/// disc plan's region-ready calls (the repaired path is announced instead).
struct Held<'a> {
    outer: &'a mut dyn PlanMonitor,
}

impl PlanMonitor for Held<'_> {
    fn progress(&mut self, fraction: f64) {
        self.outer.progress(0.85 * fraction);
    }

    fn cancelled(&self) -> bool {
        self.outer.cancelled()
    }

    fn region_ready(&mut self, _region: &RegionSummary, _path: &[Point2]) {}
}

#[cfg(test)]
mod tests;
