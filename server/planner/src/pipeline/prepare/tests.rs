//! Prepared plans: driven routes meet the coverage target, the estimate never overstates the plan, and steps
//! through a wall cost the way round.

use super::*;
use crate::map::{CellState, GridGeometry, OccupancyGrid};
use crate::pattern::TaskKind;
use crate::pipeline::NoMonitor;
use crate::space::RobotShape;

/// 6 m × 4 m at 0.1 m with a wall at x = 3 m from the floor to y = 3.2 m (a door above it).
fn two_rooms() -> CoverageSpace {
    let g = GridGeometry::new(60, 40, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    for y in 0..32 {
        grid.cells[y * 60 + 30] = CellState::Occupied;
    }
    let robot = RobotShape {
        radius_m: 0.2,
        tool_width_m: 0.4,
    };
    CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space")
}

#[test]
fn driven_routes_meet_the_coverage_target_and_the_estimate_never_overstates_the_plan() {
    use crate::decompose::DecompositionMethod;
    for seed in [3_u64, 8, 21] {
        let Some(space) = crate::decompose::tests::random_space(seed, 60, 45, 8) else {
            continue;
        };
        let params = PlanParams {
            decomposition: DecompositionMethod::Bcd,
            lanes: LaneParams {
                placement: Some(Placement::Lattice),
                ..LaneParams::default()
            },
            seed,
            ..PlanParams::default()
        };
        let near = nearest_reachable(&space);
        let basis = Arc::new(Basis::new(&space, &params, &near));
        let prepared = prepare(&space, &params, (basis, &near, &OnceLock::new()), &mut NoMonitor).expect("prepare");
        let e = prepared.estimate;
        // The steps the tour drives (straight, along walls, linked round obstacles) are in the estimate:
        // passes were added until they cover the target (within the top-up tolerance).
        assert!(
            e.coverage_pct + 1e-9 >= params.passes.coverage_target_pct - TOP_UP_TOLERANCE_PCT,
            "seed {seed}: {e:?}"
        );
        let out = super::super::assemble::assemble(&space, prepared, &mut NoMonitor).expect("assemble");
        // Links only add coverage; the estimate may not claim more than the plan covers.
        assert!(
            out.metrics.coverage_pct + 1e-9 >= e.coverage_pct,
            "seed {seed}: plan {:?} vs estimate {e:?}",
            out.metrics
        );
    }
}

#[test]
fn steps_through_a_wall_cost_the_way_round() {
    let space = two_rooms();
    let lane = |x: f64| Task {
        points: vec![Point2::new(x, 0.55), Point2::new(x, 2.55)],
        kind: TaskKind::Lane,
    };
    // Two lanes 0.9 m apart on either side of the wall: the straight step is 0.9 m, the way round
    // through the door above y = 3.2 m is over 5 m.
    let tasks = vec![vec![lane(2.55), lane(3.45)]];
    let mut options = vec![Vec::new()];
    route_regions(
        (&space, &WallSteps::default(), &Linked::default()),
        &LinkParams::default(),
        (&tasks, &[std::f64::consts::FRAC_PI_2]),
        1,
        &NoMonitor,
        &mut options,
        0..1,
    );
    assert!(!options[0].is_empty());
    for r in &options[0] {
        // 4 m of lanes plus a step of at least 2 × (3.2 − 2.55) m up to the door and back down.
        assert!(
            r.cost > 4.0 + 2.0 * (3.2 - 2.55),
            "route cost {} ignores the wall",
            r.cost
        );
        assert!(r.cost < 4.0 + 8.0, "route cost {} is not a real way round", r.cost);
    }
    assert!(through_obstacle(
        &space,
        Point2::new(2.55, 0.55),
        Point2::new(3.45, 0.55)
    ));
    assert!(!through_obstacle(
        &space,
        Point2::new(2.55, 0.55),
        Point2::new(2.55, 2.55)
    ));
}
