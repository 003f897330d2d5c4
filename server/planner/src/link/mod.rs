//! Links: collision-free transit paths between coverage regions (DESIGN §4 "Links").
//!
//! A link from `a` to `b` (map frame, metres) is found in three steps:
//!
//! 1. **Grid search** on the reachable cells of a [`CoverageSpace`], 8-connected, with the potential-field
//!    cost of seed 000 eqs. 15-16: Ψ(p) = 1 / (d(p) + ε), d the clearance (distance to the nearest non-free
//!    cell centre). The seed adds α·Ψ(p) to f = g + h; taken literally that is neither a path cost nor an
//!    admissible heuristic. What it means physically is "being close to walls costs extra", so we charge it
//!    per metre travelled: an edge u→v of length `step` costs `step · (1 + α·(Ψ(u) + Ψ(v)) / 2)`. The cost
//!    is symmetric, so forward A* ([`LinkMethod::AStar`]) and bidirectional A* (seed 003 §2.2,
//!    [`LinkMethod::Bidirectional`]) find paths of the same, optimal cost.
//! 2. **Moves.** Orthogonal moves between reachable cells; diagonal moves when both orthogonal cells beside
//!    them are reachable (no corner cutting), or — so that diagonal pinches of the 8-connected reachable
//!    set stay passable — when neither is and the straight segment between the two centres passes
//!    [`CoverageSpace::segment_ok`]. With this rule every step between cell centres keeps the robot radius
//!    of clearance.
//! 3. **Shortcutting** ([`shortcut`]): line-of-sight jumps that never bring the path closer to walls than
//!    `radius + preferred_clearance_m`, or than the grid path already was where it was closer.
//!
//! `a` and `b` need not be cell centres: they are joined to the centres of the reachable cells around them
//! (the 3 × 3 block) whose straight connection is `segment_ok`.
//!
//! [`geodesic_matrix`] gives travel lengths between many points at once (for ordering regions), from one
//! multi-source Dijkstra over the grid and a sparse graph between the sources.

mod astar;
mod bidir;
mod geodesic;
mod shortcut;
#[cfg(test)]
mod tests;
#[cfg(test)]
pub(crate) mod testutil;

use std::fmt;
use std::str::FromStr;

use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use crate::space::{CoverageSpace, RobotShape};

pub use geodesic::{DistancesFrom, geodesic_distance, geodesic_matrix};
pub use shortcut::{path_min_clearance, segment_min_clearance, shortcut};

use astar::{Frontier, Graph, Search};

/// Which grid search finds the transit path. Both return paths of the same (optimal) cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum LinkMethod {
    /// Forward A* from `a` to `b`.
    #[default]
    AStar,
    /// Bidirectional A* (seed 003 §2.2): forward and backward searches alternate until they meet and the
    /// meeting cost is provably optimal.
    Bidirectional,
}

impl LinkMethod {
    /// The name used in configuration and requests: `"astar"` or `"bidir"`.
    pub fn name(self) -> &'static str {
        match self {
            Self::AStar => "astar",
            Self::Bidirectional => "bidir",
        }
    }
}

impl fmt::Display for LinkMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for LinkMethod {
    type Err = PlannerError;

    /// Parses `"astar"` or `"bidir"` (exactly, as [`LinkMethod::name`] writes them).
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "astar" => Ok(Self::AStar),
            "bidir" => Ok(Self::Bidirectional),
            other => Err(PlannerError::InvalidParam {
                name: "link_method",
                reason: format!("unknown link method {other:?}; expected \"astar\" or \"bidir\""),
            }),
        }
    }
}

/// Knobs of the link planner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkParams {
    /// Weight α of the potential field, metres. Travelling one metre at clearance `d` costs
    /// `1 + α / (d + ε)` metres, so α is the clearance at which the cost doubles (ignoring ε). 0 turns the
    /// potential off (plain shortest paths). Default 0.2 m: a path at 0.2 m from a wall costs ~1.8× its
    /// length, at 1 m ~1.19×, at 3 m ~1.07×.
    pub alpha: f64,
    /// Softening constant ε of Ψ = 1 / (d + ε), metres; keeps Ψ finite at zero clearance ("a small constant"
    /// in seed 000). Default 0.05 m (half a typical 0.1 m cell).
    pub epsilon_m: f64,
    /// Grid search strategy.
    pub method: LinkMethod,
    /// Clearance beyond the robot radius that shortcutting tries to keep, metres (e.g. half the tool width).
    /// Shortcuts keep at least `radius + preferred_clearance_m`, or the grid path's own clearance where that
    /// is lower. Default 0.15 m (half of a 0.3 m tool).
    pub preferred_clearance_m: f64,
}

