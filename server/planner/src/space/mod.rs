//! Footprint and reach (DESIGN §6): where the robot's centre may go and what its tool can cover.
//!
//! - *traversable*: free cells whose centre is at least `robot_radius` from every non-free cell centre (the
//!   ring just outside the map counts as non-free);
//! - *reachable*: the 8-connected traversable component holding the start (seed 004, Alg. 1 — a flood fill);
//! - *coverable*: free cells within `tool_width / 2` of a reachable cell.
//!
//! A start that is not traversable snaps to the nearest traversable cell, with a warning; a start whose
//! piece of traversable space is small is reported, and may be moved into the largest piece ([`start`]).

pub mod start;

use std::collections::VecDeque;

use crate::error::{PlannerError, Result, finite};
use crate::geom::Point2;
use crate::map::{Cell, CellState, DistanceField, GridGeometry, OccupancyGrid};

/// The robot as coverage sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotShape {
    /// Radius of the robot's circular footprint, metres.
    pub radius_m: f64,
    /// Width of the swath its tool covers, metres (lanes are this far apart).
    pub tool_width_m: f64,
}

impl RobotShape {
    /// Validates both figures: finite and positive.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("robot_radius", self.radius_m), ("tool_width", self.tool_width_m)] {
            if !v.is_finite() || v <= 0.0 {
                return Err(PlannerError::InvalidParam {
                    name,
                    reason: format!("must be a positive number of metres, got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// The occupancy grid with everything coverage derives from it for one robot and one start.
#[derive(Debug, Clone)]
pub struct CoverageSpace {
    /// The occupancy grid.
    pub grid: OccupancyGrid,
    /// The robot.
    pub robot: RobotShape,
    /// Distance from every cell centre to the nearest non-free cell centre, metres.
    pub clearance: DistanceField,
    /// Traversable cells.
    pub traversable: Vec<bool>,
    /// Reachable cells.
    pub reachable: Vec<bool>,
    /// Coverable cells.
    pub coverable: Vec<bool>,
    /// Where patterns may lie, when not on every reachable cell: `Some(mask)` (within the reachable set)
    /// limits the decomposition's regions, and with them lanes, rings and passes, to the masked cells, while
    /// transits still use every reachable cell (a remainder's replan drives across covered ground to the
    /// places left to cover, [`crate::remainder`]). `None` for every space [`CoverageSpace::new`] and
    /// [`CoverageSpace::confined`] make.
    pub work: Option<Vec<bool>>,
    /// The start cell (after snapping).
    pub start_cell: Cell,
    /// The start point in the map frame (the requested one, or the snapped cell's centre), metres.
    pub start: Point2,
    /// Remarks for the user (e.g. the start was moved).
    pub warnings: Vec<String>,
}

impl CoverageSpace {
    /// Derives the spaces for `robot` starting at `start` (map frame, metres).
    pub fn new(grid: OccupancyGrid, robot: RobotShape, start: Point2) -> Result<Self> {
        Self::with_start_snap(grid, robot, start, None)
    }

    /// As [`CoverageSpace::new`]; when the start's traversable piece is small (see [`start`]) and a cell of
    /// the largest piece lies within `snap_within_m` metres of `start`, the start moves there.
    pub fn with_start_snap(
        grid: OccupancyGrid,
        robot: RobotShape,
        start: Point2,
        snap_within_m: Option<f64>,
    ) -> Result<Self> {
        robot.validate()?;
        if let Some(d) = snap_within_m {
            finite("snap_start_m", d)?;
        }
        finite("start x", start.x)?;
        finite("start y", start.y)?;
        let g = grid.geometry;
        let requested = g
            .locate(start)
            .ok_or(PlannerError::StartOutsideMap { x: start.x, y: start.y })?;
        let clearance = DistanceField::compute(g, |i| !grid.is_free(i), true);
        // A hair of tolerance so that a centre exactly robot_radius away counts (floating-point noise).
        let r = robot.radius_m - 1e-9;
        let traversable: Vec<bool> = (0..g.len()).map(|i| grid.is_free(i) && clearance.at(i) >= r).collect();
        let mut warnings = Vec::new();
        let (start_cell, start_pt) = if traversable[g.index(requested)] {
            // The cell's centre is clear; the exact point may sit a hair closer to a wall than the radius.
            if clearance.at_point(start) >= r {
                (requested, start)
            } else {
                let p = g.center(requested);
                warnings.push(format!(
                    "start ({:.3}, {:.3}) is {:.3} m from an obstacle, under the radius {} m; moved to its cell centre ({:.3}, {:.3})",
                    start.x, start.y, clearance.at_point(start), robot.radius_m, p.x, p.y
                ));
                (requested, p)
            }
        } else {
            let best = (0..g.len())
                .filter(|&i| traversable[i])
                .min_by(|&a, &b| {
                    (g.center_of(a) - start)
                        .norm()
                        .total_cmp(&(g.center_of(b) - start).norm())
                })
                .ok_or(PlannerError::NoTraversableSpace {
                    radius_m: robot.radius_m,
                })?;
            let c = g.cell(best);
            let p = g.center(c);
            warnings.push(format!(
                "start ({:.3}, {:.3}) is not traversable for radius {} m; moved {:.3} m to ({:.3}, {:.3})",
                start.x,
                start.y,
                robot.radius_m,
                (p - start).norm(),
                p.x,
                p.y
            ));
            (c, p)
        };
        let choice = start::weigh_start(&g, &traversable, (start_pt, start_cell), snap_within_m);
        warnings.extend(choice.warning);
        let (start_cell, start_pt) = if choice.snapped {
            (choice.cell, g.center(choice.cell))
        } else {
            (start_cell, start_pt)
        };
        let reachable = choice.reachable;
        let to_reachable = DistanceField::compute(g, |i| reachable[i], false);
        let half = robot.tool_width_m / 2.0 + 1e-9;
        let coverable = (0..g.len())
            .map(|i| grid.is_free(i) && to_reachable.at(i) <= half)
            .collect();
        Ok(Self {
            grid,
            robot,
            clearance,
            traversable,
            reachable,
            coverable,
            work: None,
            start_cell,
            start: start_pt,
            warnings,
        })
    }

    /// The same site on a grid `factor` times coarser (each coarse cell is free only when all the fine
    /// cells it holds are free, occupied when any is occupied, else unknown), for the same robot and start.
    /// For cheap previews of large sites; `factor` ≤ 1 gives a copy of the grid's space. (Choosing `auto`'s
    /// strategy on a 4× coarser copy was tried: the ranking did not carry over to full resolution.)
    pub fn coarsened(&self, factor: usize) -> Result<Self> {
        let g = self.geometry();
        let k = factor.max(1);
        let (w, h) = (g.width.div_ceil(k), g.height.div_ceil(k));
        let geometry = GridGeometry::new(w, h, g.resolution * k as f64, g.origin)?;
        let mut cells = vec![CellState::Free; w * h];
        for (i, state) in self.grid.cells.iter().enumerate() {
            let c = g.cell(i);
            let j = (c.y / k) * w + c.x / k;
            cells[j] = match (cells[j], *state) {
                (CellState::Occupied, _) | (_, CellState::Occupied) => CellState::Occupied,
                (CellState::Unknown, _) | (_, CellState::Unknown) => CellState::Unknown,
                _ => CellState::Free,
            };
        }
        // Coarse cells past the fine grid's edge hold fewer fine cells; they stay as their fine cells say.
        Self::new(OccupancyGrid::new(geometry, cells)?, self.robot, self.start)
    }

    /// This space confined to a part of it (a fleet robot's share, see [`crate::divide`]): the robot's centre
    /// stays on the reachable cells in `keep_reachable` connected to the start, and only the coverable cells
    /// in `keep_coverable` within tool_width / 2 of those are to be covered. The start stays where it is;
    /// when its cell is not kept, nothing is reachable and nothing coverable.
    pub fn confined(&self, keep_reachable: &[bool], keep_coverable: &[bool]) -> Self {
        self.confined_from(self.start_cell, self.start, keep_reachable, keep_coverable)
    }

    /// As [`CoverageSpace::confined`], for another robot of the same shape whose start `start` (in cell
    /// `start_cell`, on this space's reachable set) replaces this space's: one space serves a fleet's docks.
    pub fn confined_from(
        &self,
        start_cell: Cell,
        start: Point2,
        keep_reachable: &[bool],
        keep_coverable: &[bool],
    ) -> Self {
        let g = *self.geometry();
        let kept: Vec<bool> = (0..g.len())
            .map(|i| self.reachable[i] && keep_reachable.get(i).copied().unwrap_or(false))
            .collect();
        let reachable = flood_fill8(&g, &kept, start_cell);
        let to_reachable = DistanceField::compute(g, |i| reachable[i], false);
        let half = self.robot.tool_width_m / 2.0 + 1e-9;
        let coverable = (0..g.len())
            .map(|i| self.coverable[i] && keep_coverable.get(i).copied().unwrap_or(false) && to_reachable.at(i) <= half)
            .collect();
        Self {
            grid: self.grid.clone(),
            robot: self.robot,
            clearance: self.clearance.clone(),
            traversable: self.traversable.clone(),
            reachable,
            coverable,
            work: None,
            start_cell,
            start,
            // The remarks are about this space's own start.
            warnings: if start_cell == self.start_cell {
                self.warnings.clone()
            } else {
                Vec::new()
            },
        }
    }

    /// This space with only the cells of `keep_coverable` left to cover and patterns confined to `work`
    /// ([`CoverageSpace::work`], masks one flag per cell), the robot starting at `start` in `start_cell`
    /// (on this space's reachable set, which stays whole: the robot drives across what is already covered).
    /// A start off the reachable set leaves nothing reachable and nothing to cover.
    pub fn with_work(&self, start_cell: Cell, start: Point2, keep_coverable: &[bool], work: &[bool]) -> Self {
        let g = *self.geometry();
        let on = g.index(start_cell) < g.len() && self.reachable[g.index(start_cell)];
        let mask = |m: &[bool], base: &[bool]| -> Vec<bool> {
            (0..g.len())
                .map(|i| on && base[i] && m.get(i).copied().unwrap_or(false))
                .collect()
        };
        Self {
            grid: self.grid.clone(),
            robot: self.robot,
            clearance: self.clearance.clone(),
            traversable: self.traversable.clone(),
            // The reachable set is one 8-connected piece, so any of its cells reaches all of it.
            reachable: if on {
                self.reachable.clone()
            } else {
                vec![false; g.len()]
            },
            coverable: mask(keep_coverable, &self.coverable),
            work: Some(mask(work, &self.reachable)),
            start_cell,
            start,
            warnings: Vec::new(),
        }
    }

    /// The raster geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.grid.geometry
    }

    /// Clearance of an arbitrary point (distance to the nearest non-free cell centre), metres.
    #[inline]
    pub fn clearance_at(&self, p: Point2) -> f64 {
        self.clearance.at_point(p)
    }

    /// A lower bound of `clearance_at(p)` from the distance stored at the centre of `p`'s cell alone
    /// (clearance changes by at most the distance moved; the relative 1e-6 covers the f32 storage);
    /// `-∞` off the map.
    #[inline]
    pub fn clearance_lower_bound(&self, p: Point2) -> f64 {
        let g = self.geometry();
        g.locate(p).map_or(f64::NEG_INFINITY, |c| {
            let i = g.index(c);
            self.clearance.at(i) * (1.0 - 1e-6) - (p - g.center_of(i)).norm() - 1e-9
        })
    }

    /// True when `clearance_at(p) >= r`; the cheap [`CoverageSpace::clearance_lower_bound`] decides for most
    /// points away from obstacles, the exact lookup for the rest.
    #[inline]
    pub fn has_clearance(&self, p: Point2, r: f64) -> bool {
        self.clearance_lower_bound(p) >= r || self.clearance_at(p) >= r
    }

    /// True when the robot centre may stand at `p`: on the reachable set with at least `radius` clearance.
    /// A point on a cell edge or corner (a diagonal step's midpoint) belongs to every cell that touches it.
    #[inline]
    pub fn point_ok(&self, p: Point2) -> bool {
        if !self.has_clearance(p, self.robot.radius_m - 1e-9) {
            return false;
        }
        let g = self.geometry();
        let e = g.resolution * 1e-6;
        [(0.0, 0.0), (e, e), (-e, e), (e, -e), (-e, -e)]
            .iter()
            .filter_map(|&(dx, dy)| g.locate(Point2::new(p.x + dx, p.y + dy)))
            .any(|c| self.reachable[g.index(c)])
    }

    /// True when every point of segment `a`–`b` keeps `radius` clearance on the reachable set, checked every
    /// quarter cell. Samples with clearance to spare let the check leap over the samples after them (sphere
    /// tracing): clearance changes by at most the distance moved, so when sample p has clearance
    /// `radius + half a cell diagonal + s`, every cell whose centre lies within `s` plus half a diagonal of p
    /// is traversable and 8-connected to p's (reachable) cell, and every sample within `s` of p passes. The
    /// answer is the same as checking every sample.
    pub fn segment_ok(&self, a: Point2, b: Point2) -> bool {
        let len = (b - a).norm();
        let res = self.geometry().resolution;
        let n = (len / (res * 0.25)).ceil().max(1.0) as usize;
        let spacing = len / n as f64;
        let margin = self.robot.radius_m + res * std::f64::consts::FRAC_1_SQRT_2;
        let mut k = 0;
        while k <= n {
            let p = a + (b - a) * (k as f64 / n as f64);
            if !self.point_ok(p) {
                return false;
            }
            k += self.samples_clear_ahead(p, margin, spacing);
        }
        true
    }

    /// How many samples `spacing` apart to advance from `p` along a line: all those within the clearance
    /// that `p` has beyond `needed` (their clearance is at least `needed` minus what that leaves, since
    /// clearance changes by at most the distance moved), and at least one.
    #[inline]
    pub fn samples_clear_ahead(&self, p: Point2, needed: f64, spacing: f64) -> usize {
        let slack = self.clearance_lower_bound(p) - needed;
        if spacing > 0.0 && slack > spacing {
            (slack / spacing).floor() as usize
        } else {
            1
        }
    }

    /// Number of reachable cells.
    pub fn reachable_count(&self) -> usize {
        self.reachable.iter().filter(|&&r| r).count()
    }

    /// Number of coverable cells.
    pub fn coverable_count(&self) -> usize {
        self.coverable.iter().filter(|&&r| r).count()
    }

    fn cell_area_m2(&self) -> f64 {
        let r = self.geometry().resolution;
        r * r
    }

    /// Area of the reachable cells (where the robot's centre can go from the start), m².
    pub fn reachable_area_m2(&self) -> f64 {
        self.reachable_count() as f64 * self.cell_area_m2()
    }

    /// Area of the coverable cells (what a complete plan covers), m².
    pub fn coverable_area_m2(&self) -> f64 {
        self.coverable_count() as f64 * self.cell_area_m2()
    }

    /// Area of the free cells of the whole map, m².
    pub fn free_area_m2(&self) -> f64 {
        (0..self.grid.cells.len()).filter(|&i| self.grid.is_free(i)).count() as f64 * self.cell_area_m2()
    }
}

/// 8-connected flood fill of `mask` from `seed` (seed 004, Alg. 1 with 8 neighbours).
pub fn flood_fill8(g: &GridGeometry, mask: &[bool], seed: Cell) -> Vec<bool> {
    let mut out = vec![false; g.len()];
    let s = g.index(seed);
    if !mask[s] {
        return out;
    }
    out[s] = true;
    let mut queue = VecDeque::from([seed]);
    while let Some(c) = queue.pop_front() {
        for n in g.neighbors8(c) {
            let i = g.index(n);
            if mask[i] && !out[i] {
                out[i] = true;
                queue.push_back(n);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    /// The fast clearance test agrees with the exact clearance everywhere, on and off the map, near and
    /// far from obstacles (oracle: `clearance_at`).
    #[test]
    fn clearance_test_agrees_with_the_exact_clearance() {
        let (mut spaces, mut yes, mut no) = (0, 0, 0);
        for seed in 1..=20_u64 {
            let Some(space) = crate::decompose::tests::random_space(seed, 40, 30, 6) else {
                continue;
            };
            spaces += 1;
            for i in 0..=100 {
                for j in 0..=80 {
                    let p = Point2::new(-0.5 + 0.05 * i as f64 + 0.0013 * seed as f64, -0.5 + 0.05 * j as f64);
                    for r in [0.0, 0.1, 0.2, 0.2 + 1e-7, 0.35, 0.8] {
                        let fast = space.has_clearance(p, r);
                        assert_eq!(fast, space.clearance_at(p) >= r, "seed {seed} {p:?} r {r}");
                        if fast { yes += 1 } else { no += 1 }
                    }
                }
            }
        }
        assert!(
            spaces >= 10 && yes > 1000 && no > 1000,
            "{spaces} spaces, {yes} clear, {no} not"
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
        /// The leaping segment test gives the same answer as checking every quarter-cell sample (oracle).
        #[test]
        fn segment_test_agrees_with_checking_every_sample(
            seed in 1u64..40,
            ax in -0.2f64..4.2, ay in -0.2f64..3.2, bx in -0.2f64..4.2, by in -0.2f64..3.2,
        ) {
            let Some(space) = crate::decompose::tests::random_space(seed, 40, 30, 6) else { return Ok(()) };
            let (a, b) = (Point2::new(ax, ay), Point2::new(bx, by));
            let n = ((b - a).norm() / (space.geometry().resolution * 0.25)).ceil().max(1.0) as usize;
            let every = (0..=n).all(|k| space.point_ok(a + (b - a) * (k as f64 / n as f64)));
            proptest::prop_assert_eq!(space.segment_ok(a, b), every, "{:?} {:?}", a, b);
        }
    }

    #[test]
    fn coarsening_keeps_obstacles_and_the_start() {
        let g = GridGeometry::new(41, 30, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(2.01, 1.0, 2.09, 2.0, CellState::Occupied);
        let robot = RobotShape {
            radius_m: 0.3,
            tool_width_m: 0.6,
        };
        let space = CoverageSpace::new(grid, robot, Point2::new(0.5, 0.5)).expect("space");
        let coarse = space.coarsened(2).expect("coarse");
        let cg = *coarse.geometry();
        assert_eq!((cg.width, cg.height), (21, 15));
        assert!((cg.resolution - 0.2).abs() < 1e-12);
        let wall = cg.index(cg.locate(Point2::new(2.02, 1.5)).expect("on map"));
        assert!(!coarse.grid.is_free(wall), "a thin wall survives coarsening");
        assert_eq!(coarse.start, space.start);
        assert!(coarse.reachable_count() > 0);
    }

    use super::*;
    use crate::map::CellState;

    fn room() -> OccupancyGrid {
        // 4 m × 2 m at 0.1 m, walls around, a wall splitting it at x = 2 m with no door.
        let g = GridGeometry::new(40, 20, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(1.95, 0.0, 2.05, 2.0, CellState::Occupied);
        grid
    }

    #[test]
    fn reach_stops_at_walls_and_coverable_reaches_them() {
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        let s = CoverageSpace::new(room(), robot, Point2::new(0.5, 1.0)).expect("ok");
        let g = *s.geometry();
        assert!(s.warnings.is_empty());
        for i in 0..g.len() {
            let p = g.center_of(i);
            if s.reachable[i] {
                assert!(p.x < 1.95 && s.clearance.at(i) >= 0.2 - 1e-9);
            }
            if s.coverable[i] {
                assert!(p.x < 1.95);
            }
        }
        // The cell next to the dividing wall is coverable: it is 0.1 m from a reachable cell... within 0.2.
        assert!(s.coverable[g.index(g.locate(Point2::new(1.85, 1.0)).expect("on map"))]);
        assert!(!s.reachable[g.index(g.locate(Point2::new(1.85, 1.0)).expect("on map"))]);
    }

    #[test]
    fn start_in_obstacle_snaps_with_warning() {
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        let s = CoverageSpace::new(room(), robot, Point2::new(2.0, 1.0)).expect("ok");
        assert_eq!(s.warnings.len(), 1);
        assert!(s.reachable[s.geometry().index(s.start_cell)]);
        assert!((s.start.x - 2.0).abs() < 0.35);
    }

    #[test]
    fn rejects_bad_requests() {
        let ok = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        assert!(matches!(
            CoverageSpace::new(room(), ok, Point2::new(9.0, 1.0)),
            Err(PlannerError::StartOutsideMap { .. })
        ));
        assert!(matches!(
            CoverageSpace::new(room(), ok, Point2::new(f64::NAN, 1.0)),
            Err(PlannerError::NonFinite { .. })
        ));
        let bad = RobotShape {
            radius_m: -0.2,
            tool_width_m: 0.4,
        };
        assert!(matches!(
            CoverageSpace::new(room(), bad, Point2::new(0.5, 1.0)),
            Err(PlannerError::InvalidParam { .. })
        ));
        let huge = RobotShape {
            radius_m: 5.0,
            tool_width_m: 0.4,
        };
        assert!(matches!(
            CoverageSpace::new(room(), huge, Point2::new(0.5, 1.0)),
            Err(PlannerError::NoTraversableSpace { .. })
        ));
    }
}
