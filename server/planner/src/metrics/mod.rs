//! Plan metrics exactly as DESIGN §6 defines them. The CLI, the API and the benches all call [`evaluate`].
//!
//! - coverage_pct = |covered ∩ coverable| / |coverable| × 100, covered = cells whose centre lies within
//!   tool_width / 2 of the path;
//! - overlap_pct = (length × tool_width − covered area) / covered area × 100;
//! - turns = heading changes of 30° or more between consecutive segments;
//! - collisions = path points (every segment sampled each quarter cell) closer than robot_radius to a non-free
//!   cell centre; with a footprint polygon, poses whose polygon overlaps a non-free cell
//!   (`crate::footprint::FootprintCheck::count_collisions`, which `pipeline::plan_footprinted` puts here).

pub mod coverage;
pub mod dwell;

pub use coverage::CoverageRaster;
pub use dwell::{DwellMetrics, evaluate_dwell};

use crate::geom::{Point2, heading_change};
use crate::space::CoverageSpace;

/// A heading change at least this large counts as a turn (radians).
pub const TURN_THRESHOLD_RAD: f64 = std::f64::consts::PI / 6.0;

/// Figures of merit of a path on a coverage space.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct PlanMetrics {
    /// Share of coverable cells covered, percent.
    pub coverage_pct: f64,
    /// Swept area beyond the covered area, percent of the covered area.
    pub overlap_pct: f64,
    /// Path length, metres.
    pub length_m: f64,
    /// Heading changes of 30° or more.
    pub turns: usize,
    /// Sampled path points closer than the robot radius to a non-free cell (with a footprint polygon: sampled
    /// poses whose polygon overlaps a non-free cell).
    pub collisions: usize,
    /// Coverable cells.
    pub coverable_cells: usize,
    /// Coverable cells that are covered.
    pub covered_coverable_cells: usize,
}

/// Computes every metric of `path` (map frame, metres) on `space`.
pub fn evaluate(space: &CoverageSpace, path: &[Point2]) -> PlanMetrics {
    let g = *space.geometry();
    // The collision count runs beside the coverage raster (both walk the whole path).
    let (raster, collisions) = std::thread::scope(|scope| {
        let collisions = scope.spawn(|| count_collisions(space, path));
        let mut raster = CoverageRaster::new(g, space.robot.tool_width_m / 2.0);
        raster.stamp_polyline(path);
        (raster, collisions.join())
    });
    let collisions = match collisions {
        Ok(n) => n,
        Err(panic) => std::panic::resume_unwind(panic),
    };
    let length_m = crate::geom::polyline_length(path);
    let Coverage {
        coverage_pct,
        overlap_pct,
        coverable_cells,
        covered_coverable_cells,
    } = coverage_of(space, &raster, length_m);
    PlanMetrics {
        coverage_pct,
        overlap_pct,
        length_m,
        turns: count_turns(path),
        collisions,
        coverable_cells,
        covered_coverable_cells,
    }
}

/// DESIGN §6 coverage and overlap of a path of `length_m` whose covered cells are stamped on `raster`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coverage {
    /// |covered ∩ coverable| / |coverable|, percent (100 without coverable cells).
    pub coverage_pct: f64,
    /// (length × tool width − covered area) / covered area, percent (0 when nothing is covered).
    pub overlap_pct: f64,
    /// |coverable|.
    pub coverable_cells: usize,
    /// |covered ∩ coverable|.
    pub covered_coverable_cells: usize,
}

/// See [`Coverage`]; `evaluate` and the planner's estimates share it.
pub fn coverage_of(space: &CoverageSpace, raster: &CoverageRaster, length_m: f64) -> Coverage {
    let g = space.geometry();
    let coverable_cells = space.coverable_count();
    let covered_coverable_cells = (0..g.len())
        .filter(|&i| space.coverable[i] && raster.is_covered(i))
        .count();
    let covered_area = raster.count() as f64 * g.resolution * g.resolution;
    Coverage {
        coverage_pct: if coverable_cells > 0 {
            covered_coverable_cells as f64 / coverable_cells as f64 * 100.0
        } else {
            100.0
        },
        overlap_pct: if covered_area > 0.0 {
            (length_m * space.robot.tool_width_m - covered_area) / covered_area * 100.0
        } else {
            0.0
        },
        coverable_cells,
        covered_coverable_cells,
    }
}