impl Default for LinkParams {
    fn default() -> Self {
        Self {
            alpha: 0.2,
            epsilon_m: 0.05,
            method: LinkMethod::AStar,
            preferred_clearance_m: 0.15,
        }
    }
}

impl LinkParams {
    /// Defaults with `preferred_clearance_m` set to half the robot's tool width.
    pub fn for_robot(robot: &RobotShape) -> Self {
        Self {
            preferred_clearance_m: 0.5 * robot.tool_width_m,
            ..Self::default()
        }
    }

    /// Checks the ranges: α ≥ 0, ε > 0, preferred clearance ≥ 0, all finite.
    pub fn validate(&self) -> Result<()> {
        let checks: [(&'static str, f64, bool); 3] = [
            ("link alpha", self.alpha, self.alpha >= 0.0),
            ("link epsilon_m", self.epsilon_m, self.epsilon_m > 0.0),
            (
                "link preferred_clearance_m",
                self.preferred_clearance_m,
                self.preferred_clearance_m >= 0.0,
            ),
        ];
        for (name, v, in_range) in checks {
            if !v.is_finite() || !in_range {
                return Err(PlannerError::InvalidParam {
                    name,
                    reason: format!("got {v}; alpha must be >= 0 m, epsilon_m > 0 m, preferred_clearance_m >= 0 m"),
                });
            }
        }
        Ok(())
    }

    /// These parameters with every out-of-range value replaced by its default (used by the infallible entry
    /// points; call [`LinkParams::validate`] first to reject bad input instead).
    pub fn sanitized(&self) -> Self {
        let d = Self::default();
        let pick = |v: f64, ok: bool, def: f64| if v.is_finite() && ok { v } else { def };
        Self {
            alpha: pick(self.alpha, self.alpha >= 0.0, d.alpha),
            epsilon_m: pick(self.epsilon_m, self.epsilon_m > 0.0, d.epsilon_m),
            method: self.method,
            preferred_clearance_m: pick(
                self.preferred_clearance_m,
                self.preferred_clearance_m >= 0.0,
                d.preferred_clearance_m,
            ),
        }
    }
}

/// The raw result of the grid search: `a`, the centres of the cells visited, `b`.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPath {
    /// `a`, cell centres, `b` (map frame, metres). Consecutive points are `segment_ok`.
    pub points: Vec<Point2>,
    /// Potential-field cost of the path (metres-equivalent: length weighted by `1 + α·Ψ`).
    pub cost: f64,
    /// Cells expanded by the search (a measure of work).
    pub expanded: usize,
}

/// A reusable link planner for one [`CoverageSpace`]: keeps its search buffers (flat per-cell arrays)
/// between calls, so planning many links costs no re-allocation.
#[derive(Debug)]
pub struct Linker<'s> {
    space: &'s CoverageSpace,
    params: LinkParams,
    /// Lower bound of the cost multiplier `1 + α·Ψ` over the reachable set (scales the heuristic).
    min_multiplier: f64,
    fwd: Frontier,
    bwd: Frontier,
}

impl<'s> Linker<'s> {
    /// A planner on `space` with `params` (out-of-range values fall back to defaults, see
    /// [`LinkParams::sanitized`]).
    pub fn new(space: &'s CoverageSpace, params: &LinkParams) -> Self {
        let params = params.sanitized();
        // The largest clearance anywhere bounds the reachable cells' from above (so the multiplier from below).
        let max_clearance = f64::from(space.clearance.values().iter().copied().fold(0.0_f32, f32::max));
        let min_multiplier = if max_clearance.is_finite() {
            1.0 + params.alpha / (max_clearance * (1.0 + 1e-6) + params.epsilon_m)
        } else {
            1.0
        };
        Self {
            space,
            params,
            min_multiplier,
            fwd: Frontier::default(),
            bwd: Frontier::default(),
        }
    }

