//! Region routes: lanes as a zigzag, rings entered next to the arrival, chained ring pieces, large regions in
//! pieces, leg ends, closed loops.

use super::sweep::chained_runs;
use super::*;
use crate::pattern::TaskKind;

/// A straight-line search with `iterations` moves.
fn search(iterations: u64) -> RouteSearch<'static> {
    RouteSearch {
        seed: 1,
        iterations,
        stop: None,
        exact: None,
    }
}

fn lane(y: f64) -> Task {
    Task {
        points: vec![Point2::new(0.0, y), Point2::new(5.0, y)],
        kind: TaskKind::Lane,
    }
}

#[test]
fn lanes_are_driven_as_a_zigzag() {
    let tasks: Vec<Task> = (0..6).map(|k| lane(k as f64 * 0.3)).collect();
    let search = search(10_000);
    let r = route_from(&tasks, 0.0, Point2::new(0.0, 0.0), &search);
    assert_eq!(r.legs.len(), 6);
    let mut seen: Vec<usize> = r.legs.iter().map(|l| l.task).collect();
    seen.sort_unstable();
    assert_eq!(seen, (0..6).collect::<Vec<_>>());
    // 6 lanes of 5 m and 5 steps of 0.3 m.
    assert!((r.cost - (30.0 + 1.5)).abs() < 1e-9, "cost {}", r.cost);
    let back = r.reversed();
    assert_eq!(back.entry, r.exit);
    assert_eq!(back.legs[0].points(&tasks)[0], r.exit);
}

/// A closed square from `lo` to `hi` with `per_side` vertices on every side, starting at the corner `lo`.
fn square(lo: f64, hi: f64, per_side: usize) -> Task {
    let corners = [(lo, lo), (hi, lo), (hi, hi), (lo, hi), (lo, lo)];
    let mut points = Vec::new();
    for c in corners.windows(2) {
        for k in 0..per_side {
            let t = k as f64 / per_side as f64;
            points.push(Point2::new(
                c[0].0 + (c[1].0 - c[0].0) * t,
                c[0].1 + (c[1].1 - c[0].1) * t,
            ));
        }
    }
    points.push(points[0]);
    Task {
        points,
        kind: TaskKind::Ring,
    }
}

#[test]
fn nested_rings_are_entered_next_to_where_the_route_arrives() {
    // Rings 0.3 m apart; each may start at any of its vertices, not only at its corners.
    let tasks = vec![square(0.0, 4.0, 8), square(0.3, 3.7, 8)];
    let search = search(10_000);
    let r = route_from(&tasks, 0.0, Point2::new(2.0, 0.0), &search);
    assert_eq!(r.legs.len(), 2);
    // 16 m + 13.6 m of rings; every step runs 0.3 m straight across from where the route arrives (at
    // the corners only, the steps would be 1.7 m and 0.42 m: 31.7 m in all).
    let mut at = r.entry;
    let mut steps = 0.0;
    for leg in &r.legs {
        let pts = leg.points(&tasks);
        let step = (pts[0] - at).norm();
        assert!(step < 0.3 + 1e-9, "step {step} from {at:?}");
        steps += step;
        at = *pts.last().expect("points");
    }
    assert!((r.cost - (16.0 + 13.6 + steps)).abs() < 1e-9, "cost {}", r.cost);
    assert!(r.cost < 30.2 + 1e-9, "cost {}", r.cost);
}

#[test]
fn chained_pieces_are_driven_round_from_the_piece_nearest_the_entry() {
    // A 4 m square loop cut into 8 open pieces whose ends meet, and a short pass off its far side.
    let square = square(0.0, 4.0, 2).points;
    let mut tasks: Vec<Task> = square
        .windows(2)
        .map(|w| Task {
            points: w.to_vec(),
            kind: TaskKind::Ring,
        })
        .collect();
    tasks.push(Task {
        points: vec![Point2::new(4.0, 2.5), Point2::new(3.5, 2.5)],
        kind: TaskKind::Boundary,
    });
    assert_eq!(chained_runs(&tasks), vec![(0..8).collect::<Vec<_>>()]);
    let entry = Point2::new(2.1, -0.1);
    let r = route_sweep(&tasks, 0.0, entry);
    // Round the loop once from the piece starting at (2, 0), the pass inserted where it costs least.
    let pieces: Vec<usize> = r.legs.iter().map(|l| l.task).filter(|&k| k < 8).collect();
    assert_eq!(pieces, vec![1, 2, 3, 4, 5, 6, 7, 0]);
    assert!(r.legs.iter().all(|l| l.task == 8 || !l.reversed));
    let pass = r.legs.iter().position(|l| l.task == 8).expect("pass driven");
    assert_eq!(r.legs[pass - 1].task, 2, "pass after the piece ending at (4, 2)");
    // 16 m of loop, the pass (0.5 m) with its steps out (0.5 m) and back (0.71 m), 0.14 m from the entry.
    let want = 16.0 + 0.5 + 0.5 + 0.5 * 2f64.sqrt() + 0.1 * 2f64.sqrt();
    assert!((r.cost - want).abs() < 1e-9, "cost {} vs {want}", r.cost);
}

#[test]
fn regions_too_large_for_one_search_are_searched_in_pieces() {
    // Two blocks of 700 lane pieces each, a metre apart (a row split by a post): the sweep crosses the gap
    // on every row; searched piece by piece, each piece sweeps one block, then the other.
    let piece = |x: f64, y: f64| Task {
        points: vec![Point2::new(x, y), Point2::new(x + 1.0, y)],
        kind: TaskKind::Lane,
    };
    let tasks: Vec<Task> = (0..700)
        .flat_map(|k| {
            let y = k as f64 * 0.3;
            [piece(0.0, y), piece(2.0, y)]
        })
        .collect();
    assert!(SearchProblem::new(&tasks).is_none(), "too large for one search");
    let search = search(200_000);
    let entry = Point2::new(0.0, 0.0);
    let swept = route_sweep(&tasks, 0.0, entry);
    let r = route_from(&tasks, 0.0, entry, &search);
    let mut seen: Vec<usize> = r.legs.iter().map(|l| l.task).collect();
    seen.sort_unstable();
    assert_eq!(seen, (0..tasks.len()).collect::<Vec<_>>(), "every piece once");
    assert!((r.cost - legs_cost(&tasks, entry, &r.legs, &euclidean)).abs() < 1e-6);
    assert!(r.cost < 0.95 * swept.cost, "pieces {} vs sweep {}", r.cost, swept.cost);
}

#[test]
fn leg_ends_are_the_first_and_last_driven_points() {
    let tasks = vec![lane(0.0), square(0.0, 1.0, 3)];
    for task in 0..2 {
        for reversed in [false, true] {
            for start_vertex in [0, 4, 11] {
                let leg = Leg {
                    task,
                    reversed,
                    start_vertex,
                };
                let pts = leg.points(&tasks);
                assert_eq!(leg.ends(&tasks), (pts[0], pts[pts.len() - 1]), "{leg:?}");
            }
        }
    }
}

#[test]
fn closed_loops_return_to_their_start() {
    let ring = Task {
        points: vec![
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
            Point2::new(0.0, 0.0),
        ],
        kind: TaskKind::Ring,
    };
    let leg = Leg {
        task: 0,
        reversed: true,
        start_vertex: 2,
    };
    let pts = leg.points(std::slice::from_ref(&ring));
    assert_eq!(pts.first(), pts.last());
    assert_eq!(pts[0], Point2::new(1.0, 1.0));
    assert_eq!(pts.len(), 5);
}
