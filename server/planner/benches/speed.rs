//! RFICP speed-profile bench: a 10 k-waypoint path (the input to `speed::profile_path`) on a 60 m × 60 m
//! cluttered site with an attribute of Gaussian blobs; the whole profile (smoothing, sampling, refinement,
//! metrics) and the forward–backward pass alone.

use criterion::{Criterion, criterion_group, criterion_main};
use shift_planner::geom::Point2;
use shift_planner::pipeline::{NoMonitor, PlanParams, Waypoint, plan};
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_planner::speed::time_param::limit_acceleration;
use shift_planner::speed::{AttributeBlob, AttributeMap, SpeedLimits, SpeedParams, profile_path};
use shift_planner::testing::cluttered_site;

/// Densifies `path` (keeping its kinds) until it has about `n` waypoints.
fn densify(path: &[Waypoint], n: usize) -> Vec<Waypoint> {
    let length: f64 = path.windows(2).map(|w| (w[1].position - w[0].position).norm()).sum();
    let step = length / n.saturating_sub(path.len()).max(1) as f64;
    let mut out = vec![path[0]];
    for w in path.windows(2) {
        let d = (w[1].position - w[0].position).norm();
        let k = (d / step).floor() as usize;
        for j in 1..=k {
            let p = w[0].position + (w[1].position - w[0].position) * (j as f64 / (k + 1) as f64);
            out.push(Waypoint { position: p, ..w[1] });
        }
        out.push(w[1]);
    }
    out
}

fn bench(c: &mut Criterion) {
    let grid = cluttered_site(60.0, 60.0, 0.1, 60, 3).expect("site");
    let g = grid.geometry;
    let robot = RobotShape {
        radius_m: 0.3,
        tool_width_m: 0.6,
    };
    let space = CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space");
    let out = plan(&space, &PlanParams::default(), &mut NoMonitor).expect("plan");
    let path = densify(&out.waypoints, 10_000);
    let blobs: Vec<AttributeBlob> = (0..8)
        .map(|k| AttributeBlob {
            centre: Point2::new(7.0 + 6.5 * f64::from(k), 10.0 + 5.5 * f64::from(k % 5)),
            sigma_m: 4.0,
            amplitude: 0.9,
        })
        .collect();
    let attr = AttributeMap::from_blobs(g, &blobs).expect("attribute");
    let params = SpeedParams::new(SpeedLimits::default(), 0.6);
    let probe = profile_path(&space, &path, Some(&attr), &params).expect("profile");
    eprintln!(
        "input {} waypoints, output {} waypoints, dwell_cv {:.3} (const {:.3}), coverage {:.2} %, collisions {}",
        path.len(),
        probe.waypoints.len(),
        probe.dwell.dwell_cv,
        probe.dwell.dwell_cv_const_speed,
        probe.metrics.coverage_pct,
        probe.metrics.collisions
    );
    let mut group = c.benchmark_group("speed");
    group.sample_size(10);
    group.bench_function("profile_10k", |b| {
        b.iter(|| profile_path(&space, &path, Some(&attr), &params).expect("profile"))
    });
    let open_loop = SpeedParams {
        refine_iterations: 0,
        ..params
    };
    group.bench_function("profile_10k_open_loop", |b| {
        b.iter(|| profile_path(&space, &path, Some(&attr), &open_loop).expect("profile"))
    });
    let caps: Vec<f64> = probe.waypoints.iter().map(|w| w.speed_mps).collect();
    let seg: Vec<f64> = probe.waypoints.windows(2).map(|w| w[1].arc_m - w[0].arc_m).collect();
    group.bench_function("forward_backward", |b| b.iter(|| limit_acceleration(&caps, &seg, 0.5)));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
