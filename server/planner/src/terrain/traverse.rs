//! Traversability for ground robots: slope, step height and roughness against the robot's limits → the
//! planner's own [`OccupancyGrid`], so the coverage pipeline plans on terrain as on any map.
//!
//! Per cell, on the smoothed surface:
//! - slope: the angle from the horizontal of the plane fitted (least squares) to the 3 × 3 cells around it,
//!   i.e. of its surface normal;
//! - roughness: the RMS residual of the heights of those cells to that plane, metres;
//! - step: the largest rise to an 8-neighbour beyond what the steepest allowed slope climbs over that distance,
//!   max_j (|z_j − z_i| − d_j · tan(max_slope)), metres. A ramp within the slope limit has no step, however
//!   coarse the grid; a kerb of height h shows a step of h − g·tan(max_slope) on both of its sides. (On a grid
//!   coarser than the kerb is high, h over one cell is indistinguishable from a ramp: pick the grid to suit.)
//!
//! A cell is occupied when any of them is over its limit; filled cells farther than `max_fill_m` from data
//! are unknown (never free, DESIGN §6); the rest are free.

use super::plane::fit_plane;
use super::surface::TerrainSurface;
use crate::error::{PlannerError, Result, finite};
use crate::map::{CellState, GridGeometry, OccupancyGrid};

/// What a ground robot can drive on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundLimits {
    /// Steepest slope, radians, in [0, π/2).
    pub max_slope_rad: f64,
    /// Highest step, metres.
    pub max_step_m: f64,
    /// Largest RMS roughness over a 3 × 3 cell patch, metres.
    pub max_roughness_m: f64,
}

impl Default for GroundLimits {
    /// An outdoor sweeper: 15°, 10 cm, 5 cm.
    fn default() -> Self {
        Self {
            max_slope_rad: 15f64.to_radians(),
            max_step_m: 0.10,
            max_roughness_m: 0.05,
        }
    }
}

