//! Plans for a whole fleet on one site: divide ([`crate::divide`]), plan every part with the ordinary
//! pipeline ([`plan_shaped`]), and learn from the planned durations.
//!
//! Division balances an estimate (coverable area over tool width times speed); real plans add turns,
//! transits from each dock and slow-downs the estimate cannot see, and they add them unevenly (a part of
//! short lanes turns more than one of long lanes). So after each round the expected time of every cell is
//! corrected by its part's planned duration over the part's expected load (the overhead belongs to the
//! place: whoever gets those shelves next round gets their turns too), and the site is divided again, until
//! the longest planned duration is within [`FleetParams::goal_ratio`] of the shortest or the rounds run out;
//! the best round is kept.

use crate::divide::{DivideParams, Division, FleetRobot, divide_within};
use crate::error::{PlannerError, Result};
use crate::map::OccupancyGrid;
use crate::metrics::CoverageRaster;
use crate::pipeline::{NoMonitor, PlanMonitor, PlanOutput, PlanParams, plan_footprinted, plan_shaped};
use crate::space::CoverageSpace;
use crate::speed::attribute::AttributeMap;
use crate::speed::{SpeedParams, SpeedProfile};

/// Exponent of each round's correction (planned over expected time): below 1, so that a correction learned
/// on one division is not applied in full to the next, whose parts differ (full corrections made some
/// fleets swing between two divisions, each over-correcting the other).
const CALIBRATION_DAMPING: f64 = 0.6;

/// Knobs of [`plan_fleet`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FleetParams {
    /// Division knobs.
    pub divide: DivideParams,
    /// Most divide-and-plan rounds (at least one).
    pub rounds: usize,
    /// Longest over shortest planned duration that ends the rounds early.
    pub goal_ratio: f64,
}

impl Default for FleetParams {
    fn default() -> Self {
        Self {
            divide: DivideParams::default(),
            rounds: 4,
            goal_ratio: 1.08,
        }
    }
}

/// Figures of a fleet's plans together (DESIGN §6 extended to fleets).
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct FleetMetrics {
    /// Coverable cells (of any robot) covered by some robot's plan, percent.
    pub union_coverage_pct: f64,
    /// Coverable area covered by two robots or more, percent of the coverable area.
    pub seam_overlap_pct: f64,
    /// Each robot's planned duration, seconds, in the robots' order.
    pub durations_s: Vec<f64>,
    /// Longest over shortest planned duration.
    pub duration_ratio: f64,
    /// Coverable cells of the fleet.
    pub coverable_cells: usize,
}

/// A fleet's plans.
#[derive(Debug, Clone)]
pub struct FleetPlan {
    /// The division the plans were made on.
    pub division: Division,
    /// Each robot's plan and speed profile, in the robots' order.
    pub plans: Vec<(PlanOutput, SpeedProfile)>,
    /// The fleet's figures.
    pub metrics: FleetMetrics,
    /// Rounds planned (see the module docs).
    pub rounds: usize,
}

/// Divides `grid` among `robots` and plans every part (see the module docs). `params` applies to every
/// robot's plan (its limits are replaced by each robot's own).
pub fn plan_fleet(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    params: &PlanParams,
    attribute: Option<&AttributeMap>,
    fleet: &FleetParams,
) -> Result<FleetPlan> {
    plan_fleet_monitored(grid, robots, params, attribute, fleet, &mut NoMonitor)
}

/// [`plan_fleet`] watched by `monitor`: a cancel stops it between parts (and within a part's plan), with
/// [`crate::PlannerError::Cancelled`].
pub fn plan_fleet_monitored(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    params: &PlanParams,
    attribute: Option<&AttributeMap>,
    fleet: &FleetParams,
    monitor: &mut dyn PlanMonitor,
) -> Result<FleetPlan> {
    plan_fleet_with(
        grid,
        robots,
        params,
        attribute,
        fleet,
        (None, &mut |_, _, _| Ok(None)),
        monitor,
    )
}

/// Passes a fleet monitor's cancel on to one part's plan, and none of that plan's progress (a part's regions are
/// not the fleet's).
struct CancelOnly<'a>(&'a mut dyn PlanMonitor);

impl PlanMonitor for CancelOnly<'_> {
    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

/// Replaces a part's space before it is planned: called with the round (from 1), the robot's index and its
/// part's space; `None` keeps the space.
pub(super) type RefinePart<'a> = dyn FnMut(usize, usize, &CoverageSpace) -> Result<Option<CoverageSpace>> + 'a;

