//! Correction bench (DESIGN §7: cloud → correction p99 < 20 ms; optimiser median < 1 ms): a 40 m × 40 m
//! site at 0.05 m with a live tree of about 50 k obstacle points, a 30 m lane through it, and an obstacle
//! cluster of 20, 200 or 2000 points (a filled disk at 5 cm spacing, like an unfiltered scan at map
//! resolution) dropped on the lane 2.5 m ahead of the robot. Measures `judge` (3 m circle), the IKD-SWOpt
//! stage alone (`optimise`) and the whole `repair`.

use criterion::{Criterion, criterion_group, criterion_main};
use shift_planner::correct::World;
use shift_planner::correct::{CorrectParams, judge, optimise, repair};
use shift_planner::geom::Point2;
use shift_planner::map::ikd_tree::Point3;
use shift_planner::map::{CellState, DistanceField, GridGeometry, IkdParams, IkdTree, OccupancyGrid};
use std::time::Duration;

/// Deterministic xorshift in [0, 1).
fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % 1_000_000) as f64 / 1_000_000.0
    }
}

fn bench(c: &mut Criterion) {
    let (w, h, res) = (40.0, 40.0, 0.05);
    let g = GridGeometry::new((w / res) as usize, (h / res) as usize, res, Point2::origin()).expect("geometry");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(0.0, 0.0, w, 0.1, CellState::Occupied);
    grid.fill_rect(0.0, h - 0.1, w, h, CellState::Occupied);
    grid.fill_rect(0.0, 0.0, 0.1, h, CellState::Occupied);
    grid.fill_rect(w - 0.1, 0.0, w, h, CellState::Occupied);
    let field = DistanceField::compute(g, |i| !grid.is_free(i), false);
    // Background clutter: ~50 k live points in short wall pieces, none within 2 m of the lane (y = 20).
    let mut next = rng(7);
    let mut background = Vec::new();
    while background.len() < 50_000 {
        let (x, y) = (0.5 + next() * 39.0, 0.5 + next() * 39.0);
        if (y - 20.0).abs() < 2.0 {
            continue;
        }
        let ang = next() * std::f64::consts::PI;
        for k in 0..40 {
            let t = f64::from(k) * 0.05;
            let (px, py) = (x + t * ang.cos(), y + t * ang.sin());
            if (py - 20.0).abs() >= 2.0 && px > 0.2 && px < w - 0.2 && py < h - 0.2 {
                background.push(Point3::new(px as f32, py as f32, 0.0));
            }
        }
    }
    let path = vec![Point2::new(5.0, 20.0), Point2::new(35.0, 20.0)];
    let robot = Point2::new(16.0, 20.0);
    let p = CorrectParams::for_robot(0.3);
    for n in [20usize, 200, 2000] {
        // A filled disk of n points at about 5 cm spacing, its near edge 2.5 m ahead of the robot.
        let radius = (n as f64 / (std::f64::consts::PI * 400.0)).sqrt();
        let centre = Point2::new(robot.x + 2.5 + radius, 20.05);
        let mut pts = background.clone();
        let mut next = rng(n as u64);
        let mut placed = 0;
        while placed < n {
            let (a, r) = (next() * std::f64::consts::TAU, radius * next().sqrt());
            pts.push(Point3::new(
                (centre.x + r * a.cos()) as f32,
                (centre.y + r * a.sin()) as f32,
                0.0,
            ));
            placed += 1;
        }
        let mut tree = IkdTree::new(IkdParams::default()).expect("params");
        tree.build(&pts);
        let world = World::new(&grid, &field, Some(&tree)).expect("world");
        let breaches = judge(&path, 0, robot, &world, &p);
        let Some(b) = breaches.first().copied() else {
            println!("cluster {n}: no breach judged");
            continue;
        };
        let r = repair(&path, &b, &world, &p).expect("repair");
        let o = optimise(&path, &b, &world, &p).expect("optimise");
        println!(
            "cluster {n} (radius {radius:.2} m, tree {} points): repair {:?}, {} waypoints, {} iterations, J {:.3} -> {:.3}; optimiser alone {}",
            tree.len(),
            r.kind,
            r.waypoints.len(),
            r.iterations,
            r.cost_before,
            r.cost_after,
            o.as_ref().map_or("found no feasible window".to_string(), |o| format!(
                "{} iterations",
                o.iterations
            )),
        );
        c.bench_function(&format!("correct/judge/{n}"), |bch| {
            bch.iter(|| judge(&path, 0, robot, &world, &p))
        });
        c.bench_function(&format!("correct/optimise/{n}"), |bch| {
            bch.iter(|| optimise(&path, &b, &world, &p))
        });
        c.bench_function(&format!("correct/repair/{n}"), |bch| {
            bch.iter(|| repair(&path, &b, &world, &p))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_millis(500));
    targets = bench
}
criterion_main!(benches);