    /// The space it links on.
    pub fn space(&self) -> &'s CoverageSpace {
        self.space
    }

    /// The parameters in use (after sanitizing).
    pub fn params(&self) -> &LinkParams {
        &self.params
    }

    /// Collision-free transit from `a` to `b` (map frame, metres): the straight segment when it is
    /// `segment_ok` and keeps `min(radius + preferred_clearance_m, clearance(a), clearance(b))`; otherwise the
    /// grid search followed by [`shortcut`]. The polyline starts at `a` and ends at `b` exactly and every
    /// segment is `segment_ok`. `None` when `a` or `b` is not a valid robot position
    /// ([`CoverageSpace::point_ok`]) or `b` cannot be reached from `a`.
    pub fn link(&mut self, a: Point2, b: Point2) -> Option<Vec<Point2>> {
        self.link_within(a, b, f64::INFINITY)
    }

    /// [`Linker::link`], giving up (`None`) when the grid search's cost would exceed `max_cost` (with α = 0
    /// the cost is the grid path's length, metres): a bounded search for "is there a short way round?".
    pub fn link_within(&mut self, a: Point2, b: Point2, max_cost: f64) -> Option<Vec<Point2>> {
        let space = self.space;
        if !space.point_ok(a) || !space.point_ok(b) {
            return None;
        }
        let need = space.robot.radius_m + self.params.preferred_clearance_m;
        let direct_need = need.min(space.clearance_at(a)).min(space.clearance_at(b));
        if shortcut::segment_keeps(space, a, b, direct_need) {
            return Some(vec![a, b]);
        }
        let grid = self.grid_path_within(a, b, max_cost)?;
        let path = shortcut(space, &grid.points, self.params.preferred_clearance_m);
        debug_assert!(path.windows(2).all(|w| space.segment_ok(w[0], w[1])));
        Some(path)
    }

    /// The grid search alone (no shortcutting), with the configured method. `None` when `a` or `b` is not a
    /// valid robot position or `b` is not reachable from `a`.
    pub fn grid_path(&mut self, a: Point2, b: Point2) -> Option<GridPath> {
        self.grid_path_within(a, b, f64::INFINITY)
    }

    fn grid_path_within(&mut self, a: Point2, b: Point2, max_cost: f64) -> Option<GridPath> {
        let space = self.space;
        let graph = Graph::new(space);
        let search = Search {
            graph: &graph,
            alpha: self.params.alpha,
            epsilon_m: self.params.epsilon_m,
            heuristic_scale: self.min_multiplier,
            max_cost,
        };
        let sources = search.attach(a);
        let targets = search.attach(b);
        if sources.is_empty() || targets.is_empty() {
            return None;
        }
        let found = match self.params.method {
            LinkMethod::AStar => astar::search(&search, &mut self.fwd, &sources, &targets),
            LinkMethod::Bidirectional => bidir::search(&search, &mut self.fwd, &mut self.bwd, &sources, &targets),
        }?;
        let geometry = space.geometry();
        let mut points = Vec::with_capacity(found.cells.len() + 2);
        points.push(a);
        points.extend(found.cells.iter().map(|&i| geometry.center_of(i)));
        points.push(b);
        Some(GridPath {
            points,
            cost: found.cost,
            expanded: found.expanded,
        })
    }
}

/// Collision-free transit from `a` to `b` (map frame, metres): grid search on the reachable cells with the
/// potential-field cost, then line-of-sight shortcutting that keeps clearance. Returns the polyline including
/// `a` and `b` exactly; `None` when `b` is not reachable from `a` (or either is not a valid robot position,
/// see [`CoverageSpace::point_ok`]). Every segment satisfies `space.segment_ok`. For many links on one space
/// use a [`Linker`], which reuses its buffers.
pub fn link(space: &CoverageSpace, a: Point2, b: Point2, params: &LinkParams) -> Option<Vec<Point2>> {
    Linker::new(space, params).link(a, b)
}
