//! Resuming a robot's plan (issue 20, resume and replan): when the robots that share a site's remainder are
//! the robots whose plans made it (after a restart, a reconnection, or a replan asked for with nobody lost),
//! their own plans still hold the best way to cover it. Planning the remainder from scratch costs what a
//! whole plan costs (seconds on a large site) and gives paths that differ from the ones the robots were
//! driving for no gain; resuming costs a walk along the plan.
//!
//! **The rule.** The previous path is cut into pieces no longer than a tool width. A piece is kept when its
//! swath (the tool's capsule along it, DESIGN §6) is mostly ground the cleaned remainder
//! ([`crate::remainder`]) still holds: at least `RemainderParams::min_new_share` of it (default half), the
//! remainder's own "a pass worth driving" share, so the two rules cannot drift apart. Then, so that nothing
//! the previous path would have covered is lost, a piece is kept too when it sweeps a kept cell no kept
//! piece sweeps. Consecutive kept pieces form runs. The runs ahead of the robot keep the
//! plan's order (it was optimised for the whole site, and any tail of a good tour is a good tour of its
//! stops); runs behind it (stretches the robot missed: a blocked lane the corrections skipped) are put
//! where they add least (cheapest insertion, either direction). Runs are joined by a link no longer than the
//! plan's own way between them ([`crate::link::Linker::link_within`] bounded by that length), or by that
//! way; from the robot to the first run and to the dock by a link search.
//!
//! **When it does not apply** ([`resume_fleet`] answers [`FleetResume::Refused`] and the caller divides
//! the remainder again): a robot with a footprint (its links would need the polygon's checks), a link that
//! cannot be found, ground the previous paths swept that the resumed ones no longer sweep over
//! [`ResumeParams::max_unswept_share`] of what is left once cleaned by the remainder's rule (ground a live
//! obstacle now covers, stretches out of reach), or remaining durations so uneven that a new division
//! would finish sooner: the longest over [`ResumeParams::max_over_mean`] times the mean (a division can at
//! best give every robot the mean; the balance bar is 1.15).
//!
//! **A robot lost with its plan unfinished** ([`Lost`]) needs no new division either: its plan is resumed
//! like the others' and its work handed to the robots of its shape (`handover.rs`); the same checks apply
//! after that.

mod handover;
mod path;
#[cfg(test)]
mod tests;

pub use handover::Lost;
pub use path::{ResumedPath, resume_path};

use crate::decompose::DecompositionMethod;
use crate::divide::{Division, FleetRobot, NO_OWNER};
use crate::error::Result;
use crate::geom::Point2;
use crate::map::OccupancyGrid;
use crate::metrics::coverage::for_each_cell_in_capsule;
use crate::parallel::map_indexed;
use crate::pattern::PatternMethod;
use crate::remainder::{Remainder, RemainderParams, remainder};
use crate::smooth::SmoothParams;
use crate::space::CoverageSpace;
use crate::speed::attribute::AttributeMap;
use crate::speed::estimate::drive_timeline;
use crate::speed::{SpeedParams, SpeedProfile, profile_path};

use super::fleet::{FleetPlan, fleet_metrics};
use super::remainder::{FleetRemainderPlan, RemainderPlan, remainder_space};
use super::{PlanOutput, PlanStats, Waypoint, WaypointKind};

/// Knobs of [`resume_fleet`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResumeParams {
    /// Largest share of the kept remainder the resumed paths may leave unswept (after cleaning what they
    /// leave by the remainder's rule).
    pub max_unswept_share: f64,
    /// Largest remaining duration over the fleet's mean that still resumes.
    pub max_over_mean: f64,
}

impl Default for ResumeParams {
    fn default() -> Self {
        Self {
            // A hundredth: DESIGN §6's coverage bar (99 %) applied to what is left.
            max_unswept_share: 0.01,
            max_over_mean: 1.15,
        }
    }
}

/// One robot's previous plan and where it is on it.
#[derive(Debug, Clone, Copy)]
pub struct Previous<'a> {
    /// The path it was driving (from its dock back to it).
    pub path: &'a [Waypoint],
    /// The last waypoint it reached.
    pub reached: usize,
    /// Where it is.
    pub from: Point2,
}

