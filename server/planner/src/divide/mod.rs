//! Dividing a site among a fleet (issue 20): every robot gets one connected part of the coverable area,
//! holding its start, balanced by the time it will take to cover.
//!
//! The division is an additively weighted geodesic Voronoi diagram of the robots' starts, the weights found
//! by balancing (an equivalent of DARP, Kapoutsis et al. 2017, whose iterative assignment also adjusts one
//! term per robot on a distance matrix until the shares balance; ours is additive, which keeps parts
//! connected and rooms whole where DARP's multiplicative term needs a connectivity correction):
//!
//! 1. per robot, its [`CoverageSpace`] (its own radius and tool), the travel distance from its start to
//!    every reachable cell (fast marching, [`eikonal`]: round level sets, see there why), and the work each
//!    reachable cell stands for: the coverable cells nearest to it, each the seconds the robot spends on it
//!    (lanes a tool width apart at the speed the attribute asks for there, [`work`]), times a calibration
//!    per cell the caller may learn from planned durations;
//! 2. every reachable cell goes to the robot with the least `distance + weight`, ties to the lower index;
//!    the weights move (a robot with more work than the mean gets a larger weight) until the loads are
//!    within `balance_tol` of each other or the iterations run out (the best division seen is kept; the
//!    first iterations run on a sample of the cells, [`balance`]). Each robot's weight stays below every
//!    other robot's distance to its start plus that robot's weight, so no robot loses its own start.
//! 3. [`ownership`]: parts are made connected from their start in their robot's own reachable set (they
//!    nearly are already: on a shortest path from a start to a cell of its part every cell belongs to the
//!    part, by the triangle inequality, which the discrete distances keep up to their small error), cells left over go to a neighbouring part whose
//!    robot can reach them, and the coverable cells beside the walls follow the reachable cell nearest to
//!    them. Each part is then its robot's space confined to its cells plus a seam of `seam_cells` cells into
//!    its neighbours ([`CoverageSpace::confined`]), so the union of the parts' plans leaves no seam, with the
//!    robot's centre kept half a tool inside the part's boundary with other parts (its swath ends there).
//!
//! Why this follows walls and doorways: grid distances run through doorways, so every cell of a room
//! entered by one doorway is the same distance further from every start outside it than the doorway is; the
//! whole room goes to one robot unless a robot starts inside it or the balance needs a corridor cut, never a
//! room cut by a wall into pieces one robot must drive round to.

mod balance;
pub mod docks;
mod eikonal;
mod ownership;
#[cfg(test)]
mod tests;
mod work;

use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use std::sync::Arc;

use crate::footprint::Footprint;
use crate::map::{Cell, DistanceField, OccupancyGrid};
use crate::space::{CoverageSpace, RobotShape};
use crate::speed::SpeedLimits;
use crate::speed::attribute::AttributeMap;

/// No robot owns the cell.
pub const NO_OWNER: u32 = u32::MAX;

/// One robot of the fleet as division sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct FleetRobot {
    /// Its start (dock), map frame, metres.
    pub start: Point2,
    /// Radius and tool width (with a footprint: its planning radius, [`Footprint::planning_radius_m`]).
    pub shape: RobotShape,
    /// Its speed limits.
    pub limits: SpeedLimits,
    /// A robot that is not a disc: its part is planned with the footprint
    /// ([`crate::pipeline::plan_footprinted`]).
    pub footprint: Option<Footprint>,
}

impl FleetRobot {
    /// A round robot (no footprint) docked at `start`.
    pub fn disc(start: Point2, shape: RobotShape, limits: SpeedLimits) -> Self {
        Self {
            start,
            shape,
            limits,
            footprint: None,
        }
    }
}

/// Knobs of [`divide`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DivideParams {
    /// Loads within this share of each other count as balanced (0.02: the longest at most 2 % over the
    /// shortest).
    pub balance_tol: f64,
    /// Most balancing iterations on the sample of cells, then on every cell.
    pub iterations: [usize; 2],
    /// Cells of a neighbour's part each part covers too, so that the union of the plans leaves no seam.
    pub seam_cells: usize,
}

impl Default for DivideParams {
    fn default() -> Self {
        Self {
            balance_tol: 0.02,
            iterations: [300, 40],
            seam_cells: 1,
        }
    }
}

/// A robot's share.
#[derive(Debug, Clone)]
pub struct Part {
    /// The robot's space confined to its part (plan it with the ordinary pipeline).
    pub space: CoverageSpace,
    /// The work the division expected of it, seconds (rate × coverable cells it owns).
    pub load_s: f64,
    /// Coverable cells it owns (without the seam), m².
    pub owned_area_m2: f64,
}

