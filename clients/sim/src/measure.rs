//! What was really covered, by the simulator's own measure (DESIGN §6 definitions on the hidden world): the
//! cells swept by each robot's tool along its driven trace, against the coverable cells of the world with its
//! hidden static obstacles (reachable from the robot's start with its radius; within its region when its plan
//! was restricted to one).

use shift_planner::geom::{Point2, point_in_polygon};
use shift_planner::map::OccupancyGrid;
use shift_planner::space::{CoverageSpace, RobotShape};

use crate::robot::SimRobot;

/// Covered fractions, percent.
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    /// Per robot: its swept cells over its own coverable cells (within its region).
    pub robots: Vec<f64>,
    /// The fleet: cells any robot swept over cells any robot could cover.
    pub fleet: f64,
}

fn coverable(grid: &OccupancyGrid, robot: &SimRobot) -> Vec<bool> {
    let shape = RobotShape {
        radius_m: robot.spec.radius,
        tool_width_m: robot.spec.tool_width,
    };
    let start = Point2::new(robot.spec.start[0], robot.spec.start[1]);
    let mut mask = match CoverageSpace::with_start_snap(grid.clone(), shape, start, Some(1.0)) {
        Ok(space) => space.coverable,
        Err(e) => {
            tracing::warn!(robot = %robot.spec.id, "no coverable area: {e}");
            vec![false; grid.cells.len()]
        }
    };
    if let Some(region) = &robot.spec.region {
        let g = grid.geometry;
        for (i, m) in mask.iter_mut().enumerate() {
            *m = *m && point_in_polygon(g.center_of(i), region);
        }
    }
    mask
}

fn pct(part: usize, whole: usize) -> f64 {
    if whole == 0 {
        0.0
    } else {
        100.0 * part as f64 / whole as f64
    }
}

/// Measures the robots' swept cells against `world_grid` (the map with hidden static obstacles burned in).
pub fn measure(world_grid: &OccupancyGrid, robots: &[SimRobot]) -> Coverage {
    let n = world_grid.cells.len();
    let mut fleet_coverable = vec![false; n];
    let mut fleet_swept = vec![false; n];
    let mut per_robot = Vec::with_capacity(robots.len());
    for robot in robots {
        let mask = coverable(world_grid, robot);
        let swept = robot.swept.covered();
        let mine = (0..n).filter(|&i| mask[i] && swept[i]).count();
        per_robot.push(pct(mine, mask.iter().filter(|&&m| m).count()));
        for i in 0..n {
            fleet_coverable[i] |= mask[i];
            fleet_swept[i] |= swept[i];
        }
    }
    let covered = (0..n).filter(|&i| fleet_coverable[i] && fleet_swept[i]).count();
    let whole = fleet_coverable.iter().filter(|&&m| m).count();
    Coverage {
        robots: per_robot,
        fleet: pct(covered, whole),
    }
}
