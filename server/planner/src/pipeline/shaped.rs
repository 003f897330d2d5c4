//! Plans whose speeds follow an attribute map (RFICP): the strategy is chosen by what the robot will do.
//!
//! The portfolio ranks strategies by the request's objective (estimated driving time by default), which
//! is right when the robot drives as fast as its limits allow. With an attribute map the dwell uniformity
//! matters too, and it depends on the path's shape in ways the estimate cannot see: every sharp corner is a
//! slow-down the attribute did not ask for. So the best few strategies that meet the coverage bar and keep
//! overlap within [`super::OVERLAP_BAR_PCT`] are linked and profiled in rank order. Among those whose dwell
//! reaches [`DWELL_GOAL_RATIO`] the fastest wins under the time objective (the estimate that ranked them
//! cannot see the slow-downs the attribute asks for), the best-ranked under the others. When none reaches
//! it, the strategies the portfolio holds in reserve on large sites get their chance, and failing that the
//! most uniform dwell relative to constant speed wins. Region-ready calls are held back until the winner is
//! known and then replayed for it alone, so what a client was told is always the final plan.

use std::collections::VecDeque;

use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use crate::space::CoverageSpace;
use crate::speed::attribute::AttributeMap;
use crate::speed::{SpeedParams, SpeedProfile, profile_path};

use super::assemble::assemble;
use super::portfolio::{coverage_bar, economical, prepare_ranked};
use super::prepare::Prepared;
use super::{Objective, PlanMonitor, PlanOutput, PlanParams, RegionSummary, plan};

/// At most this many strategies are linked and profiled.
pub const SHAPED_CANDIDATES: usize = 3;

/// The speed profile's goal: a dwell CV at most this share of the same path's at constant speed (RFICP
/// halves the spread of coverage against the attribute's demand).
pub const DWELL_GOAL_RATIO: f64 = 0.5;

/// Plans `space` (see [`plan`]) and profiles the result with `attribute` and `speed`. Without an attribute
/// map this is [`plan`] followed by [`profile_path`]; with one, see the module docs.
pub fn plan_shaped(
    space: &CoverageSpace,
    params: &PlanParams,
    attribute: Option<&AttributeMap>,
    speed: &SpeedParams,
    monitor: &mut dyn PlanMonitor,
) -> Result<(PlanOutput, SpeedProfile)> {
    let Some(attr) = attribute else {
        let out = plan(space, params, monitor)?;
        let profile = profile_path(space, &out.waypoints, None, speed)?;
        return Ok((out, profile));
    };
    let target = coverage_bar(params);
    let mut ranked = prepare_ranked(space, params, monitor)?;
    let worth = |p: &Prepared| economical(p.estimate.coverage_pct, p.estimate.overlap_pct, target);
    // The first-ranked plan always; others only when they are economical too.
    let mut queue: VecDeque<Prepared> = VecDeque::new();
    let mut reserve_asked = false;
    let first_ok = ranked.prepared.first().is_some_and(worth);
    for (k, p) in std::mem::take(&mut ranked.prepared).into_iter().enumerate() {
        if k == 0 || (first_ok && worth(&p)) {
            queue.push_back(p);
        }
    }
    // (dwell ratio, duration, plan, profile, held region calls) of the best candidate so far.
    let mut best: Option<(f64, f64, PlanOutput, SpeedProfile, Vec<Announced>)> = None;
    let time = params.objective == Objective::Time;
    let mut tried = 0;
    while tried < SHAPED_CANDIDATES {
        let Some(prepared) = queue.pop_front() else {
            // Nothing reached the goal: the strategies held in reserve get their chance.
            if reserve_asked || !first_ok || best.as_ref().is_some_and(|b| b.0 <= DWELL_GOAL_RATIO) {
                break;
            }
            reserve_asked = true;
            queue.extend(
                ranked
                    .prepare_reserve(space, params, monitor)?
                    .into_iter()
                    .filter(|p| worth(p)),
            );
            continue;
        };
        tried += 1;
        let mut held = Held {
            outer: &*monitor,
            regions: Vec::new(),
        };
        let out = assemble(space, prepared, &mut held)?;
        let regions = held.regions;
        let profile = profile_path(space, &out.waypoints, Some(attr), speed)?;
        monitor.progress(0.75 + 0.25 * tried as f64 / SHAPED_CANDIDATES as f64);
        if monitor.cancelled() {
            return Err(PlannerError::Cancelled);
        }
        let m = &profile.metrics;
        let ok = m.collisions == 0 && economical(m.coverage_pct, m.overlap_pct, target);
        let d = &profile.dwell;
        let ratio = if d.dwell_cv_const_speed > 0.0 {
            d.dwell_cv / d.dwell_cv_const_speed
        } else {
            0.0
        };
        let duration = d.duration_s;
        let wins = match &best {
            None => true,
            Some((b, b_duration, ..)) => {
                ok && if *b <= DWELL_GOAL_RATIO {
                    // Both reach the goal: under the time objective the faster one (the estimate that ranked
                    // them knows nothing of the slow-downs the attribute asks for); else the earlier one.
                    time && ratio <= DWELL_GOAL_RATIO && duration + 1e-9 < *b_duration
                } else {
                    ratio + 1e-9 < *b
                }
            }
        };
        if wins {
            best = Some((ratio, duration, out, profile, regions));
        }
        // Candidates come best-ranked first: unless time decides among those that reach the goal, the first
        // that reaches it is the one.
        if !time && best.as_ref().is_some_and(|b| b.0 <= DWELL_GOAL_RATIO) {
            break;
        }
    }
    monitor.progress(1.0);
    let (_, _, out, profile, regions) = best.ok_or(PlannerError::Cancelled)?;
    for (summary, path) in &regions {
        monitor.region_ready(summary, path);
    }
    Ok((out, profile))
}

