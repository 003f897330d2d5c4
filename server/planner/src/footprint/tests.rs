//! The footprint checks against a brute-force oracle, and the lattice through a doorway.

use proptest::prelude::*;

use super::*;
use crate::geom::Point2;
use crate::map::{CellState, DistanceField, GridGeometry, OccupancyGrid};
use crate::space::{CoverageSpace, RobotShape};
use crate::testing::two_rooms;

/// The oracle, written apart from the checker: the separating-axis test of the polygon at the pose (vertices
/// turned here) against every blocked cell's square grown by `margin`, cells off the map blocked.
/// `None` when some square is within a micrometre of touching and none clearly overlaps (too close to call
/// in single precision).
fn oracle(grid: &OccupancyGrid, fp: &Footprint, x: f64, y: f64, yaw: f64, margin: f64) -> Option<bool> {
    let g = &grid.geometry;
    let (s, c) = (yaw.sin(), yaw.cos());
    let poly: Vec<(f64, f64)> = fp
        .vertices()
        .iter()
        .map(|v| (x + v.x * c - v.y * s, y + v.x * s + v.y * c))
        .collect();
    let mut axes = vec![(1.0, 0.0), (0.0, 1.0)];
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        axes.push((b.1 - a.1, a.0 - b.0));
    }
    let half = g.resolution / 2.0 + margin;
    let mut close = false;
    // Every cell near the polygon's box.
    let cell = |v: f64, o: f64| ((v - o) / g.resolution).floor() as i64;
    let (x0, x1) = poly
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |m, p| (m.0.min(p.0), m.1.max(p.0)));
    let (y0, y1) = poly
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |m, p| (m.0.min(p.1), m.1.max(p.1)));
    for iy in cell(y0, g.origin.y) - 2..=cell(y1, g.origin.y) + 2 {
        for ix in cell(x0, g.origin.x) - 2..=cell(x1, g.origin.x) + 2 {
            let on = ix >= 0 && iy >= 0 && ix < g.width as i64 && iy < g.height as i64;
            if on && grid.cells[(iy * g.width as i64 + ix) as usize] == CellState::Free {
                continue;
            }
            let (cx, cy) = (
                g.origin.x + (ix as f64 + 0.5) * g.resolution,
                g.origin.y + (iy as f64 + 0.5) * g.resolution,
            );
            let square = [
                (cx - half, cy - half),
                (cx + half, cy - half),
                (cx + half, cy + half),
                (cx - half, cy + half),
            ];
            // The largest gap between the projections over every axis (normalised): > 0 means apart.
            let gap = axes
                .iter()
                .map(|&(ax, ay)| {
                    let n = (ax * ax + ay * ay).sqrt();
                    let proj = |p: &(f64, f64)| (p.0 * ax + p.1 * ay) / n;
                    let (a0, a1) = poly
                        .iter()
                        .map(proj)
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |m, v| (m.0.min(v), m.1.max(v)));
                    let (b0, b1) = square
                        .iter()
                        .map(proj)
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |m, v| (m.0.min(v), m.1.max(v)));
                    (b0 - a1).max(a0 - b1)
                })
                .fold(f64::NEG_INFINITY, f64::max);
            if gap.abs() < 1e-6 {
                close = true;
            } else if gap < 0.0 {
                return Some(false);
            }
        }
    }
    (!close).then_some(true)
}

/// A random site: free with blocked cells at `density`, a wall along one side.
fn random_grid(seed: u64, w: usize, h: usize, density: f64) -> OccupancyGrid {
    let g = GridGeometry::new(w, h, 0.05, Point2::new(-0.3, 0.2)).expect("valid");
    let mut s = seed | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % 1_000_000) as f64 / 1_000_000.0
    };
    let cells = (0..g.len())
        .map(|i| {
            if g.cell(i).x == 3 || next() < density {
                if next() < 0.3 {
                    CellState::Unknown
                } else {
                    CellState::Occupied
                }
            } else {
                CellState::Free
            }
        })
        .collect();
    OccupancyGrid::new(g, cells).expect("grid")
}

/// A convex footprint with its vertices on an ellipse round an offset centre.
fn random_footprint(n: usize, a: f64, b: f64, angles: &[f64], off: (f64, f64)) -> Option<Footprint> {
    let mut t: Vec<f64> = angles.iter().take(n).copied().collect();
    t.sort_by(f64::total_cmp);
    let v: Vec<[f64; 2]> = t.iter().map(|t| [off.0 + a * t.cos(), off.1 + b * t.sin()]).collect();
    Footprint::new(&v).ok()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    /// `pose_free` (fast paths and parry2d) gives the oracle's answer, with and without a margin.
    #[test]
    fn pose_free_agrees_with_the_separating_axis_oracle(
        seed in 1u64..10_000,
        density in 0.0f64..0.08,
        n in 3usize..8,
        a in 0.08f64..0.7, b in 0.08f64..0.7,
        angles in proptest::collection::vec(0.0f64..std::f64::consts::TAU, 8),
        off in (-0.05f64..0.05, -0.05f64..0.05),
        x in -0.5f64..2.4, y in 0.0f64..2.0, yaw in -7.0f64..7.0,
        margin_eighths in 0u32..2,
    ) {
        let grid = random_grid(seed, 40, 36, density);
        let Some(fp) = random_footprint(n, a, b, &angles, off) else { return Ok(()) };
        let df = DistanceField::compute(grid.geometry, |i| !grid.is_free(i), true);
        let margin = f64::from(margin_eighths) * 0.05 / 8.0;
        let check = FootprintCheck::new(&grid, &df, &fp).expect("check").with_margin(margin);
        if let Some(want) = oracle(&grid, &fp, x, y, yaw, margin) {
            prop_assert_eq!(check.pose_free(x, y, yaw), want, "{:?} at ({}, {}, {})", fp, x, y, yaw);
        }
    }
}

