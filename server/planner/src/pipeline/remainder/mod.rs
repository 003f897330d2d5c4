//! Replanning what is left of a site (issue 20, resume and replan): the cleaned remainder
//! ([`crate::remainder`]) planned with the ordinary pipeline, for one robot ([`plan_remainder`]) or a fleet
//! ([`plan_fleet_remainder`]).
//!
//! The replan's space keeps the robot's whole reachable set (it drives across covered ground to the places
//! left) but has only the kept cells to cover and lays its patterns on the work zone alone
//! ([`CoverageSpace::with_work`]): each piece of the remainder is a region of its own (or several), its
//! lanes sit half a tool inside its boundary with covered ground, and the visiting order and links join
//! them as they join any regions.

use crate::divide::FleetRobot;
use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use crate::map::OccupancyGrid;
use crate::remainder::{Remainder, RemainderParams, remainder};
use crate::space::CoverageSpace;
use crate::speed::attribute::AttributeMap;
use crate::speed::{SpeedParams, SpeedProfile};

use super::fleet::{FleetParams, FleetPlan, plan_fleet_with};

#[cfg(test)]
pub(crate) mod tests;
use super::{PlanMonitor, PlanOutput, PlanParams, plan_shaped};

/// A robot's replan.
#[derive(Debug, Clone)]
pub struct RemainderPlan {
    /// What was left to cover, cleaned, with its figures.
    pub remainder: Remainder,
    /// The space the replan was made on (only the kept cells coverable; see the module docs).
    pub space: CoverageSpace,
    /// The plan, from `from` back to it.
    pub plan: PlanOutput,
    /// Its speed profile.
    pub profile: SpeedProfile,
}

/// The replan space of `remainder` on `space`, the robot starting at `from` (snapped to the nearest
/// reachable cell's centre, with a warning, when it is not on the reachable set with the robot's
/// clearance). Errors: `from` off the map or not finite, or a space with nothing reachable.
pub fn remainder_space(space: &CoverageSpace, remainder: &Remainder, from: Point2) -> Result<CoverageSpace> {
    crate::error::finite("from x", from.x)?;
    crate::error::finite("from y", from.y)?;
    let g = *space.geometry();
    let cell = g
        .locate(from)
        .ok_or(PlannerError::StartOutsideMap { x: from.x, y: from.y })?;
    let r = space.robot.radius_m - 1e-9;
    let (start_cell, start, warning) = if space.reachable[g.index(cell)] && space.clearance_at(from) >= r {
        (cell, from, None)
    } else {
        let best = (0..g.len())
            .filter(|&i| space.reachable[i])
            .min_by(|&a, &b| {
                (g.center_of(a) - from)
                    .norm()
                    .total_cmp(&(g.center_of(b) - from).norm())
            })
            .ok_or(PlannerError::NoTraversableSpace {
                radius_m: space.robot.radius_m,
            })?;
        let p = g.center_of(best);
        let note = format!(
            "the replan starts at ({:.3}, {:.3}), {:.3} m from ({:.3}, {:.3}), which is not reachable with the robot's clearance",
            p.x,
            p.y,
            (p - from).norm(),
            from.x,
            from.y
        );
        (g.cell(best), p, Some(note))
    };
    let mut out = space.with_work(start_cell, start, &remainder.keep, &remainder.work);
    out.warnings.extend(warning);
    out.warnings.extend(remainder.warning());
    Ok(out)
}

/// Cleans the remainder of `space` given the measured `covered` flags (one per grid cell) and plans it with
/// the ordinary pipeline ([`plan_shaped`]) from `from` (the robot's position) back to it.
pub fn plan_remainder(
    space: &CoverageSpace,
    covered: &[bool],
    from: Point2,
    (params, remainder_params): (&PlanParams, &RemainderParams),
    attribute: Option<&AttributeMap>,
    speed: &SpeedParams,
    monitor: &mut dyn PlanMonitor,
) -> Result<RemainderPlan> {
    let remainder = remainder(space, covered, remainder_params)?;
    let space = remainder_space(space, &remainder, from)?;
    let (plan, profile) = plan_shaped(&space, params, attribute, speed, monitor)?;
    Ok(RemainderPlan {
        remainder,
        space,
        plan,
        profile,
    })
}

/// A fleet's replan.
#[derive(Debug, Clone)]
pub struct FleetRemainderPlan {
    /// The plans: the division was made on the uncovered cells only, and each part's space is its cleaned
    /// remainder (`division.coverable` holds the cells kept in some part).
    pub fleet: FleetPlan,
    /// Each robot's cleaned remainder, in the robots' order.
    pub remainders: Vec<Remainder>,
}

/// Divides what `covered` leaves of `grid` among `robots` (every reachable cell is still shared out, so
/// each robot drives across covered ground in its part, but only uncovered cells weigh in the balance),
/// cleans each part's remainder and plans it (as [`super::fleet::plan_fleet`] does, rounds included).
pub fn plan_fleet_remainder(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    covered: &[bool],
    (params, remainder_params): (&PlanParams, &RemainderParams),
    attribute: Option<&AttributeMap>,
    fleet: &FleetParams,
    monitor: &mut dyn PlanMonitor,
) -> Result<FleetRemainderPlan> {
    remainder_params.validate()?;
    if covered.len() != grid.cells.len() {
        return Err(PlannerError::InvalidParam {
            name: "covered",
            reason: format!(
                "needs one flag per grid cell ({}), got {}",
                grid.cells.len(),
                covered.len()
            ),
        });
    }
    let uncovered: Vec<bool> = covered.iter().map(|&c| !c).collect();
    // Each round's remainders (the best round is kept, and it need not be the last).
    let mut rounds: Vec<Vec<Remainder>> = Vec::new();
    let plan = plan_fleet_with(
        grid,
        robots,
        params,
        attribute,
        fleet,
        (Some(&uncovered), &mut |round, _, part| {
            let rem = remainder(part, covered, remainder_params)?;
            let space = remainder_space(part, &rem, part.start)?;
            if rounds.len() < round {
                rounds.resize(round, Vec::new());
            }
            rounds[round - 1].push(rem);
            Ok(Some(space))
        }),
        monitor,
    )?;
    let remainders = rounds
        .into_iter()
        .nth(plan.rounds.saturating_sub(1))
        .unwrap_or_default();
    Ok(FleetRemainderPlan {
        fleet: plan,
        remainders,
    })
}

/// Splits `path` where `driven_m` metres of it have been driven: the driven part and the rest, both holding
/// the split point (for benches and tests that stamp what a robot drove; the daemon measures it instead).
pub fn split_at_length(path: &[Point2], driven_m: f64) -> (Vec<Point2>, Vec<Point2>) {
    let mut left = driven_m.max(0.0);
    for (k, w) in path.windows(2).enumerate() {
        let d = (w[1] - w[0]).norm();
        if left <= d {
            let p = if d > 0.0 {
                w[0] + (w[1] - w[0]) * (left / d)
            } else {
                w[0]
            };
            let mut driven = path[..=k].to_vec();
            driven.push(p);
            let mut rest = vec![p];
            rest.extend_from_slice(&path[k + 1..]);
            return (driven, rest);
        }
        left -= d;
    }
    (path.to_vec(), path.last().map(|&p| vec![p]).unwrap_or_default())
}