/// [`plan_fleet`] with the division made on the cells of `only` ([`crate::divide::divide_within`]) and each
/// part's space passed through `refine` before it is planned; `division.coverable` then holds the cells
/// coverable in some refined part.
pub(super) fn plan_fleet_with(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    params: &PlanParams,
    attribute: Option<&AttributeMap>,
    fleet: &FleetParams,
    (only, refine): (Option<&[bool]>, &mut RefinePart<'_>),
    monitor: &mut dyn PlanMonitor,
) -> Result<FleetPlan> {
    let mut plan_round = |calibration: &[f64], round: usize| -> Result<FleetPlan> {
        if monitor.cancelled() {
            return Err(PlannerError::Cancelled);
        }
        let mut division = divide_within(grid, robots, attribute, Some(calibration), &fleet.divide, only)?;
        let mut refined = false;
        for (k, part) in division.parts.iter_mut().enumerate() {
            if let Some(space) = refine(round, k, &part.space)? {
                part.space = space;
                refined = true;
            }
        }
        if refined {
            for (i, c) in division.coverable.iter_mut().enumerate() {
                *c = division.parts.iter().any(|p| p.space.coverable[i]);
            }
        }
        let mut plans = Vec::with_capacity(robots.len());
        for (part, robot) in division.parts.iter().zip(robots) {
            let p = PlanParams {
                limits: robot.limits,
                ..params.clone()
            };
            let speed = SpeedParams {
                attribute_range: attribute.and_then(|a| a.range_over(&division.coverable)),
                ..SpeedParams::new(robot.limits, robot.shape.tool_width_m)
            };
            if monitor.cancelled() {
                return Err(PlannerError::Cancelled);
            }
            let mut part_monitor = CancelOnly(&mut *monitor);
            plans.push(match &robot.footprint {
                Some(f) => plan_footprinted(&part.space, f, &p, attribute, &speed, &mut part_monitor)?,
                None => plan_shaped(&part.space, &p, attribute, &speed, &mut part_monitor)?,
            });
        }
        let metrics = fleet_metrics(&division, &plans);
        Ok(FleetPlan {
            division,
            plans,
            metrics,
            rounds: round,
        })
    };
    let mut calibration = vec![1.0; grid.cells.len()];
    let mut last = plan_round(&calibration, 1)?;
    let mut best: Option<FleetPlan> = None;
    for round in 2..=fleet.rounds.max(1) {
        if last.metrics.duration_ratio <= fleet.goal_ratio {
            break;
        }
        let factors: Vec<f64> = (last.division.parts.iter().zip(&last.metrics.durations_s))
            .map(|(part, d)| {
                if part.load_s > 0.0 && *d > 0.0 {
                    (d / part.load_s).powf(CALIBRATION_DAMPING)
                } else {
                    1.0
                }
            })
            .collect();
        for (c, &o) in calibration.iter_mut().zip(&last.division.owner) {
            if let Some(f) = factors.get(o as usize) {
                *c *= f;
            }
        }
        let next = plan_round(&calibration, round)?;
        let keep = match best.take() {
            Some(b) if b.metrics.duration_ratio <= last.metrics.duration_ratio => b,
            _ => last,
        };
        best = Some(keep);
        last = next;
    }
    Ok(match best {
        Some(b) if b.metrics.duration_ratio < last.metrics.duration_ratio => b,
        _ => last,
    })
}

/// [`FleetMetrics`] of `plans` on `division`.
pub fn fleet_metrics(division: &Division, plans: &[(PlanOutput, SpeedProfile)]) -> FleetMetrics {
    let n = division.coverable.len();
    let mut times = vec![0u8; n];
    for ((_, profile), part) in plans.iter().zip(&division.parts) {
        let mut raster = CoverageRaster::new(*part.space.geometry(), part.space.robot.tool_width_m / 2.0);
        raster.stamp_polyline(&profile.points());
        for (t, &c) in times.iter_mut().zip(raster.covered()) {
            *t = t.saturating_add(u8::from(c));
        }
    }
    let coverable = division.coverable.iter().filter(|&&c| c).count();
    let covered = (0..n).filter(|&i| division.coverable[i] && times[i] > 0).count();
    let twice = (0..n).filter(|&i| division.coverable[i] && times[i] > 1).count();
    let durations_s: Vec<f64> = plans.iter().map(|(_, p)| p.dwell.duration_s).collect();
    let lo = durations_s.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = durations_s.iter().copied().fold(0.0, f64::max);
    let pct = |k: usize| {
        if coverable > 0 {
            k as f64 / coverable as f64 * 100.0
        } else {
            100.0
        }
    };
    FleetMetrics {
        union_coverage_pct: pct(covered),
        seam_overlap_pct: pct(twice),
        duration_ratio: if lo > 0.0 { hi / lo } else { f64::INFINITY },
        durations_s,
        coverable_cells: coverable,
    }
}
