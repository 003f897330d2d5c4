//! Link tests: method names and params, straight and door paths, unreachable ends, the potential term, diagonal
//! pinches, and random links that are valid and agree between the two searches.

use super::testutil::{Rng, random_point, random_space};
use super::*;
use crate::map::{Cell, CellState, GridGeometry, OccupancyGrid};
use proptest::prelude::*;

fn two_rooms() -> CoverageSpace {
    // 6 m × 3 m; a wall at x = 3 m with a 0.8 m door at y ∈ [2.0, 2.8].
    let g = GridGeometry::new(60, 30, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(2.95, 0.0, 3.05, 1.95, CellState::Occupied);
    let robot = RobotShape {
        radius_m: 0.15,
        tool_width_m: 0.3,
    };
    CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space")
}

fn assert_valid(space: &CoverageSpace, path: &[Point2], a: Point2, b: Point2) {
    assert!(path.len() >= 2);
    assert_eq!(path[0], a);
    assert_eq!(path[path.len() - 1], b);
    for w in path.windows(2) {
        assert!(space.segment_ok(w[0], w[1]), "segment {:?} -> {:?} not ok", w[0], w[1]);
    }
}

#[test]
fn method_names_round_trip() {
    for m in [LinkMethod::AStar, LinkMethod::Bidirectional] {
        assert_eq!(m.name().parse::<LinkMethod>().expect("parses"), m);
        assert_eq!(m.to_string(), m.name());
    }
    assert!(matches!(
        "dijkstra".parse::<LinkMethod>(),
        Err(PlannerError::InvalidParam { .. })
    ));
}

#[test]
fn params_validate_and_sanitize() {
    assert!(LinkParams::default().validate().is_ok());
    let bad = LinkParams {
        alpha: -1.0,
        epsilon_m: 0.0,
        preferred_clearance_m: f64::NAN,
        ..LinkParams::default()
    };
    assert!(bad.validate().is_err());
    assert_eq!(bad.sanitized(), LinkParams::default());
    let robot = RobotShape {
        radius_m: 0.2,
        tool_width_m: 0.5,
    };
    assert_eq!(LinkParams::for_robot(&robot).preferred_clearance_m, 0.25);
}

#[test]
fn straight_line_when_visible() {
    let s = two_rooms();
    let (a, b) = (Point2::new(0.7, 1.03), Point2::new(2.2, 1.51));
    assert_eq!(link(&s, a, b, &LinkParams::default()), Some(vec![a, b]));
}

#[test]
fn goes_through_the_door_with_few_vertices() {
    let s = two_rooms();
    let (a, b) = (Point2::new(1.02, 0.51), Point2::new(5.03, 0.49));
    for method in [LinkMethod::AStar, LinkMethod::Bidirectional] {
        let params = LinkParams {
            method,
            ..LinkParams::default()
        };
        let path = link(&s, a, b, &params).expect("reachable through the door");
        assert_valid(&s, &path, a, b);
        assert!(path.len() <= 5, "{method}: {} vertices: {path:?}", path.len());
        // It passes above the wall's end (centre of its top cell row at y = 1.95 m).
        assert!(path.iter().any(|p| p.y > 1.95 && (p.x - 3.0).abs() < 0.6), "{path:?}");
        // Keeps min(radius + preferred, the grid path's clearance), and the radius everywhere.
        let grid = Linker::new(&s, &params).grid_path(a, b).expect("grid path");
        let kept = path_min_clearance(&s, &path);
        assert!(kept >= (0.15f64 + 0.15).min(path_min_clearance(&s, &grid.points)) - 1e-9);
        assert!(kept >= 0.15 - 1e-9);
        assert!(grid.points.len() > 30 && path.len() < grid.points.len());
    }
}

#[test]
fn unreachable_or_invalid_gives_none() {
    // Same rooms, no door.
    let g = GridGeometry::new(60, 30, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(2.95, 0.0, 3.05, 3.0, CellState::Occupied);
    let robot = RobotShape {
        radius_m: 0.15,
        tool_width_m: 0.3,
    };
    let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space");
    let a = Point2::new(1.0, 1.0);
    for method in [LinkMethod::AStar, LinkMethod::Bidirectional] {
        let params = LinkParams {
            method,
            ..LinkParams::default()
        };
        // Across the wall: not on the reachable set at all.
        assert_eq!(link(&s, a, Point2::new(5.0, 1.0), &params), None);
        // In the wall, off the map, NaN.
        assert_eq!(link(&s, a, Point2::new(3.0, 1.0), &params), None);
        assert_eq!(link(&s, a, Point2::new(-3.0, 1.0), &params), None);
        assert_eq!(link(&s, Point2::new(f64::NAN, 1.0), a, &params), None);
    }
}

#[test]
fn potential_keeps_away_from_walls() {
    // A 3 m wide corridor; a plain shortest path around the block hugs its corner, the potential path
    // keeps more room.
    let g = GridGeometry::new(80, 40, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(3.5, 0.0, 4.5, 2.5, CellState::Occupied);
    let robot = RobotShape {
        radius_m: 0.15,
        tool_width_m: 0.3,
    };
    let s = CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space");
    let (a, b) = (Point2::new(1.0, 1.0), Point2::new(7.0, 1.0));
    let plain = LinkParams {
        alpha: 0.0,
        preferred_clearance_m: 0.0,
        ..LinkParams::default()
    };
    let field = LinkParams {
        alpha: 0.5,
        preferred_clearance_m: 0.0,
        ..LinkParams::default()
    };
    let gp = Linker::new(&s, &plain).grid_path(a, b).expect("path");
    let gf = Linker::new(&s, &field).grid_path(a, b).expect("path");
    assert!(path_min_clearance(&s, &gf.points) > path_min_clearance(&s, &gp.points) + 0.1);
    assert!(crate::geom::polyline_length(&gf.points) >= crate::geom::polyline_length(&gp.points) - 1e-9);
}

#[test]
fn diagonal_pinch_is_passable_when_clear() {
    // Two thin diagonal walls on the line x + y = 39 (cells) leave one gap; with a 0.2 m radius the cells
    // beside the gap are not traversable, so the halves meet only at the diagonal step
    // (19, 19) → (20, 20), whose segment still keeps 0.21 m from both wall ends.
    let g = GridGeometry::new(40, 40, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    for k in 0..19 {
        grid.set(Cell::new(21 + k, 18 - k), CellState::Occupied);
        grid.set(Cell::new(18 - k, 21 + k), CellState::Occupied);
    }
    let robot = RobotShape {
        radius_m: 0.2,
        tool_width_m: 0.4,
    };
    let (a, b) = (Point2::new(0.62, 0.71), Point2::new(3.43, 3.38));
    let s = CoverageSpace::new(grid, robot, a).expect("space");
    assert!(
        s.point_ok(a) && s.point_ok(b),
        "both halves reachable through the pinch"
    );
    for side in [Cell::new(20, 19), Cell::new(19, 20)] {
        assert!(!s.reachable[g.index(side)]);
    }
    let mut costs = Vec::new();
    for method in [LinkMethod::AStar, LinkMethod::Bidirectional] {
        let params = LinkParams {
            method,
            ..LinkParams::default()
        };
        let mut linker = Linker::new(&s, &params);
        let grid_path = linker.grid_path(a, b).expect("through the pinch");
        assert!(grid_path.points.contains(&g.center(Cell::new(19, 19))));
        assert!(grid_path.points.contains(&g.center(Cell::new(20, 20))));
        costs.push(grid_path.cost);
        let path = linker.link(a, b).expect("through the pinch");
        assert_valid(&s, &path, a, b);
    }
    assert!((costs[0] - costs[1]).abs() < 1e-9 * costs[0]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_links_are_valid_and_methods_agree(
        seed in any::<u64>(), w in 12usize..48, h in 12usize..48, obstacles in 0usize..14,
        radius in 0.08f64..0.26, alpha in 0.0f64..1.0, pref in 0.0f64..0.4,
    ) {
        let Some(s) = random_space(seed, w, h, obstacles, radius) else { return Ok(()) };
        let mut rng = Rng::new(seed ^ 0xABCD);
        let a = random_point(&s, &mut rng);
        let b = random_point(&s, &mut rng);
        let pa = LinkParams { alpha, preferred_clearance_m: pref, method: LinkMethod::AStar, ..LinkParams::default() };
        let pb = LinkParams { method: LinkMethod::Bidirectional, ..pa };
        let mut la = Linker::new(&s, &pa);
        let mut lb = Linker::new(&s, &pb);
        let ga = la.grid_path(a, b);
        let gb = lb.grid_path(a, b);
        match (&ga, &gb) {
            (Some(ga), Some(gb)) => {
                prop_assert!((ga.cost - gb.cost).abs() <= 1e-9 * ga.cost.max(1.0), "astar {} bidir {}", ga.cost, gb.cost);
                for g in [ga, gb] {
                    prop_assert_eq!(g.points[0], a);
                    prop_assert_eq!(*g.points.last().expect("non-empty"), b);
                    for w in g.points.windows(2) {
                        prop_assert!(s.segment_ok(w[0], w[1]));
                    }
                }
            }
            (None, None) => {}
            _ => prop_assert!(false, "methods disagree on reachability: {:?} vs {:?}", ga.is_some(), gb.is_some()),
        }
        for l in [&mut la, &mut lb] {
            let path = l.link(a, b);
            prop_assert_eq!(path.is_some(), ga.is_some());
            if let (Some(path), Some(grid)) = (path, &ga) {
                prop_assert_eq!(path[0], a);
                prop_assert_eq!(*path.last().expect("non-empty"), b);
                for w in path.windows(2) {
                    prop_assert!(s.segment_ok(w[0], w[1]), "segment {:?} -> {:?}", w[0], w[1]);
                }
                let need = radius + pref;
                prop_assert!(path_min_clearance(&s, &path) >= need.min(path_min_clearance(&s, &grid.points)) - 1e-9);
                prop_assert!(path.len() <= grid.points.len());
            }
        }
        // Reusing the buffers for the reverse link gives the same cost.
        if let Some(ga) = &ga {
            let back = la.grid_path(b, a).expect("symmetric reachability");
            prop_assert!((back.cost - ga.cost).abs() <= 1e-9 * ga.cost.max(1.0));
        }
    }
}
