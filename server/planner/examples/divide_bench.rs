//! Division and fleet plans on the generated cluttered site (issue 20's bench):
//! `cargo run --release -p shift-planner --example divide_bench -- [SIDE_M] [ROBOTS ...]` (default 200 m,
//! 2 4 8 robots). Docks are spread along the site's edges. Prints, per fleet size, the division's time
//! (spaces, distances, balancing, ownership), the time to plan every part (all rounds), and the fleet's
//! figures: planned durations (longest, shortest, ratio), union coverage, seam overlap.

use std::time::Instant;

use shift_planner::divide::{DivideParams, FleetRobot, divide};
use shift_planner::pipeline::PlanParams;
use shift_planner::pipeline::fleet::{FleetParams, plan_fleet};
use shift_planner::space::RobotShape;
use shift_planner::speed::SpeedLimits;
use shift_planner::testing::{cluttered_site, rim_docks};

fn main() {
    let args: Vec<f64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let side = args.first().copied().unwrap_or(200.0);
    let sizes: Vec<usize> = if args.len() > 1 {
        args[1..].iter().map(|&n| n as usize).collect()
    } else {
        vec![2, 4, 8]
    };
    let grid = cluttered_site(side, side, 0.1, (side * side / 100.0) as usize, 7).expect("site");
    let shape = RobotShape {
        radius_m: 0.3,
        tool_width_m: 0.6,
    };
    for n in sizes {
        let robots: Vec<FleetRobot> = (rim_docks(side, n).into_iter())
            .map(|start| FleetRobot::disc(start, shape, SpeedLimits::default()))
            .collect();
        let t = Instant::now();
        let div = divide(&grid, &robots, None, None, &DivideParams::default()).expect("divides");
        let divide_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let fleet = plan_fleet(&grid, &robots, &PlanParams::default(), None, &FleetParams::default()).expect("plans");
        let fleet_ms = t.elapsed().as_secs_f64() * 1e3;
        let m = &fleet.metrics;
        println!(
            "{{\"side_m\": {side}, \"cells\": {}, \"robots\": {n}, \"divide_ms\": {divide_ms:.0}, \"expected_load_ratio\": {:.3}, \"fleet_plan_ms\": {fleet_ms:.0}, \"rounds\": {}, \"longest_s\": {:.0}, \"shortest_s\": {:.0}, \"duration_ratio\": {:.3}, \"coverage_pct\": {:.2}, \"seam_overlap_pct\": {:.2}, \"warnings\": {:?}}}",
            grid.cells.len(),
            div.load_ratio(),
            fleet.rounds,
            m.durations_s.iter().copied().fold(0.0, f64::max),
            m.durations_s.iter().copied().fold(f64::INFINITY, f64::min),
            m.duration_ratio,
            m.union_coverage_pct,
            m.seam_overlap_pct,
            fleet.division.warnings
        );
    }
}