impl GroundLimits {
    /// Checks the ranges, naming the field that is wrong.
    pub fn validate(&self) -> Result<()> {
        let slope = finite("max_slope_rad", self.max_slope_rad)?;
        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&slope) {
            return Err(PlannerError::InvalidParam {
                name: "max_slope_rad",
                reason: format!("must lie in [0, π/2), got {slope}"),
            });
        }
        for (name, v) in [
            ("max_step_m", self.max_step_m),
            ("max_roughness_m", self.max_roughness_m),
        ] {
            if finite(name, v)? < 0.0 {
                return Err(PlannerError::InvalidParam {
                    name,
                    reason: format!("must be ≥ 0 m, got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// The three traversability measures per cell.
#[derive(Debug, Clone, PartialEq)]
pub struct Traversability {
    /// Raster geometry (that of the surface).
    pub geometry: GridGeometry,
    /// Slope per cell, radians.
    pub slope_rad: Vec<f64>,
    /// Step per cell, metres (0 when no neighbour rises faster than the slope limit).
    pub step_m: Vec<f64>,
    /// Roughness per cell, metres.
    pub roughness_m: Vec<f64>,
}

impl Traversability {
    /// Measures a surface; the step depends on the slope limit.
    pub fn new(surface: &TerrainSurface, limits: &GroundLimits) -> Result<Self> {
        limits.validate()?;
        let g = &surface.geometry;
        let z = &surface.heights;
        let tan_max = limits.max_slope_rad.tan();
        let n = g.len();
        let (mut slope_rad, mut step_m, mut roughness_m) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut samples = Vec::with_capacity(9);
        for i in 0..n {
            let c = g.cell(i);
            samples.clear();
            let mut step = 0.0f64;
            for dy in -1..=1isize {
                for dx in -1..=1isize {
                    let Some(o) = g.offset(c, dx, dy) else { continue };
                    let j = g.index(o);
                    let (mx, my) = (dx as f64 * g.resolution, dy as f64 * g.resolution);
                    samples.push([mx, my, z[j], 1.0]);
                    step = step.max((z[j] - z[i]).abs() - mx.hypot(my) * tan_max);
                }
            }
            if let Some(fit) = fit_plane(&samples) {
                slope_rad[i] = fit.slope_rad();
                roughness_m[i] = fit.rms_residual;
            }
            step_m[i] = step;
        }
        Ok(Self {
            geometry: *g,
            slope_rad,
            step_m,
            roughness_m,
        })
    }

    /// True when cell `i` is within every limit.
    pub fn passable(&self, i: usize, limits: &GroundLimits) -> bool {
        self.slope_rad[i] <= limits.max_slope_rad
            && self.step_m[i] <= limits.max_step_m
            && self.roughness_m[i] <= limits.max_roughness_m
    }

    /// The occupancy grid: occupied over a limit, unknown where the surface was filled farther than
    /// `max_fill_m` from data, free elsewhere.
    pub fn occupancy(&self, surface: &TerrainSurface, limits: &GroundLimits, max_fill_m: f64) -> Result<OccupancyGrid> {
        finite("max_fill_m", max_fill_m)?;
        let cells = (0..self.geometry.len())
            .map(|i| {
                if f64::from(surface.fill_ring[i]) * self.geometry.resolution > max_fill_m {
                    CellState::Unknown
                } else if self.passable(i, limits) {
                    CellState::Free
                } else {
                    CellState::Occupied
                }
            })
            .collect();
        OccupancyGrid::new(self.geometry, cells)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point2;
    use crate::map::Cell;

    fn geometry(n: usize, g: f64) -> GridGeometry {
        GridGeometry::new(n, n, g, Point2::origin()).expect("geometry")
    }

    fn occupancy(s: &TerrainSurface, limits: &GroundLimits) -> OccupancyGrid {
        Traversability::new(s, limits)
            .and_then(|t| t.occupancy(s, limits, 1.0))
            .expect("occupancy")
    }

    #[test]
    fn a_ramp_steeper_than_the_limit_is_occupied_a_gentler_one_free() {
        let limits = GroundLimits::default();
        for (deg, want) in [
            (20.0f64, CellState::Occupied),
            (10.0, CellState::Free),
            (14.5, CellState::Free),
        ] {
            let slope = deg.to_radians().tan();
            let s = TerrainSurface::from_fn(geometry(40, 0.1), |x, y| slope * (0.6 * x + 0.8 * y)).expect("surface");
            let t = Traversability::new(&s, &limits).expect("measures");
            let worst = t
                .slope_rad
                .iter()
                .map(|a| (a - deg.to_radians()).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-9, "{deg}°: slope error {worst}");
            let grid = occupancy(&s, &limits);
            assert!(
                grid.cells.iter().all(|&c| c == want),
                "{deg}° ramp should be all {want:?}"
            );
        }
    }

    #[test]
    fn a_ramp_within_the_limit_has_no_step_even_on_a_coarse_grid() {
        let slope = 14f64.to_radians().tan();
        let s = TerrainSurface::from_fn(geometry(20, 1.0), |x, _| slope * x).expect("surface");
        let t = Traversability::new(&s, &GroundLimits::default()).expect("measures");
        assert!(
            t.step_m.iter().all(|&v| v <= 0.0),
            "a 14° ramp rises 0.25 m per metre, yet is no step"
        );
        assert!(
            occupancy(&s, &GroundLimits::default())
                .cells
                .iter()
                .all(|&c| c == CellState::Free)
        );
    }

    #[test]
    fn a_twenty_centimetre_kerb_is_a_wall_for_a_ten_centimetre_step_limit() {
        let g = 0.05;
        let s = TerrainSurface::from_fn(geometry(40, g), |x, _| if x > 1.0 { 0.2 } else { 0.0 }).expect("surface");
        let limits = GroundLimits::default();
        let t = Traversability::new(&s, &limits).expect("measures");
        let grid = occupancy(&s, &limits);
        let want_step = 0.2 - g * limits.max_slope_rad.tan();
        for y in 0..40 {
            // The kerb lies between columns 19 (x = 0.975) and 20 (x = 1.025).
            for x in [19, 20] {
                let i = grid.geometry.index(Cell::new(x, y));
                assert!(
                    (t.step_m[i] - want_step).abs() < 1e-12,
                    "step {} at {x},{y}",
                    t.step_m[i]
                );
                assert_eq!(grid.cells[i], CellState::Occupied, "kerb cell {x},{y}");
            }
            for x in (0..19).chain(21..40) {
                assert_eq!(grid.state(Cell::new(x, y)), CellState::Free, "flat cell {x},{y}");
            }
        }
        // A robot that climbs 25 cm steps and any slope or roughness drives over it.
        let climber = GroundLimits {
            max_slope_rad: 1.5,
            max_step_m: 0.25,
            max_roughness_m: 1.0,
        };
        assert!(occupancy(&s, &climber).cells.iter().all(|&c| c == CellState::Free));
    }

    #[test]
    fn bumps_are_rough_and_far_fills_unknown() {
        let s = TerrainSurface::from_fn(geometry(30, 0.1), |x, y| 0.12 * ((x * 31.4).sin() * (y * 31.4).sin()))
            .expect("surface");
        let limits = GroundLimits {
            max_slope_rad: 1.5,
            max_step_m: 1.0,
            max_roughness_m: 0.02,
        };
        let t = Traversability::new(&s, &limits).expect("measures");
        assert!(t.roughness_m.iter().any(|&r| r > 0.05));
        assert!(occupancy(&s, &limits).cells.contains(&CellState::Occupied));
        let mut far = TerrainSurface::from_fn(geometry(10, 0.5), |_, _| 0.0).expect("surface");
        far.fill_ring[0] = 3;
        far.fill_ring[1] = 2;
        let grid = occupancy(&far, &GroundLimits::default());
        assert_eq!((grid.cells[0], grid.cells[1]), (CellState::Unknown, CellState::Free));
    }

    #[test]
    fn bad_limits_are_named() {
        let s = TerrainSurface::from_fn(geometry(4, 1.0), |_, _| 0.0).expect("surface");
        let bad = GroundLimits {
            max_slope_rad: 2.0,
            ..GroundLimits::default()
        };
        assert!(matches!(
            Traversability::new(&s, &bad),
            Err(PlannerError::InvalidParam {
                name: "max_slope_rad",
                ..
            })
        ));
        let bad = GroundLimits {
            max_step_m: f64::NAN,
            ..GroundLimits::default()
        };
        assert!(matches!(
            Traversability::new(&s, &bad),
            Err(PlannerError::NonFinite {
                field: "max_step_m",
                ..
            })
        ));
    }
}