/// Heading changes of at least 30° between consecutive non-degenerate segments.
pub fn count_turns(path: &[Point2]) -> usize {
    let dirs: Vec<_> = path
        .windows(2)
        .map(|s| s[1] - s[0])
        .filter(|d| d.norm() > 1e-9)
        .collect();
    dirs.windows(2)
        .filter(|d| heading_change(d[0], d[1]) >= TURN_THRESHOLD_RAD - 1e-12)
        .count()
}

/// Path points closer than the robot radius to a non-free cell, sampling each segment every quarter cell.
pub fn count_collisions(space: &CoverageSpace, path: &[Point2]) -> usize {
    let r = space.robot.radius_m - 1e-6;
    let step = space.geometry().resolution * 0.25;
    let mut n = 0;
    if let [p] = path {
        return usize::from(!space.has_clearance(*p, r));
    }
    for (k, s) in path.windows(2).enumerate() {
        let len = (s[1] - s[0]).norm();
        let m = (len / step).ceil().max(1.0) as usize;
        let spacing = len / m as f64;
        let mut j = if k == 0 { 0 } else { 1 };
        while j <= m {
            let p = s[0] + (s[1] - s[0]) * (j as f64 / m as f64);
            if !space.has_clearance(p, r) {
                n += 1;
            }
            // Samples within the clearance to spare are clear too (clearance changes by at most the distance
            // moved): leap over them; the count is that of checking every sample.
            j += space.samples_clear_ahead(p, r, spacing);
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::space::RobotShape;

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(128))]
        /// The leaping collision count equals the count over every quarter-cell sample (oracle).
        #[test]
        fn collision_count_equals_checking_every_sample(
            seed in 1u64..40,
            pts in proptest::collection::vec((-0.2f64..4.2, -0.2f64..3.2), 1..8),
        ) {
            let Some(space) = crate::decompose::tests::random_space(seed, 40, 30, 6) else { return Ok(()) };
            let path: Vec<Point2> = pts.iter().map(|&(x, y)| Point2::new(x, y)).collect();
            let r = space.robot.radius_m - 1e-6;
            let step = space.geometry().resolution * 0.25;
            let mut want = usize::from(path.len() == 1 && !space.has_clearance(path[0], r));
            for (k, s) in path.windows(2).enumerate() {
                let m = ((s[1] - s[0]).norm() / step).ceil().max(1.0) as usize;
                want += (usize::from(k > 0)..=m)
                    .filter(|&j| !space.has_clearance(s[0] + (s[1] - s[0]) * (j as f64 / m as f64), r))
                    .count();
            }
            proptest::prop_assert_eq!(count_collisions(&space, &path), want);
        }
    }

    #[test]
    fn lanes_over_an_empty_room() {
        // 3 m × 1.2 m room; tool 0.4: lanes at y = 0.2+0.1·k…, clearance radius 0.2.
        let g = GridGeometry::new(30, 12, 0.1, Point2::origin()).expect("valid");
        let grid = OccupancyGrid::filled(g, CellState::Free);
        let space = CoverageSpace::new(
            grid,
            RobotShape {
                radius_m: 0.2,
                tool_width_m: 0.4,
            },
            Point2::new(0.5, 0.5),
        )
        .expect("ok");
        // Reachable centres: x in [0.15, 2.85], y in [0.15, 1.05] (0.2 m from the ring outside the map).
        let path = vec![
            Point2::new(0.15, 0.15),
            Point2::new(2.85, 0.15),
            Point2::new(2.85, 0.45),
            Point2::new(0.15, 0.45),
            Point2::new(0.15, 0.75),
            Point2::new(2.85, 0.75),
            Point2::new(2.85, 1.05),
            Point2::new(0.15, 1.05),
        ];
        let m = evaluate(&space, &path);
        assert_eq!(m.collisions, 0);
        assert_eq!(m.turns, 6);
        assert!((m.length_m - (4.0 * 2.7 + 3.0 * 0.3)).abs() < 1e-9);
        assert_eq!(m.coverage_pct, 100.0, "{m:?}");
        // Four lanes where 3.5 would do: about 25 % overlap.
        assert!(m.overlap_pct > 15.0 && m.overlap_pct < 35.0, "{m:?}");
        // Dropping the middle lane leaves a band uncovered.
        let sparse = evaluate(&space, &[path[0], path[1], path[6], path[7]]);
        assert!(sparse.coverage_pct < 90.0, "{sparse:?}");
        // A path through the wall ring collides.
        let bad = evaluate(&space, &[Point2::new(0.05, 0.5), Point2::new(1.0, 0.5)]);
        assert!(bad.collisions > 0);
        // An empty path covers nothing.
        assert_eq!(evaluate(&space, &[]).coverage_pct, 0.0);
    }
}