/// The plan output of a resumed `path` on `rspace` and its profile; the output's metrics are the profile's
/// (DESIGN §6 of the path as driven, counting `rspace.coverable`: one evaluation, not two).
fn resumed_output(
    rspace: &CoverageSpace,
    path: &ResumedPath,
    attribute: Option<&AttributeMap>,
    speed: &SpeedParams,
) -> Result<(PlanOutput, SpeedProfile)> {
    let mut stats = PlanStats::default();
    for w in path.waypoints.windows(2) {
        let d = (w[1].position - w[0].position).norm();
        match w[1].kind {
            WaypointKind::Cover => stats.pattern_m += d,
            WaypointKind::Transit => stats.transit_m += d,
        }
    }
    let mut warnings = rspace.warnings.clone();
    warnings.push(format!(
        "resumed: {} stretches of the previous plan ({:.0} m) still sweep what is left{}",
        path.runs,
        path.reused_m,
        if path.inserted > 0 {
            format!(", {} of them missed earlier and put back on the way", path.inserted)
        } else {
            String::new()
        }
    ));
    let profile = profile_path(rspace, &path.waypoints, attribute, speed)?;
    let output = PlanOutput {
        metrics: profile.metrics,
        waypoints: path.waypoints.clone(),
        regions: Vec::new(),
        labels: Vec::new(),
        stats,
        // The previous plan's strategy goes on; these name no new choice.
        decomposition: DecompositionMethod::Auto,
        pattern: PatternMethod::Lanes,
        lane_placement: None,
        warnings,
    };
    Ok((output, profile))
}

/// The replan space of `rem` for the robot of `previous` and its resumed path on it (`None`: see
/// [`resume_path`]).
fn resume_on(
    space: &CoverageSpace,
    rem: &Remainder,
    previous: Previous<'_>,
    remainder_params: &RemainderParams,
) -> Result<Option<(CoverageSpace, ResumedPath)>> {
    let rspace = remainder_space(space, rem, previous.from)?;
    Ok(resume_path(
        space,
        &rem.keep,
        previous.path,
        (previous.reached, rspace.start),
        remainder_params.min_new_share,
    )
    .map(|path| (rspace, path)))
}

/// Resumes one robot's plan on `space` given the `covered` flags (one per grid cell): the cleaned remainder
/// and the resumed path, its metrics counted against the whole remainder. `None` when it cannot be resumed
/// (see the module docs; the caller plans the remainder instead, [`super::remainder::plan_remainder`]).
pub fn plan_resume(
    space: &CoverageSpace,
    covered: &[bool],
    previous: Previous<'_>,
    remainder_params: &RemainderParams,
    attribute: Option<&AttributeMap>,
    speed: &SpeedParams,
) -> Result<Option<(RemainderPlan, ResumedPath)>> {
    let rem = remainder(space, covered, remainder_params)?;
    let Some((rspace, path)) = resume_on(space, &rem, previous, remainder_params)? else {
        return Ok(None);
    };
    let (plan, profile) = resumed_output(&rspace, &path, attribute, speed)?;
    Ok(Some((
        RemainderPlan {
            remainder: rem,
            space: rspace,
            plan,
            profile,
        },
        path,
    )))
}

/// What [`resume_fleet`] decided.
#[derive(Debug, Clone)]
pub enum FleetResume {
    /// Every robot's plan resumed.
    Resumed(Box<FleetRemainderPlan>),
    /// The remainder is better divided again, for the reason given (a remark for the user).
    Refused(String),
}

