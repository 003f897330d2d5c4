//! Link planner benchmarks on a generated 200 m × 200 m map at 0.1 m (4 M cells) with random obstacles:
//! one long link (corner to corner, A* and bidirectional A*) and geodesic matrices over 500 and 2000 points.
//! Prints the median of a few timed runs of each before criterion's own statistics.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use shift_planner::geom::Point2;
use shift_planner::link::{LinkMethod, LinkParams, Linker, geodesic_matrix};
use shift_planner::map::{CellState, GridGeometry, OccupancyGrid};
use shift_planner::space::{CoverageSpace, RobotShape};

const SIZE: usize = 2000;
const RES: f64 = 0.1;

/// 200 m × 200 m, 0.1 m cells, ~600 random boxes and disks (0.3 m – 3 m), seeded.
fn cluttered_space() -> CoverageSpace {
    let g = GridGeometry::new(SIZE, SIZE, RES, Point2::origin()).expect("valid geometry");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    for _ in 0..600 {
        let (cx, cy) = (rng.random_range(0.0..200.0), rng.random_range(0.0..200.0));
        let disk = rng.random_bool(0.5);
        let (ex, ey) = (rng.random_range(0.15..1.5), rng.random_range(0.15..1.5));
        let (x0, x1) = (
            ((cx - ex) / RES).floor().max(0.0) as usize,
            (((cx + ex) / RES).ceil() as usize).min(SIZE - 1),
        );
        let (y0, y1) = (
            ((cy - ey) / RES).floor().max(0.0) as usize,
            (((cy + ey) / RES).ceil() as usize).min(SIZE - 1),
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = g.center(shift_planner::map::Cell::new(x, y));
                let inside = if disk {
                    (p.x - cx).hypot(p.y - cy) <= ex
                } else {
                    (p.x - cx).abs() <= ex && (p.y - cy).abs() <= ey
                };
                if inside {
                    grid.cells[y * SIZE + x] = CellState::Occupied;
                }
            }
        }
    }
    let robot = RobotShape {
        radius_m: 0.2,
        tool_width_m: 0.4,
    };
    CoverageSpace::new(grid, robot, Point2::new(100.0, 100.0)).expect("space")
}

/// The reachable cell centre nearest to `p`.
fn nearest_reachable(space: &CoverageSpace, p: Point2) -> Point2 {
    let g = space.geometry();
    (0..g.len())
        .filter(|&i| space.reachable[i])
        .map(|i| g.center_of(i))
        .min_by(|a, b| (a - p).norm().total_cmp(&(b - p).norm()))
        .expect("reachable cells")
}

fn random_points(space: &CoverageSpace, n: usize, seed: u64) -> Vec<Point2> {
    let g = space.geometry();
    let cells: Vec<usize> = (0..g.len()).filter(|&i| space.reachable[i]).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| g.center_of(cells[rng.random_range(0..cells.len())]))
        .collect()
}

fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[runs / 2]
}

fn benches(c: &mut Criterion) {
    let space = cluttered_space();
    let a = nearest_reachable(&space, Point2::new(3.0, 3.0));
    let b = nearest_reachable(&space, Point2::new(197.0, 197.0));
    let p500 = random_points(&space, 500, 1);
    let p2000 = random_points(&space, 2000, 2);
    println!(
        "map {SIZE}×{SIZE} at {RES} m, reachable cells {}",
        space.reachable_count()
    );
    // For scale on a shared machine: the existing footprint/reach computation on the same map.
    let grid = space.grid.clone();
    let (robot, start) = (space.robot, space.start);
    println!(
        "median CoverageSpace::new (reference): {:.1} ms",
        median_ms(3, || {
            black_box(CoverageSpace::new(grid.clone(), robot, start).ok());
        })
    );

    for method in [LinkMethod::AStar, LinkMethod::Bidirectional] {
        let params = LinkParams {
            method,
            ..LinkParams::default()
        };
        let mut linker = Linker::new(&space, &params);
        let grid = linker.grid_path(a, b).expect("corner to corner is connected");
        let path = linker.link(a, b).expect("path");
        let ms = median_ms(5, || {
            black_box(linker.link(a, b));
        });
        println!(
            "median link {method} (reused buffers): {ms:.1} ms — expanded {} cells, {} grid points -> {} vertices",
            grid.expanded,
            grid.points.len(),
            path.len()
        );
        let fresh = median_ms(5, || {
            black_box(shift_planner::link::link(&space, a, b, &params));
        });
        println!("median link {method} (fresh buffers): {fresh:.1} ms");
    }
    // A short link (~10 m) with a fresh Linker: only the pages the search touches are faulted in.
    let near = nearest_reachable(&space, Point2::new(110.0, 104.0));
    let centre = nearest_reachable(&space, Point2::new(100.0, 100.0));
    let params = LinkParams::default();
    println!(
        "median short link (~10 m, fresh buffers): {:.2} ms",
        median_ms(5, || {
            black_box(shift_planner::link::link(&space, centre, near, &params));
        })
    );
    println!(
        "median geodesic_matrix 500 points: {:.1} ms",
        median_ms(5, || {
            black_box(geodesic_matrix(&space, &p500));
        })
    );
    println!(
        "median geodesic_matrix 2000 points: {:.1} ms",
        median_ms(3, || {
            black_box(geodesic_matrix(&space, &p2000));
        })
    );

    let mut group = c.benchmark_group("link");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    let params = LinkParams::default();
    let mut linker = Linker::new(&space, &params);
    group.bench_function("long_link_astar", |bch| bch.iter(|| black_box(linker.link(a, b))));
    let bidir = LinkParams {
        method: LinkMethod::Bidirectional,
        ..params
    };
    let mut linker_b = Linker::new(&space, &bidir);
    group.bench_function("long_link_bidir", |bch| bch.iter(|| black_box(linker_b.link(a, b))));
    group.bench_function("geodesic_matrix_500", |bch| {
        bch.iter(|| black_box(geodesic_matrix(&space, &p500)))
    });
    group.finish();
}

criterion_group!(link_benches, benches);
criterion_main!(link_benches);
