//! Property tests of the correction stage: random obstacles near random polylines in a random free box,
//! every repair checked against a brute-force oracle (all obstacle points and non-free cell centres).

use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::geom::{Point2, point_segment_distance};
use crate::map::{CellState, OccupancyGrid};

use super::optimize::{Window, optimise_window};
use super::path::Arclen;
use super::tests::{Site, after_arc, blob, to_path, walled};
use super::*;

/// A random scene: a walled free box with a few static disks, a polyline inside, live clusters on it.
fn scene(seed: u64, waypoints: usize, clusters: usize, window: f64) -> (Site, Vec<Point2>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (w, h) = (rng.random_range(8.0..14.0), rng.random_range(8.0..14.0));
    let mut grid: OccupancyGrid = walled(w, h);
    let path: Vec<Point2> = (0..waypoints)
        .map(|_| Point2::new(rng.random_range(1.2..w - 1.2), rng.random_range(1.2..h - 1.2)))
        .collect();
    let arc = Arclen::new(&path);
    let mut live = Vec::new();
    for k in 0..clusters {
        // The first cluster lies inside the judged circle, so most cases have a breach.
        let s = if k == 0 {
            rng.random_range(0.6..0.9) * window.min(arc.total()).max(1.0)
        } else {
            rng.random_range(0.15..1.0) * arc.total()
        };
        let on = arc.point_at(s);
        let c = on + nalgebra::Vector2::new(rng.random_range(-0.4..0.4), rng.random_range(-0.4..0.4));
        let radius = rng.random_range(0.02..0.6);
        if k % 3 == 2 {
            grid.fill_disk(c, radius, CellState::Occupied);
        } else {
            live.extend(blob(c, radius, rng.random_range(0.04..0.12)));
        }
    }
    (Site::new(grid, live), path)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 40, ..ProptestConfig::default() })]

    #[test]
    fn repairs_are_collision_free_and_keep_the_rest(
        seed in any::<u64>(),
        waypoints in 2usize..5,
        clusters in 1usize..4,
        window in 2.0f64..6.0,
    ) {
        let (site, path) = scene(seed, waypoints, clusters, window);
        let world = site.world();
        let p = CorrectParams { window_radius_m: window, ..CorrectParams::default() };
        let breaches = judge(&path, 0, path[0], &world, &p);
        for b in breaches.iter().take(1) {
            let r = match repair(&path, b, &world, &p) {
                Err(CorrectError::AnchorInCollision { .. }) => {
                    // Only when the robot itself stands in collision.
                    prop_assert!(site.oracle(&path[..1]).0 < p.d_safe() + 1e-9);
                    continue;
                }
                other => other.expect("repair"),
            };
            if std::env::var_os("CORRECT_PROP_LOG").is_some() {
                eprintln!("case {seed}: {:?} {} waypoints, {} iterations", r.kind, r.waypoints.len(), r.iterations);
            }
            let (clear, on_map) = site.oracle(&r.waypoints);
            prop_assert!(on_map, "{:?} left the map", r.kind);
            if let Some(e) = r.escape {
                // The robot already stood inside the band: never closer than it was, the radius within the
                // escape's allowance and from there on.
                prop_assert!(e.floor_m < p.robot_radius_m && clear >= e.floor_m - 1e-9, "{:?} escape {:?} clearance {}", r.kind, e, clear);
                let allowance = 2.0 * (p.robot_radius_m - e.floor_m) + 2.0 * p.spacing_m + 0.01;
                let (rest, _) = site.oracle(&after_arc(&r.waypoints, allowance));
                prop_assert!(r.waypoints.len() == 1 || rest >= p.robot_radius_m, "{:?} escape {:?}: {} after the allowance", r.kind, e, rest);
            } else {
                prop_assert!(clear >= p.robot_radius_m, "{:?} clearance {}", r.kind, clear);
            }
            prop_assert!(r.from <= r.to && r.to <= path.len());
            // Fixed ends: the anchors lie on the kept join pieces of the original path.
            let first = r.waypoints[0];
            prop_assert!(to_path(first, &path) < 1e-9);
            if r.from >= 1 {
                prop_assert!(point_segment_distance(first, path[r.from - 1], path[r.from.min(path.len() - 1)]) < 1e-9);
            }
            let last = r.waypoints[r.waypoints.len() - 1];
            if r.to < path.len() {
                prop_assert!(point_segment_distance(last, path[r.to - 1], path[r.to]) < 1e-9);
            } else if r.kind != RepairKind::Skipped {
                prop_assert!((last - path[path.len() - 1]).norm() < 1e-9);
            }
            if r.kind == RepairKind::Optimised {
                prop_assert!(r.cost_after <= r.cost_before);
            }
            let out = apply(&path, &r);
            prop_assert_eq!(&out[..r.from], &path[..r.from]);
            prop_assert_eq!(&out[out.len() - (path.len() - r.to)..], &path[r.to..]);
        }
    }

    #[test]
    fn optimiser_never_raises_the_cost(seed in any::<u64>(), clusters in 1usize..4, spacing in 0.05f64..0.2) {
        let (site, path) = scene(seed, 2, clusters, 3.0);
        let world = site.world();
        let p = CorrectParams { spacing_m: spacing, ..CorrectParams::default() };
        let arc = Arclen::new(&path);
        let (s0, s1) = (0.1 * arc.total(), 0.9 * arc.total());
        if let Some(win) = Window::new(&arc, s0, s1, p.spacing_m) {
            let opt = optimise_window(&win, &world, &world, &p);
            prop_assert!(opt.cost_after <= opt.cost_before, "{} > {}", opt.cost_after, opt.cost_before);
            prop_assert_eq!(opt.points[..2].to_vec(), win.head.to_vec());
            prop_assert_eq!(opt.points[opt.points.len() - 2..].to_vec(), win.tail.to_vec());
        }
    }
}
