//! Lanes follow the map: on a generated map of two perpendicular corridors (an L: one along x, one along
//! y, each 4 m wide and 30 m long, not a shared scene) each corridor is swept along its length — the plan
//! has about as many turns as lanes along the corridors need, not the hundreds that lanes across them would.

use shift_planner::geom::Point2;
use shift_planner::map::{CellState, GridGeometry, OccupancyGrid};
use shift_planner::pipeline::{NoMonitor, PlanParams, plan};
use shift_planner::space::{CoverageSpace, RobotShape};

#[test]
fn each_of_two_perpendicular_corridors_is_swept_along_its_length() {
    let res = 0.1;
    let (len, width) = (30.0, 4.0);
    let n = ((len + 1.0) / res) as usize;
    let g = GridGeometry::new(n, n, res, Point2::origin()).expect("geometry");
    let mut grid = OccupancyGrid::filled(g, CellState::Occupied);
    for i in 0..g.len() {
        let p = g.center_of(i);
        let along_x = p.x > 0.5 && p.x < 0.5 + len && p.y > 0.5 && p.y < 0.5 + width;
        let along_y = p.x > 0.5 && p.x < 0.5 + width && p.y > 0.5 && p.y < 0.5 + len;
        if along_x || along_y {
            grid.cells[i] = CellState::Free;
        }
    }
    let robot = RobotShape {
        radius_m: 0.25,
        tool_width_m: 0.5,
    };
    let space = CoverageSpace::new(grid, robot, Point2::new(2.0, 2.0)).expect("space");
    let out = plan(&space, &PlanParams::default(), &mut NoMonitor).expect("plan");
    let m = out.metrics;
    assert!(m.coverage_pct >= 99.0 && m.collisions == 0, "{m:?}");
    // Lanes along both corridors: about width / tool = 8 lanes each, two turns per lane: ~32 turns, plus
    // the corner square, passes and transits. Lanes across a corridor would need len / tool = 60 lanes.
    assert!(m.turns <= 80, "{} turns: some corridor is swept across", m.turns);
    // The cover length that runs along each corridor's axis dominates there.
    let pts = out.points();
    let (mut in_x, mut in_y) = ([0.0f64; 2], [0.0f64; 2]);
    for s in pts.windows(2) {
        let (a, b) = (s[0], s[1]);
        let mid = a + (b - a) / 2.0;
        let d = b - a;
        if mid.x > 0.5 + width + 1.0 {
            in_x[0] += d.x.abs();
            in_x[1] += d.y.abs();
        } else if mid.y > 0.5 + width + 1.0 {
            in_y[0] += d.x.abs();
            in_y[1] += d.y.abs();
        }
    }
    assert!(in_x[0] > 4.0 * in_x[1], "corridor along x: {in_x:?} (|dx|, |dy|)");
    assert!(in_y[1] > 4.0 * in_y[0], "corridor along y: {in_y:?} (|dx|, |dy|)");
}
