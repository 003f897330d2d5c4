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

#[cfg(test)]
pub(crate) mod testutil {
    //! Random maps for the link tests.
    use crate::geom::Point2;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::space::{CoverageSpace, RobotShape};

    /// A tiny deterministic generator (xorshift64*), so tests need no extra dependency.
    pub struct Rng(u64);

    impl Rng {
        pub fn new(seed: u64) -> Self {
            Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
        }
        pub fn next_u64(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
        /// Uniform in [0, 1).
        pub fn unit(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
        }
        pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
        pub fn below(&mut self, n: usize) -> usize {
            (self.next_u64() % n as u64) as usize
        }
    }

    /// A `w × h` map at 0.1 m with `obstacles` random rectangles and disks (half-sizes 0.05–1.2 m); `None`
    /// when the robot fits nowhere.
    pub fn random_space(seed: u64, w: usize, h: usize, obstacles: usize, radius_m: f64) -> Option<CoverageSpace> {
        let mut rng = Rng::new(seed);
        let g = GridGeometry::new(w, h, 0.1, Point2::new(-1.0, 2.0)).ok()?;
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        let (wm, hm) = (w as f64 * 0.1, h as f64 * 0.1);
        for _ in 0..obstacles {
            let c = Point2::new(-1.0 + rng.range(0.0, wm), 2.0 + rng.range(0.0, hm));
            let disk = rng.unit() < 0.5;
            let (ex, ey) = if disk {
                let r = rng.range(0.05, 0.6);
                (r, r)
            } else {
                (rng.range(0.05, 1.2), rng.range(0.05, 1.2))
            };
            // Paint inside the bounding box only (fast on big maps).
            let (cx, cy) = g.to_cell_coords(c);
            let (x0, x1) = (
                (cx - ex * 10.0 - 1.0).max(0.0) as usize,
                ((cx + ex * 10.0 + 1.0) as usize).min(w - 1),
            );
            let (y0, y1) = (
                (cy - ey * 10.0 - 1.0).max(0.0) as usize,
                ((cy + ey * 10.0 + 1.0) as usize).min(h - 1),
            );
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let p = g.center(crate::map::Cell::new(x, y));
                    let inside = if disk {
                        (p - c).norm() <= ex
                    } else {
                        (p.x - c.x).abs() <= ex && (p.y - c.y).abs() <= ey
                    };
                    if inside {
                        grid.cells[y * w + x] = CellState::Occupied;
                    }
                }
            }
        }
        let robot = RobotShape {
            radius_m,
            tool_width_m: 0.3,
        };
        let start = Point2::new(-1.0 + rng.range(0.0, wm), 2.0 + rng.range(0.0, hm));
        CoverageSpace::new(grid, robot, start).ok()
    }

    /// A random valid robot position (not a cell centre) on the reachable set.
    pub fn random_point(space: &CoverageSpace, rng: &mut Rng) -> Point2 {
        random_points(space, rng, 1)[0]
    }

    /// `n` random valid robot positions (not cell centres) on the reachable set.
    pub fn random_points(space: &CoverageSpace, rng: &mut Rng, n: usize) -> Vec<Point2> {
        let g = *space.geometry();
        let cells: Vec<usize> = (0..g.len()).filter(|&i| space.reachable[i]).collect();
        (0..n)
            .map(|_| {
                for _ in 0..1000 {
                    let c = g.center_of(cells[rng.below(cells.len())]);
                    let p = c + crate::geom::Vector2::new(rng.range(-0.05, 0.05), rng.range(-0.05, 0.05));
                    if space.point_ok(p) {
                        return p;
                    }
                }
                g.center_of(cells[0])
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::testutil::{Rng, random_point, random_space};
    use super::*;
    use crate::map::{Cell, CellState, GridGeometry, OccupancyGrid};
    use proptest::prelude::*;

    fn two_rooms() -> CoverageSpace {
        // 6 m × 3 m; a wall at x = 3 m with a 0.8 m door at y ∈ [2.0, 2.8].
        let g = GridGeometry::new(60, 30, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(2.95, 0.0, 3.05, 1.95, CellState::Occupied);
        let robot = RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        };
        CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space")
    }

    fn assert_valid(space: &CoverageSpace, path: &[Point2], a: Point2, b: Point2) {
        assert!(path.len() >= 2);
        assert_eq!(path[0], a);
        assert_eq!(path[path.len() - 1], b);
        for w in path.windows(2) {
            assert!(space.segment_ok(w[0], w[1]), "segment {:?} -> {:?} not ok", w[0], w[1]);
        }
    }

    #[test]
    fn method_names_round_trip() {
        for m in [LinkMethod::AStar, LinkMethod::Bidirectional] {
            assert_eq!(m.name().parse::<LinkMethod>().expect("parses"), m);
            assert_eq!(m.to_string(), m.name());
        }
        assert!(matches!(
            "dijkstra".parse::<LinkMethod>(),
            Err(PlannerError::InvalidParam { .. })
        ));
    }

    #[test]
    fn params_validate_and_sanitize() {
        assert!(LinkParams::default().validate().is_ok());
        let bad = LinkParams {
            alpha: -1.0,
            epsilon_m: 0.0,
            preferred_clearance_m: f64::NAN,
            ..LinkParams::default()
        };
        assert!(bad.validate().is_err());
        assert_eq!(bad.sanitized(), LinkParams::default());
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.5,
        };
        assert_eq!(LinkParams::for_robot(&robot).preferred_clearance_m, 0.25);
    }

    #[test]
    fn straight_line_when_visible() {
        let s = two_rooms();
        let (a, b) = (Point2::new(0.7, 1.03), Point2::new(2.2, 1.51));
        assert_eq!(link(&s, a, b, &LinkParams::default()), Some(vec![a, b]));
    }

    #[test]
    fn goes_through_the_door_with_few_vertices() {
        let s = two_rooms();
        let (a, b) = (Point2::new(1.02, 0.51), Point2::new(5.03, 0.49));
        for method in [LinkMethod::AStar, LinkMethod::Bidirectional] {
            let params = LinkParams {
                method,
                ..LinkParams::default()
            };
            let path = link(&s, a, b, &params).expect("reachable through the door");
            assert_valid(&s, &path, a, b);
            assert!(path.len() <= 5, "{method}: {} vertices: {path:?}", path.len());
            // It passes above the wall's end (centre of its top cell row at y = 1.95 m).
            assert!(path.iter().any(|p| p.y > 1.95 && (p.x - 3.0).abs() < 0.6), "{path:?}");
            // Keeps min(radius + preferred, the grid path's clearance), and the radius everywhere.
            let grid = Linker::new(&s, &params).grid_path(a, b).expect("grid path");
            let kept = path_min_clearance(&s, &path);
            assert!(kept >= (0.15f64 + 0.15).min(path_min_clearance(&s, &grid.points)) - 1e-9);
            assert!(kept >= 0.15 - 1e-9);
            assert!(grid.points.len() > 30 && path.len() < grid.points.len());
        }
    }

    #[test]
    fn unreachable_or_invalid_gives_none() {
        // Same rooms, no door.
        let g = GridGeometry::new(60, 30, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(2.95, 0.0, 3.05, 3.0, CellState::Occupied);
        let robot = RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        };
        let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space");
        let a = Point2::new(1.0, 1.0);
        for method in [LinkMethod::AStar, LinkMethod::Bidirectional] {
            let params = LinkParams {
                method,
                ..LinkParams::default()
            };
            // Across the wall: not on the reachable set at all.
            assert_eq!(link(&s, a, Point2::new(5.0, 1.0), &params), None);
            // In the wall, off the map, NaN.
            assert_eq!(link(&s, a, Point2::new(3.0, 1.0), &params), None);
            assert_eq!(link(&s, a, Point2::new(-3.0, 1.0), &params), None);
            assert_eq!(link(&s, Point2::new(f64::NAN, 1.0), a, &params), None);
        }
    }

    #[test]
    fn potential_keeps_away_from_walls() {
        // A 3 m wide corridor; a plain shortest path around the block hugs its corner, the potential path
        // keeps more room.
        let g = GridGeometry::new(80, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(3.5, 0.0, 4.5, 2.5, CellState::Occupied);
        let robot = RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        };
        let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space");
        let (a, b) = (Point2::new(1.0, 1.0), Point2::new(7.0, 1.0));
        let plain = LinkParams {
            alpha: 0.0,
            preferred_clearance_m: 0.0,
            ..LinkParams::default()
        };
        let field = LinkParams {
            alpha: 0.5,
            preferred_clearance_m: 0.0,
            ..LinkParams::default()
        };
        let gp = Linker::new(&s, &plain).grid_path(a, b).expect("path");
        let gf = Linker::new(&s, &field).grid_path(a, b).expect("path");
        assert!(path_min_clearance(&s, &gf.points) > path_min_clearance(&s, &gp.points) + 0.1);
        assert!(crate::geom::polyline_length(&gf.points) >= crate::geom::polyline_length(&gp.points) - 1e-9);
    }

    #[test]
    fn diagonal_pinch_is_passable_when_clear() {
        // Two thin diagonal walls on the line x + y = 39 (cells) leave one gap; with a 0.2 m radius the cells
        // beside the gap are not traversable, so the halves meet only at the diagonal step
        // (19, 19) → (20, 20), whose segment still keeps 0.21 m from both wall ends.
        let g = GridGeometry::new(40, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        for k in 0..19 {
            grid.set(Cell::new(21 + k, 18 - k), CellState::Occupied);
            grid.set(Cell::new(18 - k, 21 + k), CellState::Occupied);
        }
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        let (a, b) = (Point2::new(0.62, 0.71), Point2::new(3.43, 3.38));
        let s = CoverageSpace::new(grid, robot, a).expect("space");
        assert!(
            s.point_ok(a) && s.point_ok(b),
            "both halves reachable through the pinch"
        );
        for side in [Cell::new(20, 19), Cell::new(19, 20)] {
            assert!(!s.reachable[g.index(side)]);
        }
        let mut costs = Vec::new();
        for method in [LinkMethod::AStar, LinkMethod::Bidirectional] {
            let params = LinkParams {
                method,
                ..LinkParams::default()
            };
            let mut linker = Linker::new(&s, &params);
            let grid_path = linker.grid_path(a, b).expect("through the pinch");
            assert!(grid_path.points.contains(&g.center(Cell::new(19, 19))));
            assert!(grid_path.points.contains(&g.center(Cell::new(20, 20))));
            costs.push(grid_path.cost);
            let path = linker.link(a, b).expect("through the pinch");
            assert_valid(&s, &path, a, b);
        }
        assert!((costs[0] - costs[1]).abs() < 1e-9 * costs[0]);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        #[test]
        fn random_links_are_valid_and_methods_agree(
            seed in any::<u64>(), w in 12usize..48, h in 12usize..48, obstacles in 0usize..14,
            radius in 0.08f64..0.26, alpha in 0.0f64..1.0, pref in 0.0f64..0.4,
        ) {
            let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
            let mut rng = Rng::new(seed ^ 0xABCD);
            let a = random_point(&s, &mut rng);
            let b = random_point(&s, &mut rng);
            let pa = LinkParams { alpha, preferred_clearance_m: pref, method: LinkMethod::AStar, ..LinkParams::default() };
            let pb = LinkParams { method: LinkMethod::Bidirectional, ..pa };
            let mut la = Linker::new(&s, &pa);
            let mut lb = Linker::new(&s, &pb);
            let ga = la.grid_path(a, b);
            let gb = lb.grid_path(a, b);
            match (&ga, &gb) {
                (Some(ga), Some(gb)) => {
                    prop_assert!((ga.cost - gb.cost).abs() <= 1e-9 * ga.cost.max(1.0), "astar {} bidir {}", ga.cost, gb.cost);
                    for g in [ga, gb] {
                        prop_assert_eq!(g.points[0], a);
                        prop_assert_eq!(*g.points.last().expect("non-empty"), b);
                        for w in g.points.windows(2) {
                            prop_assert!(s.segment_ok(w[0], w[1]));
                        }
                    }
                }
                (None, None) => {}
                _ => prop_assert!(false, "methods disagree on reachability: {:?} vs {:?}", ga.is_some(), gb.is_some()),
            }
            for l in [&mut la, &mut lb] {
                let path = l.link(a, b);
                prop_assert_eq!(path.is_some(), ga.is_some());
                if let (Some(path), Some(grid)) = (path, &ga) {
                    prop_assert_eq!(path[0], a);
                    prop_assert_eq!(*path.last().expect("non-empty"), b);
                    for w in path.windows(2) {
                        prop_assert!(s.segment_ok(w[0], w[1]), "segment {:?} -> {:?}", w[0], w[1]);
                    }
                    let need = radius + pref;
                    prop_assert!(path_min_clearance(&s, &path) >= need.min(path_min_clearance(&s, &grid.points)) - 1e-9);
                    prop_assert!(path.len() <= grid.points.len());
                }
            }
            // Reusing the buffers for the reverse link gives the same cost.
            if let Some(ga) = &ga {
                let back = la.grid_path(b, a).expect("symmetric reachability");
                prop_assert!((back.cost - ga.cost).abs() <= 1e-9 * ga.cost.max(1.0));
            }
        }
    }
}
