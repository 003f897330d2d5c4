//! The objective decides the plan: on open fields with a few obstacles (generated here, not the shared
//! scenes) the default, time, picks a plan that drives in less time than the plan the overlap objective
//! picks, and with at most 1.5 × the turns of a plain lane plan (the S-shape baseline); every objective
//! still meets the coverage bar without collisions.

use shift_planner::baseline::{Baseline, run_baseline};
use shift_planner::geom::Point2;
use shift_planner::map::{CellState, GridGeometry, OccupancyGrid};
use shift_planner::pipeline::{NoMonitor, Objective, PlanParams, plan};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::{SpeedLimits, SpeedParams, profile_path};

/// A `w_m` × `h_m` field at 0.2 m with rectangular obstacles `[x0, y0, x1, y1]` (metres).
fn field(w_m: f64, h_m: f64, obstacles: &[[f64; 4]], robot: RobotShape, start: Point2) -> CoverageSpace {
    let res = 0.2;
    let g = GridGeometry::new((w_m / res) as usize, (h_m / res) as usize, res, Point2::origin()).expect("geometry");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    for i in 0..g.len() {
        let p = g.center_of(i);
        if obstacles
            .iter()
            .any(|o| p.x >= o[0] && p.x <= o[2] && p.y >= o[1] && p.y <= o[3])
        {
            grid.cells[i] = CellState::Occupied;
        }
    }
    CoverageSpace::new(grid, robot, start).expect("space")
}

fn duration(space: &CoverageSpace, objective: Objective) -> (f64, usize, f64) {
    let limits = SpeedLimits::default();
    let params = PlanParams {
        objective,
        limits,
        ..PlanParams::default()
    };
    let out = plan(space, &params, &mut NoMonitor).expect("plan");
    let profile = profile_path(
        space,
        &out.waypoints,
        None,
        &SpeedParams::new(limits, space.robot.tool_width_m),
    )
    .expect("profile");
    let m = profile.metrics;
    assert_eq!(m.collisions, 0, "{objective:?}: {m:?}");
    assert!(m.coverage_pct >= 99.0, "{objective:?}: {m:?}");
    (profile.dwell.duration_s, m.turns, m.coverage_pct)
}

#[test]
fn time_beats_overlap_on_time_and_keeps_turns_near_a_lane_plan() {
    let fields = [
        // A 0.6 ha field with one rectangular obstacle and a 2 m tool (a sprayer).
        (
            100.0,
            60.0,
            vec![[40.0, 20.0, 55.0, 32.0]],
            RobotShape {
                radius_m: 0.8,
                tool_width_m: 2.0,
            },
        ),
        // A yard with three sheds and a 1 m sweeper.
        (
            50.0,
            36.0,
            vec![[8.0, 8.0, 14.0, 12.0], [30.0, 20.0, 33.0, 29.0], [20.0, 4.0, 26.0, 6.0]],
            RobotShape {
                radius_m: 0.4,
                tool_width_m: 1.0,
            },
        ),
    ];
    for (w, h, obstacles, robot) in fields {
        let space = field(w, h, &obstacles, robot, Point2::new(2.0, 2.0));
        let (t_time, turns_time, _) = duration(&space, Objective::Time);
        let (t_overlap, _, _) = duration(&space, Objective::Overlap);
        assert!(
            t_time <= t_overlap * 1.01,
            "{w} × {h} m: time objective {t_time:.0} s, overlap objective {t_overlap:.0} s"
        );
        let lanes = run_baseline(&space, Baseline::SShape, 1, 0.0).expect("lanes");
        let lane_turns = lanes.metrics.turns;
        assert!(
            turns_time as f64 <= 1.5 * lane_turns as f64,
            "{w} × {h} m: {turns_time} turns against {lane_turns} for a lane plan"
        );
        eprintln!(
            "{w} × {h} m: time {t_time:.0} s ({turns_time} turns), overlap objective {t_overlap:.0} s, lanes {lane_turns} turns"
        );
    }
}