/// A region-ready call: the region and its path.
type Announced = (RegionSummary, Vec<Point2>);

/// A monitor that passes cancellation through and holds region-ready calls back.
struct Held<'a> {
    outer: &'a dyn PlanMonitor,
    regions: Vec<Announced>,
}

impl PlanMonitor for Held<'_> {
    fn cancelled(&self) -> bool {
        self.outer.cancelled()
    }

    fn region_ready(&mut self, region: &RegionSummary, path: &[Point2]) {
        self.regions.push((region.clone(), path.to_vec()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::tests::random_space;
    use crate::pipeline::NoMonitor;
    use crate::speed::SpeedLimits;

    /// Records which regions were announced.
    #[derive(Default)]
    struct Announcements(Vec<u32>);

    impl PlanMonitor for Announcements {
        fn region_ready(&mut self, region: &RegionSummary, _path: &[Point2]) {
            self.0.push(region.id);
        }
    }

    #[test]
    fn the_chosen_plan_is_the_one_announced_and_profiled() {
        let space = random_space(5, 70, 50, 6).expect("space");
        let g = *space.geometry();
        // Dirt rising from left to right.
        let values: Vec<f64> = (0..g.len())
            .map(|i| 0.1 + 0.9 * g.cell(i).x as f64 / g.width as f64)
            .collect();
        let attr = AttributeMap::from_values(g, values).expect("attribute");
        let speed = SpeedParams::new(SpeedLimits::default(), space.robot.tool_width_m);
        let params = PlanParams::default();
        let mut heard = Announcements::default();
        let (out, profile) = plan_shaped(&space, &params, Some(&attr), &speed, &mut heard).expect("plan");
        let ids: Vec<u32> = out.regions.iter().map(|r| r.id).collect();
        assert_eq!(heard.0, ids, "announced once, in visiting order, for the plan returned");
        let again = profile_path(&space, &out.waypoints, Some(&attr), &speed).expect("profile");
        assert_eq!(profile.dwell, again.dwell);
        assert_eq!(profile.metrics, again.metrics);
        let m = &profile.metrics;
        assert!(m.collisions == 0 && m.coverage_pct >= 99.0, "{m:?}");
        // Without an attribute map it is the plain plan.
        let (plain, _) = plan_shaped(&space, &params, None, &speed, &mut NoMonitor).expect("plan");
        assert_eq!(
            plain.points(),
            plan(&space, &params, &mut NoMonitor).expect("plan").points()
        );
    }
}
