//! What was really covered, by the simulator's own measure (DESIGN §6 definitions on the hidden world): the
//! cells swept by each robot's tool along its driven trace, against the coverable cells of the world with its
//! hidden static obstacles (reachable from the robot's start with its radius; within its region when its plan
//! was restricted to one).

use shift_planner::geom::{Point2, point_in_polygon};
use shift_planner::map::{CellState, OccupancyGrid};
use shift_planner::space::{CoverageSpace, RobotShape};

use crate::robot::SimRobot;

/// Covered fractions, percent.
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    /// Per robot: its swept cells over its own coverable cells (within its region).
    pub robots: Vec<f64>,
    /// The fleet: cells any robot swept over cells any robot could cover.
    pub fleet: f64,
    /// The most the fleet's plans can cover when every robot keeps inside its region (as the daemon plans a
    /// request with a `region`: cells outside it are unknown): cells some robot reaches from its start without
    /// leaving its region, over the fleet's coverable cells. 100 without regions; below it, the rest of the
    /// area lies in pockets of a region that its robot can only reach through a neighbour's.
    pub fleet_within_regions: f64,
}

/// The cells `robot` can cover on `grid` from its start (DESIGN §6 coverable), or none with a warning.
fn coverable_on(grid: OccupancyGrid, robot: &SimRobot) -> Vec<bool> {
    let shape = RobotShape {
        radius_m: robot.spec.radius,
        tool_width_m: robot.spec.tool_width,
    };
    let start = Point2::new(robot.spec.start[0], robot.spec.start[1]);
    let n = grid.cells.len();
    match CoverageSpace::with_start_snap(grid, shape, start, Some(1.0)) {
        Ok(space) => space.coverable,
        Err(e) => {
            tracing::warn!(robot = %robot.spec.id, "no coverable area: {e}");
            vec![false; n]
        }
    }
}

/// The robot's coverable cells (reachable over the whole world) within its region, and those it reaches
/// without leaving the region (the same without a region).
fn coverable(grid: &OccupancyGrid, robot: &SimRobot) -> (Vec<bool>, Vec<bool>) {
    let mut mask = coverable_on(grid.clone(), robot);
    let Some(region) = &robot.spec.region else {
        return (mask.clone(), mask);
    };
    let g = grid.geometry;
    let inside: Vec<bool> = (0..grid.cells.len())
        .map(|i| point_in_polygon(g.center_of(i), region))
        .collect();
    for (m, &inside) in mask.iter_mut().zip(&inside) {
        *m = *m && inside;
    }
    let mut confined = grid.clone();
    for (c, &inside) in confined.cells.iter_mut().zip(&inside) {
        if !inside {
            *c = CellState::Unknown;
        }
    }
    (mask, coverable_on(confined, robot))
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
    let mut fleet_confined = vec![false; n];
    let mut per_robot = Vec::with_capacity(robots.len());
    for robot in robots {
        let (mask, confined) = coverable(world_grid, robot);
        let swept = robot.swept.covered();
        let mine = (0..n).filter(|&i| mask[i] && swept[i]).count();
        per_robot.push(pct(mine, mask.iter().filter(|&&m| m).count()));
        for i in 0..n {
            fleet_coverable[i] |= mask[i];
            fleet_swept[i] |= swept[i];
            fleet_confined[i] |= confined[i];
        }
    }
    let covered = (0..n).filter(|&i| fleet_coverable[i] && fleet_swept[i]).count();
    let whole = fleet_coverable.iter().filter(|&&m| m).count();
    let reachable = (0..n).filter(|&i| fleet_coverable[i] && fleet_confined[i]).count();
    Coverage {
        robots: per_robot,
        fleet: pct(covered, whole),
        fleet_within_regions: pct(reachable, whole),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::file::RobotSpecFile;
    use shift_planner::map::{Cell, GridGeometry};

    fn robot(id: &str, x: f64, y: f64, region: Option<Vec<[f64; 2]>>, g: GridGeometry) -> SimRobot {
        let spec = RobotSpecFile {
            id: id.into(),
            start: [x, y, 0.0],
            radius: 0.2,
            tool_width: 0.4,
            v_max: None,
            a_max: None,
            w_max: None,
            region,
        };
        SimRobot::new(spec, g, 0.2)
    }

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
        vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
    }

    /// A 10 × 4 m room with a wall at y = 2 along its left half: the left region's upper half can be reached
    /// only through the right region.
    #[test]
    fn a_pocket_reached_only_through_a_neighbours_region_is_outside_what_the_plans_can_cover() {
        let g = GridGeometry::new(100, 40, 0.1, Point2::new(0.0, 0.0)).expect("geometry");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        for x in 0..50 {
            grid.set(Cell::new(x, 20), CellState::Occupied);
        }
        let open = measure(&grid, &[robot("a", 2.5, 1.0, None, g), robot("b", 7.5, 2.0, None, g)]);
        assert!((open.fleet_within_regions - 100.0).abs() < 1e-9);
        assert!(open.fleet.abs() < 1e-9, "nothing was driven");

        let left = rect(0.0, 0.0, 5.0, 4.0);
        let right = rect(5.0, 0.0, 10.0, 4.0);
        let split = measure(
            &grid,
            &[
                robot("a", 2.5, 1.0, Some(left), g),
                robot("b", 7.5, 2.0, Some(right), g),
            ],
        );
        // The pocket (x < 5, y > 2) is about a quarter of the room.
        assert!(
            (70.0..80.0).contains(&split.fleet_within_regions),
            "{}",
            split.fleet_within_regions
        );
    }
}
