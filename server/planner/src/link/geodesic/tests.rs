//! Geodesic distances against exact per-pair searches: a corridor, walls, the matrix and `DistancesFrom` on
//! random maps, and the excess on cluttered maps.

use super::super::testutil::{Rng, random_points, random_space};
use super::*;
use crate::map::{CellState, GridGeometry, OccupancyGrid};
use crate::space::RobotShape;
use proptest::prelude::*;

#[test]
fn corridor_distances_are_exact_along_a_line() {
    // An empty 10 m × 1 m strip: points on its centre line; geodesics are the straight distances.
    let g = GridGeometry::new(100, 10, 0.1, Point2::origin()).expect("valid");
    let grid = OccupancyGrid::filled(g, CellState::Free);
    let robot = RobotShape {
        radius_m: 0.2,
        tool_width_m: 0.4,
    };
    let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 0.5)).expect("space");
    let pts: Vec<Point2> = [0.55, 2.05, 4.95, 9.05, 9.08]
        .iter()
        .map(|&x| Point2::new(x, 0.55))
        .collect();
    let m = geodesic_matrix(&s, &pts);
    for i in 0..pts.len() {
        for j in 0..pts.len() {
            assert!(
                (m[i * 5 + j] - (pts[i] - pts[j]).norm()).abs() < 1e-9,
                "{i} {j}: {}",
                m[i * 5 + j]
            );
        }
    }
}

#[test]
fn walls_lengthen_and_separate() {
    // Wall at x = 3 m with a door at the top; a third point boxed in.
    let g = GridGeometry::new(60, 30, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(2.95, 0.0, 3.05, 1.95, CellState::Occupied);
    let robot = RobotShape {
        radius_m: 0.15,
        tool_width_m: 0.3,
    };
    let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space");
    let pts = [Point2::new(2.55, 0.55), Point2::new(3.45, 0.55), Point2::new(-5.0, 0.0)];
    let m = geodesic_matrix(&s, &pts);
    let exact = geodesic_distance(&s, pts[0], pts[1]).expect("connected");
    // Around the wall: up ~1.6 m, over, down again.
    assert!(exact > 3.0, "{exact}");
    assert!(m[1] >= exact - 1e-9 && m[1] <= exact * 1.02, "{} vs {exact}", m[1]);
    assert_eq!(m[1], m[3]);
    assert_eq!(m[2], f64::INFINITY);
    assert_eq!(m[8], 0.0);
    assert!(geodesic_matrix(&s, &[]).is_empty());
    assert_eq!(geodesic_matrix(&s, &pts[..1]), vec![0.0]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn matrix_matches_per_pair_search(
        seed in any::<u64>(), w in 16usize..60, h in 16usize..60, obstacles in 0usize..16,
        radius in 0.08f64..0.22, npts in 2usize..24,
    ) {
        let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
        let mut rng = Rng::new(seed ^ 0x77);
        let pts = random_points(&s, &mut rng, npts);
        let m = geodesic_matrix(&s, &pts);
        let diag = 0.1 * std::f64::consts::SQRT_2;
        for i in 0..npts {
            prop_assert_eq!(m[i * npts + i], 0.0);
            for j in 0..npts {
                let v = m[i * npts + j];
                prop_assert_eq!(v, m[j * npts + i]);
                prop_assert!(v >= (pts[i] - pts[j]).norm() - 1e-9);
                if i < j {
                    match geodesic_distance(&s, pts[i], pts[j]) {
                        // An upper bound (up to a cell diagonal for points sharing a cell), and not a
                        // wild one.
                        Some(exact) => {
                            prop_assert!(v >= exact - diag - 1e-9, "{} < {}", v, exact);
                            prop_assert!(v <= 2.0 * exact + diag, "{} vs {}", v, exact);
                        }
                        None => prop_assert!(v.is_infinite()),
                    }
                }
            }
        }
    }

    /// Distances from one point over the whole grid equal the per-pair search.
    #[test]
    fn distances_from_one_point_match_per_pair_search(
        seed in any::<u64>(), w in 16usize..60, h in 16usize..60, obstacles in 0usize..16,
        radius in 0.08f64..0.22, npts in 2usize..12,
    ) {
        let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
        let mut rng = Rng::new(seed ^ 0x55);
        let pts = random_points(&s, &mut rng, npts);
        let from = DistancesFrom::new(&s, pts[0]);
        for &p in &pts[1..] {
            match (from.to(&s, p), geodesic_distance(&s, pts[0], p)) {
                (Some(d), Some(exact)) => prop_assert!((d - exact).abs() < 1e-9, "{} vs {}", d, exact),
                (d, exact) => prop_assert_eq!(d, exact),
            }
        }
    }
}

/// Relative excess of the matrix over the exact per-pair distance on seeded cluttered maps.
fn excess_stats(size: usize, obstacles: usize, npts: usize, seeds: std::ops::Range<u64>) -> (f64, f64, usize) {
    let mut all = Vec::new();
    for seed in seeds {
        let Some(s) = random_space(seed, size, size, obstacles, 0.15) else {
            continue;
        };
        let mut rng = Rng::new(seed);
        let pts = random_points(&s, &mut rng, npts);
        let m = geodesic_matrix(&s, &pts);
        for i in 0..npts {
            for j in i + 1..npts {
                if let Some(exact) = geodesic_distance(&s, pts[i], pts[j]) {
                    all.push((m[i * npts + j] - exact) / exact.max(0.3));
                }
            }
        }
    }
    all.sort_by(f64::total_cmp);
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    (mean, all[all.len() * 95 / 100], all.len())
}

#[test]
fn close_to_exact_on_cluttered_maps() {
    // 10 m × 10 m, 40 obstacles, 25 points, 4 maps: measured mean excess ≈ 5 %, p95 ≈ 17 %.
    let (mean, p95, pairs) = excess_stats(100, 40, 25, 0..4);
    assert!(pairs > 500, "{pairs}");
    assert!(mean <= 0.08, "mean relative excess {mean}");
    assert!(p95 <= 0.25, "p95 relative excess {p95}");
}

/// The same on bigger maps (slow: per-pair A* for every pair).
#[test]
#[ignore]
fn close_to_exact_on_big_cluttered_maps() {
    for (size, obstacles, npts) in [(150, 60, 50), (300, 200, 60)] {
        let (mean, p95, pairs) = excess_stats(size, obstacles, npts, 0..6);
        println!("{size}² cells, {obstacles} obstacles, {npts} points: {pairs} pairs, mean {mean:.4}, p95 {p95:.4}");
        assert!(mean <= 0.08 && p95 <= 0.25);
    }
}
