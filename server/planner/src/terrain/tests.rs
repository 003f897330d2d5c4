//! The terrain pipeline end to end on synthetic clouds.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::geom::Point2;
use crate::map::CellState;
use crate::pipeline::{NoMonitor, PlanParams, plan};
use crate::space::{CoverageSpace, RobotShape};

/// `per_cell` points in every `g`-metre cell of `[0, w] × [0, h]` on `z`, with ±1 cm noise, none where `hole`
/// holds, and a `spikes` share of them lifted by 2–4 m (birds, dust, a stray return).
fn cloud(
    w: f64,
    h: f64,
    g: f64,
    z: impl Fn(f64, f64) -> f64,
    hole: impl Fn(f64, f64) -> bool,
    spikes: f64,
) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let mut pts = Vec::new();
    for j in 0..(h / g).round() as usize {
        for i in 0..(w / g).round() as usize {
            for _ in 0..3 {
                let x = (i as f64 + rng.random_range(0.01..0.99)) * g;
                let y = (j as f64 + rng.random_range(0.01..0.99)) * g;
                if hole(x, y) {
                    continue;
                }
                let mut zz = z(x, y) + rng.random_range(-0.01..0.01);
                if rng.random::<f64>() < spikes {
                    zz += rng.random_range(2.0..4.0);
                }
                pts.push([x, y, zz]);
            }
        }
    }
    pts
}

fn hills(x: f64, y: f64) -> f64 {
    3.0 * (x / 8.0).sin() * (y / 7.0).cos() + 0.05 * x
}

#[test]
fn a_drone_plans_over_a_noisy_cloud_with_a_hole() {
    // 40 m × 30 m of hills, a 3 m pond without returns, 1 % of the points stray.
    let pond = |x: f64, y: f64| (x - 25.0).hypot(y - 12.0) < 3.0;
    let pts = cloud(40.0, 30.0, 0.5, hills, pond, 0.01);
    let terrain = TerrainParams::default();
    let drone = DroneParams {
        tool_width_m: 4.0,
        altitude_offset_m: 3.0,
        ..DroneParams::default()
    };
    let out = plan_drone(&pts, &terrain, &drone).expect("plan");
    let s = &out.surface;
    let err: Vec<f64> = (0..s.geometry.len())
        .map(|i| {
            let c = s.geometry.center_of(i);
            (s.heights[i] - hills(c.x, c.y)).abs()
        })
        .collect();
    let worst = err.iter().copied().fold(0.0, f64::max);
    let rms = (err.iter().map(|e| e * e).sum::<f64>() / err.len() as f64).sqrt();
    let m = &out.metrics;
    eprintln!(
        "noisy cloud: {} points, {} filled, {} smoothed, surface error RMS {rms:.3} worst {worst:.3} m; {:?} lanes {}, \
         coverage {:.4}, spacing p5 {:.3} p95 {:.3}, altitude p95 {:.4} max {:.4}, max slope {:.1}°",
        pts.len(),
        out.report.filled_cells,
        out.report.smooth.smoothed_cells,
        out.plan.axis,
        m.lanes,
        m.surface_coverage,
        m.lane_spacing_m.p5,
        m.lane_spacing_m.p95,
        m.altitude_error_m.p95,
        m.altitude_error_m.max,
        m.max_path_slope_rad.to_degrees()
    );
    assert!(out.report.filled_cells > 50);
    // The median of 3 points already drops most strays; smoothing takes the cells where 2 of 3 strayed. What
    // is left is under half a cell (0.25 m), the smallest spike removed by default.
    assert!(rms < 0.02 && worst < 0.25, "surface error RMS {rms} worst {worst}");
    assert!(m.surface_coverage >= 0.99);
    assert!(m.lane_spacing_m.p5 >= 0.85 * 4.0 && m.lane_spacing_m.p95 <= 4.0 + 1e-3);
    assert!(m.altitude_error_m.p95 < 0.05);
    assert!(out.plan.path.iter().all(|p| p[2].is_finite()));
    // Deterministic: the same cloud gives the same plan, bit for bit.
    let again = plan_drone(&pts, &terrain, &drone).expect("plan");
    assert_eq!(again.plan, out.plan);
}

#[test]
fn a_ground_robot_plans_around_a_mound_too_steep_to_climb() {
    // A 30 m square field, flat but for a mound of 3 m (flanks up to ~32°) in the middle.
    let mound = |x: f64, y: f64| 3.0 * (-((x - 15.0).powi(2) + (y - 15.0).powi(2)) / 8.0).exp();
    let pts = cloud(30.0, 30.0, 0.25, mound, |_, _| false, 0.0);
    let limits = GroundLimits::default();
    let out = ground_occupancy(&pts, &TerrainParams::default(), &limits, Some(1.0)).expect("occupancy");
    let g = &out.occupancy;
    let occupied: Vec<usize> = (0..g.cells.len())
        .filter(|&i| g.cells[i] == CellState::Occupied)
        .collect();
    // The flank steeper than 15° is a ring 0.37–4.5 m from the top (|∇z| = 0.75·r·e^(−r²/8) > tan 15°).
    for &i in &occupied {
        let c = g.geometry.center_of(i);
        let r = (c.x - 15.0).hypot(c.y - 15.0);
        assert!(r > 0.2 && r < 4.9, "occupied cell at r = {r:.2} m");
    }
    let at = |r: f64| {
        g.geometry
            .index(g.geometry.locate(Point2::new(15.0 + r, 15.0)).expect("on the map"))
    };
    assert_eq!(g.cells[at(2.5)], CellState::Occupied);
    assert_eq!(g.cells[at(10.0)], CellState::Free);
    // The ring's area over 0.5 m cells: π(4.5² − 0.37²)/0.25 ≈ 253 cells.
    assert!(occupied.len() > 200, "{} occupied", occupied.len());
    let robot = RobotShape {
        radius_m: 0.3,
        tool_width_m: 0.6,
    };
    let space = CoverageSpace::new(out.occupancy.clone(), robot, Point2::new(1.0, 1.0)).expect("space");
    let params = PlanParams {
        threads: 1,
        ..PlanParams::default()
    };
    let plan = plan(&space, &params, &mut NoMonitor).expect("plan");
    eprintln!(
        "mound: {} occupied cells, coverage {:.2} %, collisions {}",
        occupied.len(),
        plan.metrics.coverage_pct,
        plan.metrics.collisions
    );
    assert_eq!(plan.metrics.collisions, 0);
    assert!(plan.metrics.coverage_pct > 95.0);
    for w in &plan.waypoints {
        let r = (w.position.x - 15.0).hypot(w.position.y - 15.0);
        assert!(
            !(0.5..4.5).contains(&r),
            "a waypoint on the steep flank at r = {r:.2} m"
        );
    }
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let terrain = TerrainParams::default();
    assert!(matches!(
        plan_drone(&[], &terrain, &DroneParams::default()),
        Err(crate::PlannerError::EmptyCloud { .. })
    ));
    // Two points: a grid of 1 × 1 cells is too small for a surface.
    assert!(matches!(
        ground_occupancy(
            &[[0.0, 0.0, 0.0], [0.1, 0.1, 0.0]],
            &terrain,
            &GroundLimits::default(),
            None
        ),
        Err(crate::PlannerError::TerrainTooSmall { .. })
    ));
    let nan = [[f64::NAN, 0.0, 0.0]; 5];
    assert!(matches!(
        plan_drone(&nan, &terrain, &DroneParams::default()),
        Err(crate::PlannerError::EmptyCloud { total: 5, skipped: 5 })
    ));
}
