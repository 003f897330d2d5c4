//! Terrain processing of a 1 M-point cloud (issue 23's bench), printing ONE JSON line.
//!
//! `cargo run --release -p shift-planner --example terrain_bench [-- POINTS [GRID_M]]` (defaults 1 000 000
//! points, 0.5 m).
//!
//! The cloud (seeded): 200 m × 250 m of rolling ground (two sine waves of 4 m and 1.5 m), a 3 m ridge, a 0.3 m
//! kerb along x = 120 m, every point with 2 cm of noise, and 1 % outliers 0.5–3 m above the ground (vegetation,
//! birds, multipath). Stages, wall-clock:
//! 1. `grid_ms`: the cloud gridded into a height field;
//! 2. `surface_ms`: curvature outliers smoothed and gaps filled (seed 000 §IV.A);
//! 3. `drone_ms`: lanes, 3-D waypoints and speeds (§IV.B);
//! 4. `metrics_ms`: the surface mesh and the drone metrics;
//! 5. `ground_ms`: traversability and the occupancy grid for a ground robot (from the cloud again, so it
//!    includes stages 1–2).
//!
//! Memory: `peak_rss_mb` is the process's high-water mark (Linux `VmHWM`), `cloud_mb` the cloud's own bytes.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shift_planner::speed::SpeedLimits;
use shift_planner::terrain::{
    DroneParams, ElevationGrid, GroundLimits, TerrainMesh, TerrainParams, TerrainSurface, VerticalLimits,
    drone_metrics, ground_occupancy, plan_lanes, profile_drone,
};

fn ground(x: f64, y: f64) -> f64 {
    let rolling = 4.0 * (x / 37.0).sin() * (y / 53.0).cos() + 1.5 * (x / 11.0 + y / 17.0).sin();
    let ridge = 3.0 * (-((x - 60.0 - 0.3 * y) / 6.0).powi(2)).exp();
    let kerb = if x > 120.0 { 0.3 } else { 0.0 };
    rolling + ridge + kerb
}

fn cloud(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let (x, y) = (rng.random_range(0.0..200.0), rng.random_range(0.0..250.0));
            let mut z = ground(x, y) + rng.random_range(-0.02..0.02);
            if rng.random_bool(0.01) {
                z += rng.random_range(0.5..3.0);
            }
            [x, y, z]
        })
        .collect()
}

fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1_000_000);
    let grid_m: f64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(0.5);
    let points = cloud(n, 7);
    let mut params = TerrainParams::default();
    params.grid.cell_m = grid_m;

    let t = Instant::now();
    let grid = ElevationGrid::from_points(&points, &params.grid).expect("grid");
    let grid_ms = ms(t);
    let t = Instant::now();
    let (surface, report) = TerrainSurface::extract(&grid, &params.smooth).expect("surface");
    let surface_ms = ms(t);
    let t = Instant::now();
    let drone = DroneParams {
        tool_width_m: 5.0,
        altitude_offset_m: 3.0,
        ..DroneParams::default()
    };
    let plan = plan_lanes(&surface, &drone).expect("lanes");
    let profile = profile_drone(
        &plan,
        None,
        &SpeedLimits::new(0.5, 8.0, 2.0),
        &VerticalLimits::default(),
    )
    .expect("speeds");
    let drone_ms = ms(t);
    let t = Instant::now();
    let mesh = TerrainMesh::new(&surface).expect("mesh");
    let m = drone_metrics(&surface, &mesh, &plan);
    let metrics_ms = ms(t);
    let t = Instant::now();
    let ground_out = ground_occupancy(&points, &params, &GroundLimits::default(), None).expect("ground");
    let ground_ms = ms(t);
    let blocked = (0..ground_out.occupancy.geometry.len())
        .filter(|&i| !ground_out.occupancy.is_free(i))
        .count();
    println!(
        "{{\"points\": {n}, \"grid_m\": {grid_m}, \"cells\": {}, \"grid_ms\": {grid_ms:.1}, \"surface_ms\": {surface_ms:.1}, \
         \"drone_ms\": {drone_ms:.1}, \"metrics_ms\": {metrics_ms:.1}, \"ground_ms\": {ground_ms:.1}, \
         \"outliers_smoothed\": {}, \"filled_cells\": {}, \"waypoints\": {}, \"lanes\": {}, \"surface_coverage_pct\": {:.2}, \
         \"altitude_p95_m\": {:.3}, \"spacing_p5_m\": {:.3}, \"spacing_p95_m\": {:.3}, \"flight_s\": {:.0}, \
         \"ground_blocked_pct\": {:.2}, \"cloud_mb\": {:.1}, \"peak_rss_mb\": {:.1}}}",
        surface.geometry.len(),
        report.smooth.smoothed_cells,
        report.filled_cells,
        plan.path.len(),
        m.lanes,
        100.0 * m.surface_coverage,
        m.altitude_error_m.p95,
        m.lane_spacing_m.p5,
        m.lane_spacing_m.p95,
        profile.duration_s(),
        100.0 * blocked as f64 / ground_out.occupancy.geometry.len() as f64,
        (n * std::mem::size_of::<[f64; 3]>()) as f64 / 1_048_576.0,
        peak_rss_mb(),
    );
}