#[test]
fn the_oracle_sees_both_answers_often() {
    let (mut free, mut blocked, mut band) = (0, 0, 0);
    let fp = Footprint::rectangle(0.6, 0.3).expect("valid");
    for seed in 1..40u64 {
        let grid = random_grid(seed, 40, 36, 0.004);
        let df = DistanceField::compute(grid.geometry, |i| !grid.is_free(i), true);
        let check = FootprintCheck::new(&grid, &df, &fp).expect("check");
        for k in 0..50 {
            let (x, y, yaw) = (-0.2 + 0.038 * k as f64, 0.3 + 0.035 * seed as f64, 0.37 * k as f64);
            let p = Point2::new(x, y);
            let c = df.at_point(p);
            if c > fp.inscribed_radius_m() && c < fp.circumscribed_radius_m() + 0.05 {
                band += 1;
            }
            match oracle(&grid, &fp, x, y, yaw, 0.0) {
                Some(true) => free += 1,
                Some(false) => blocked += 1,
                None => {}
            }
            if let Some(want) = oracle(&grid, &fp, x, y, yaw, 0.0) {
                assert_eq!(check.pose_free(x, y, yaw), want, "seed {seed} ({x}, {y}, {yaw})");
            }
        }
    }
    assert!(
        free > 200 && blocked > 200 && band > 200,
        "{free} free, {blocked} blocked, {band} in the band"
    );
}

/// A corridor 1.0 m wide: a 1.2 × 0.8 m rectangle drives along it but cannot turn across it.
#[test]
fn a_rectangle_drives_a_corridor_lengthwise_only() {
    let g = GridGeometry::new(100, 60, 0.05, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Occupied);
    grid.fill_rect(0.5, 1.0, 4.5, 2.0, CellState::Free);
    let df = DistanceField::compute(g, |i| !grid.is_free(i), true);
    let fp = Footprint::rectangle(1.2, 0.8).expect("valid");
    let check = FootprintCheck::new(&grid, &df, &fp).expect("check");
    assert!(check.pose_free(2.5, 1.5, 0.0));
    assert!(check.pose_free(2.5, 1.5, std::f64::consts::PI));
    assert!(!check.pose_free(2.5, 1.5, std::f64::consts::FRAC_PI_2));
    assert!(!check.pose_free(2.5, 1.5, 0.5), "a 29° slant touches a side wall");
    assert!(!check.rotation_free(2.5, 1.5, 0.0, 1.0));
    assert!(check.rotation_free(2.5, 1.5, 0.0, 0.05));
    assert!(check.segment_free(Point2::new(1.2, 1.5), Point2::new(3.8, 1.5)));
    assert!(
        !check.segment_free(Point2::new(1.2, 1.5), Point2::new(4.2, 1.5)),
        "the nose hits the end wall"
    );
    let path = [Point2::new(1.2, 1.5), Point2::new(3.8, 1.5)];
    assert_eq!(check.count_collisions(&path), 0);
    let turn = [Point2::new(1.2, 1.5), Point2::new(2.5, 1.5), Point2::new(2.5, 1.6)];
    assert!(
        check.count_collisions(&turn) > 0,
        "turning across the corridor collides"
    );
}

/// The 0.8 × 1.2 m rectangle passes a 1.0 m doorway only heading through it, at any angle of the walls; its
/// circumscribed disc (r ≈ 0.72 m) cannot.
#[test]
fn the_lattice_passes_a_doorway_heading_through_it() {
    let fp = Footprint::rectangle(1.2, 0.8).expect("valid");
    for deg in [0.0_f64, 17.0, 33.0, 45.0, 71.0] {
        let rooms = two_rooms((4.0, 4.0), 0.2, 1.0, deg.to_radians(), 0.05).expect("scene");
        let grid = &rooms.grid;
        let df = DistanceField::compute(grid.geometry, |i| !grid.is_free(i), true);
        let m = FootprintCheck::planning_margin_m(0.05);
        let check = FootprintCheck::new(grid, &df, &fp).expect("check").with_margin(m);
        let dir = crate::geom::direction(rooms.through_rad);
        let goal = rooms.door + dir * 2.0;
        assert!(rooms.in_far_room(goal));
        let path = connect(&check, rooms.start, Some(0.0), goal, None, &LatticeParams::default())
            .unwrap_or_else(|| panic!("{deg}°: no path through the doorway"));
        let exact = FootprintCheck::new(grid, &df, &fp).expect("check");
        assert_eq!(exact.count_collisions(&path), 0, "{deg}°: {path:?}");
        // Every pose in the wall's band heads through the doorway (either way along its axis).
        let mut in_door = 0;
        poses::visit_poses(&path, None, None, 0.0125, 0.02, &mut |p, h| {
            if rooms.in_wall_band(p) {
                in_door += 1;
                let off = poses::wrap_angle(2.0 * (h - rooms.through_rad)).abs() / 2.0;
                assert!(
                    off < 30f64.to_radians(),
                    "{deg}°: heading {:.1}° in the doorway",
                    h.to_degrees()
                );
            }
            std::ops::ControlFlow::Continue(())
        });
        assert!(in_door > 0, "{deg}°: the path passes the doorway");
        let disc = RobotShape {
            radius_m: fp.circumscribed_radius_m(),
            tool_width_m: 0.8,
        };
        let space = CoverageSpace::new(grid.clone(), disc, rooms.start).expect("space");
        let g = space.geometry();
        assert!(
            (0..g.len()).all(|i| !space.reachable[i] || !rooms.in_far_room(g.center_of(i))),
            "{deg}°: the circumscribed disc reaches the far room"
        );
    }
}