/// A site divided among a fleet.
#[derive(Debug, Clone)]
pub struct Division {
    /// Robot index per grid cell, [`NO_OWNER`] where nobody covers.
    pub owner: Vec<u32>,
    /// Cells some robot of the fleet can cover (the union of the robots' coverable sets on the whole map).
    pub coverable: Vec<bool>,
    /// One part per robot, in the robots' order.
    pub parts: Vec<Part>,
    /// The balancing weights found, metres.
    pub weights: Vec<f64>,
    /// Remarks for the user (cells nobody could be given, a balance not reached).
    pub warnings: Vec<String>,
}

impl Division {
    /// Longest over shortest expected load (1 is perfect balance).
    pub fn load_ratio(&self) -> f64 {
        let (lo, hi) = self.parts.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), p| {
            (lo.min(p.load_s), hi.max(p.load_s))
        });
        if lo > 0.0 { hi / lo } else { f64::INFINITY }
    }
}

/// What division knows of one robot on the map.
struct RobotField {
    /// Its whole space on the map (before confinement), shared with the robots of its shape whose docks lie
    /// on the same reachable set (the space's own start is the first such robot's).
    space: Arc<CoverageSpace>,
    /// Distance to the space's reachable set, with the nearest reachable cell of every cell (shared likewise).
    to_reachable: Arc<DistanceField>,
    /// Its dock's cell, and the dock (the space's start, or a cell centre when it was moved there).
    start_cell: Cell,
    start: Point2,
    /// Travel distance from its dock to every reachable cell, metres ([`eikonal`]; filled in by
    /// [`travel_distances`]).
    dist: Vec<f64>,
}

/// Fills every field's travel distances, the robots shared out over the cores (each march is independent and
/// sequential, so the result does not depend on the number of threads).
fn travel_distances(fields: &mut [RobotField]) {
    let threads = std::thread::available_parallelism()
        .map_or(1, usize::from)
        .min(fields.len())
        .max(1);
    let chunk = fields.len().div_ceil(threads).max(1);
    let march = |f: &mut RobotField| {
        let g = *f.space.geometry();
        let s = g.index(f.start_cell);
        f.dist = eikonal::travel_distance(&g, &f.space.reachable, s, (g.center_of(s) - f.start).norm());
    };
    std::thread::scope(|scope| {
        for part in fields.chunks_mut(chunk) {
            scope.spawn(move || part.iter_mut().for_each(march));
        }
    });
}

impl RobotField {
    /// `earlier`: the fields made so far, whose spaces are reused when `robot` has the same shape and its dock
    /// stands on one's reachable set with the robot's clearance (the space would come out the same).
    fn new(grid: &OccupancyGrid, robot: &FleetRobot, earlier: &[RobotField]) -> Result<Self> {
        let g = grid.geometry;
        let shared = g.locate(robot.start).and_then(|c| {
            earlier.iter().find(|f| {
                f.space.robot == robot.shape
                    && f.space.reachable[g.index(c)]
                    && f.space.clearance_at(robot.start) >= robot.shape.radius_m
            })
        });
        let (space, to_reachable, start_cell, start) = match (shared, g.locate(robot.start)) {
            (Some(f), Some(c)) => (f.space.clone(), f.to_reachable.clone(), c, robot.start),
            _ => {
                let space = CoverageSpace::new(grid.clone(), robot.shape, robot.start)?;
                let reachable = &space.reachable;
                let to_reachable = DistanceField::compute(g, |i| reachable[i], false);
                let (c, p) = (space.start_cell, space.start);
                (Arc::new(space), Arc::new(to_reachable), c, p)
            }
        };
        Ok(Self {
            space,
            to_reachable,
            start_cell,
            start,
            dist: Vec::new(),
        })
    }
}

/// Divides `grid` among `robots` (see the module docs), with the speeds `attribute` asks for (RFICP) in the
/// expected times when given (it must have the grid's geometry). `calibration[i]` multiplies the expected
/// time on cell i (1 without knowledge; a caller that planned the parts can pass each part's planned over
/// expected duration on its cells, to correct for the turns and transits the estimate does not see: they
/// belong to the place, short lanes between shelves or a long way from the dock, more than to the robot).
/// Errors name the robot: a start off the map or where the robot fits nowhere, two starts in one cell.
pub fn divide(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    attribute: Option<&AttributeMap>,
    calibration: Option<&[f64]>,
    params: &DivideParams,
) -> Result<Division> {
    divide_within(grid, robots, attribute, calibration, params, None)
}