/// Resumes every robot's plan on `grid` (see the module docs), or says why the fleet's remainder is better
/// divided again. `robots[k].start` is ignored (each robot starts where `previous[k]` says it is).
///
/// The caller's part: `previous` holds the plans of *every* robot that goes on, and `lost` those of the robots
/// lost with their plans unfinished: their work is handed over to the robots of their shape
/// (`handover.rs`). A robot joining without a plan changes the fleet the other way; its share is for a new
/// division (this function cannot see a plan it is not given). The ground of a lost plan not given here
/// counts as ground the resumed paths no longer sweep.
pub fn resume_fleet(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    (previous, lost): (&[Previous<'_>], &[Lost<'_>]),
    covered: &[bool],
    remainder_params: &RemainderParams,
    attribute: Option<&AttributeMap>,
    params: &ResumeParams,
) -> Result<FleetResume> {
    let refused = |why: &str| Ok(FleetResume::Refused(format!("not resumed: {why}")));
    if robots.is_empty() || robots.len() != previous.len() {
        return refused("a robot has no plan to resume");
    }
    if robots
        .iter()
        .chain(lost.iter().map(|l| l.robot))
        .any(|r| r.footprint.is_some())
    {
        return refused("a robot has a footprint");
    }
    let g = grid.geometry;
    let mut coverable = vec![false; g.len()];
    let mut owner = vec![NO_OWNER; g.len()];
    let mut swept_any = covered.to_vec();
    let (mut parts, mut plans, mut remainders) = (Vec::new(), Vec::new(), Vec::new());
    // Robots of one shape standing on one reachable set share a space and a remainder (neither depends on
    // where on it the robot stands).
    let mut spaces: Vec<(CoverageSpace, Remainder)> = Vec::new();
    let mut space_of = Vec::with_capacity(robots.len());
    for (robot, prev) in robots.iter().zip(previous) {
        let on = |s: &CoverageSpace| g.locate(prev.from).is_some_and(|c| s.reachable[g.index(c)]);
        let at = match spaces
            .iter()
            .position(|(space, _)| space.robot == robot.shape && on(space))
        {
            Some(at) => at,
            None => {
                let space = CoverageSpace::new(grid.clone(), robot.shape, prev.from)?;
                let rem = remainder(&space, covered, remainder_params)?;
                for (c, &keep) in coverable.iter_mut().zip(&rem.keep) {
                    *c |= keep;
                }
                spaces.push((space, rem));
                spaces.len() - 1
            }
        };
        space_of.push(at);
    }
    // One speed law for the whole fleet, over all that is left (as a division's plans get it).
    let attribute_range = attribute.and_then(|a| a.range_over(&coverable));
    let speed_of = |robot: &FleetRobot| SpeedParams {
        attribute_range,
        ..SpeedParams::new(robot.limits, robot.shape.tool_width_m)
    };
    let mut resumed: Vec<(CoverageSpace, ResumedPath)> = Vec::with_capacity(robots.len());
    let walked = map_indexed(previous.len(), |k| {
        let (space, rem) = &spaces[space_of[k]];
        resume_on(space, rem, previous[k], remainder_params)
    });
    for one in walked {
        let Some((mut rspace, path)) = one? else {
            return refused("a robot cannot reach what its plan has left");
        };
        for (i, &s) in path.swept.iter().enumerate() {
            swept_any[i] |= s;
        }
        // Its share: the kept cells it sweeps (its metrics count against these).
        rspace.coverable = path.swept.clone();
        resumed.push((rspace, path));
    }
    let profile_of = |k: usize, (rspace, path): &(CoverageSpace, ResumedPath)| {
        resumed_output(rspace, path, attribute, &speed_of(&robots[k]))
    };
    // A path's time for the handover's split: without an attribute map the fastest drive the limits allow
    // (the profile's duration where smoothing rounds every corner, for a fraction of its cost); with one the
    // profile, which follows the attribute. Sample by sample: (arc length, seconds).
    let timeline = |robot: &FleetRobot, rspace: &CoverageSpace, path: &ResumedPath| -> Result<Vec<(f64, f64)>> {
        let speed = speed_of(robot);
        let w = robot.shape.tool_width_m;
        if attribute.is_none() {
            let smooth = speed.smooth.unwrap_or_else(|| SmoothParams::for_tool(w));
            return Ok(drive_timeline(
                &path.waypoints,
                &robot.limits,
                &smooth,
                speed.spacing_for(w),
            ));
        }
        let (_, profile) = resumed_output(rspace, path, attribute, &speed)?;
        Ok(profile.waypoints.iter().map(|w| (w.arc_m, w.time_s)).collect())
    };
    let duration_of = |k: usize, (rspace, path): &(CoverageSpace, ResumedPath)| {
        timeline(&robots[k], rspace, path).map(|t| t.last().map_or(0.0, |&(_, t)| t))
    };
    let mut handed_m2 = 0.0;
    if !lost.is_empty() {
        let mut durations_s = (resumed.iter().enumerate())
            .map(|(k, r)| duration_of(k, r))
            .collect::<Result<Vec<f64>>>()?;
        for l in lost {
            let view = handover::Resumed {
                paths: &mut resumed,
                durations_s: &durations_s,
                space_of: &space_of,
                robots,
            };
            let chain_time = |space: &CoverageSpace, rem: &Remainder, path: &ResumedPath| {
                if attribute.is_none() {
                    // (The space is read only to profile with an attribute.)
                    return timeline(l.robot, space, path);
                }
                let from = path.waypoints.first().map_or(space.start, |w| w.position);
                let mut rspace = remainder_space(space, rem, from)?;
                rspace.coverable = path.swept.clone();
                timeline(l.robot, &rspace, path)
            };
            let cells = match handover::hand_over(l, &spaces, view, &swept_any, remainder_params, chain_time)? {
                Ok(cells) => cells,
                Err(why) => return refused(&why),
            };
            for (k, taken) in cells.into_iter().enumerate() {
                if taken.is_empty() {
                    continue;
                }
                for &i in &taken {
                    swept_any[i] = true;
                    resumed[k].1.swept[i] = true;
                    resumed[k].0.coverable[i] = true;
                }
                handed_m2 += taken.len() as f64 * g.resolution * g.resolution;
                durations_s[k] = duration_of(k, &resumed[k])?;
            }
        }
    }
    let profiled = map_indexed(resumed.len(), |k| profile_of(k, &resumed[k]))
        .into_iter()
        .collect::<Result<Vec<_>>>()?;
    for (k, ((rspace, _), (output, profile))) in resumed.into_iter().zip(profiled).enumerate() {
        for (i, &s) in rspace.coverable.iter().enumerate() {
            if s && owner[i] == NO_OWNER {
                owner[i] = k as u32;
            }
        }
        let owned = rspace.coverable.iter().filter(|&&s| s).count() as f64 * g.resolution * g.resolution;
        parts.push(crate::divide::Part {
            space: rspace,
            load_s: profile.dwell.duration_s,
            owned_area_m2: owned,
        });
        plans.push((output, profile));
        remainders.push(spaces[space_of[k]].1.clone());
    }
    // What the previous paths swept but no resumed path sweeps (pieces a live obstacle now blocks, stretches
    // out of reach), cleaned by the remainder's own rule. Ground outside every previous path's swath is not
    // counted: the plans' own misses along walls were left out when they were made.
    let kept = coverable.iter().filter(|&&c| c).count();
    let bound = params.max_unswept_share * kept as f64;
    let unswept = (0..g.len()).filter(|&i| coverable[i] && !swept_any[i]).count();
    // Each step below only drops cells from the count: within the bound at any step, within it at the end
    // (and the passes over the grid after it are spared).
    let left = if unswept as f64 <= bound {
        unswept
    } else {
        let mut held = vec![false; g.len()];
        let lost_plans = lost.iter().map(|l| (l.robot, &l.previous));
        for (robot, prev) in robots.iter().zip(previous).chain(lost_plans) {
            let half = robot.shape.tool_width_m / 2.0;
            for w in prev.path.windows(2) {
                for_each_cell_in_capsule(&g, w[0].position, w[1].position, half, |i| held[i] = true);
            }
        }
        let done: Vec<bool> = (0..g.len()).map(|i| swept_any[i] || !held[i]).collect();
        let raw = (0..g.len()).filter(|&i| coverable[i] && !done[i]).count();
        if raw as f64 <= bound {
            raw
        } else {
            (spaces.iter())
                .map(|(space, _)| remainder(space, &done, remainder_params).map(|r| r.kept_cells))
                .sum::<Result<usize>>()?
        }
    };
    if kept > 0 && left as f64 > bound {
        return refused(&format!(
            "the robots' plans can no longer sweep {:.1} m² of the {:.1} m² left (a live obstacle, or no way there)",
            left as f64 * g.resolution * g.resolution,
            kept as f64 * g.resolution * g.resolution
        ));
    }
    let durations: Vec<f64> = plans.iter().map(|(_, p)| p.dwell.duration_s).collect();
    let mean = durations.iter().sum::<f64>() / durations.len() as f64;
    let longest = durations.iter().copied().fold(0.0, f64::max);
    if robots.len() > 1 && longest > params.max_over_mean * mean {
        return refused(&format!(
            "the longest resumed plan ({longest:.0} s) is {:.2} × the mean ({mean:.0} s)",
            longest / mean
        ));
    }
    let division = Division {
        owner,
        coverable,
        parts,
        weights: vec![0.0; robots.len()],
        warnings: vec![format!(
            "resumed each robot's plan (no new division){}: the longest has {longest:.0} s left, {:.2} × the mean",
            if lost.is_empty() {
                String::new()
            } else {
                format!(
                    ", the unfinished lanes of {} lost robot(s) handed over ({handed_m2:.1} m²)",
                    lost.len()
                )
            },
            if mean > 0.0 { longest / mean } else { 1.0 }
        )],
    };
    let metrics = fleet_metrics(&division, &plans);
    Ok(FleetResume::Resumed(Box::new(FleetRemainderPlan {
        fleet: FleetPlan {
            division,
            plans,
            metrics,
            rounds: 0,
        },
        remainders,
    })))
}