/// As [`divide`], with only the coverable cells flagged in `only` (one flag per grid cell) to cover, as when
/// a remainder is replanned ([`crate::pipeline::remainder`]): they alone weigh in the balance and are left
/// coverable in the parts, while every reachable cell is still shared out (robots drive across the rest of
/// their part). `None` is [`divide`].
pub fn divide_within(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    attribute: Option<&AttributeMap>,
    calibration: Option<&[f64]>,
    params: &DivideParams,
    only: Option<&[bool]>,
) -> Result<Division> {
    if only.is_some_and(|o| o.len() != grid.cells.len()) {
        return Err(PlannerError::InvalidParam {
            name: "only",
            reason: format!("needs one flag per grid cell ({})", grid.cells.len()),
        });
    }
    if robots.is_empty() {
        return Err(PlannerError::InvalidParam {
            name: "robots",
            reason: "at least one robot is needed".into(),
        });
    }
    if !(params.balance_tol.is_finite() && params.balance_tol >= 0.0) {
        return Err(PlannerError::InvalidParam {
            name: "balance_tol",
            reason: format!("must be a non-negative number, got {}", params.balance_tol),
        });
    }
    let mut fields: Vec<RobotField> = Vec::with_capacity(robots.len());
    for (k, r) in robots.iter().enumerate() {
        let f = RobotField::new(grid, r, &fields).map_err(|e| PlannerError::InvalidParam {
            name: "robots",
            reason: format!("robots[{k}]: {e}"),
        })?;
        fields.push(f);
    }
    for (k, f) in fields.iter().enumerate() {
        if let Some(j) = fields[..k].iter().position(|o| o.start_cell == f.start_cell) {
            return Err(PlannerError::InvalidParam {
                name: "robots",
                reason: format!("robots[{k}].start is in the same map cell as robots[{j}].start"),
            });
        }
    }
    travel_distances(&mut fields);
    let g = grid.geometry;
    if attribute.is_some_and(|a| *a.geometry() != g) {
        return Err(PlannerError::InvalidParam {
            name: "attribute",
            reason: "the attribute map must have the site's grid geometry".into(),
        });
    }
    let cell_area = g.resolution * g.resolution;
    let coverable: Vec<bool> = (0..g.len())
        .map(|i| only.is_none_or(|o| o[i]) && fields.iter().any(|f| f.space.coverable[i]))
        .collect();
    let work = work::Work::new(robots, calibration, &g, attribute, &coverable);
    let table = balance::Table::new(&fields, &work);
    let (weights, balanced) = balance::balance(&table, params);
    let mut warnings = Vec::new();
    let mut owner = ownership::assign(&table, &weights, g.len());
    let stranded = ownership::make_connected(&fields, &mut owner);
    if stranded > 0 {
        warnings.push(format!(
            "{:.1} m² reachable only through other robots' parts was left to no robot",
            stranded as f64 * cell_area
        ));
    }
    ownership::extend_to_coverable(&fields, &mut owner);
    let mut parts = Vec::with_capacity(robots.len());
    for (k, f) in fields.iter().enumerate() {
        let inset = f.space.robot.tool_width_m / 2.0;
        let (keep_reachable, mut keep_coverable) =
            ownership::part_masks(&f.space, f.start_cell, &owner, k as u32, params.seam_cells, inset);
        if let Some(o) = only {
            keep_coverable.iter_mut().zip(o).for_each(|(c, &o)| *c &= o);
        }
        let space = f
            .space
            .confined_from(f.start_cell, f.start, &keep_reachable, &keep_coverable);
        let owned: Vec<usize> = (0..g.len())
            .filter(|&i| owner[i] == k as u32 && f.space.coverable[i] && coverable[i])
            .collect();
        parts.push(Part {
            space,
            load_s: owned.iter().map(|&i| work.at(k, i)).sum(),
            owned_area_m2: owned.len() as f64 * cell_area,
        });
    }
    let mut division = Division {
        owner,
        coverable,
        parts,
        weights,
        warnings,
    };
    if !balanced {
        let ratio = division.load_ratio();
        division.warnings.push(format!(
            "the expected loads could not be balanced closer than {ratio:.2} (longest over shortest): rooms are \
             not cut and no robot gives up its start"
        ));
    }
    Ok(division)
}
