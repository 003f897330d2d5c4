//! Unit tests of the correction stage, checked against brute-force oracles (every obstacle point and every
//! non-free cell centre), never against the stage's own `verify`.

use crate::geom::{Point2, point_segment_distance};
use crate::map::ikd_tree::Point3;
use crate::map::{CellState, DistanceField, GridGeometry, IkdParams, IkdTree, LivePoints, OccupancyGrid};

use super::*;

/// A site: grid, its distance field, live points.
pub(crate) struct Site {
    pub(crate) grid: OccupancyGrid,
    pub(crate) field: DistanceField,
    pub(crate) tree: IkdTree,
    pub(crate) live: Vec<Point2>,
}

impl Site {
    pub(crate) fn new(grid: OccupancyGrid, live: Vec<Point2>) -> Self {
        let field = DistanceField::compute(grid.geometry, |i| !grid.is_free(i), false);
        let mut tree = IkdTree::new(IkdParams::default()).expect("params");
        let pts: Vec<Point3> = live.iter().map(|q| Point3::new(q.x as f32, q.y as f32, 0.0)).collect();
        tree.build(&pts);
        // The oracle sees exactly what the tree stores.
        let live = pts
            .iter()
            .map(|q| Point2::new(f64::from(q.x), f64::from(q.y)))
            .collect();
        Self {
            grid,
            field,
            tree,
            live,
        }
    }

    pub(crate) fn world(&self) -> World<'_> {
        World::new(
            &self.grid,
            &self.field,
            Some(LivePoints::new(&self.tree, Point2::origin())),
        )
        .expect("consistent")
    }

    /// The world with each live point read as its voxel square (the tree's voxel size), as the live map reads
    /// its downsampled points.
    pub(crate) fn world_as_voxels(&self) -> World<'_> {
        World::new(
            &self.grid,
            &self.field,
            Some(LivePoints::voxels(&self.tree, Point2::origin())),
        )
        .expect("consistent")
    }

    /// Brute-force smallest distance from the polyline (continuous segments) to any obstacle (static cells
    /// credited `STATIC_SLACK_M`, see below), and whether it stays on the map.
    pub(crate) fn oracle(&self, pts: &[Point2]) -> (f64, bool) {
        let g = &self.grid.geometry;
        let statics: Vec<Point2> = (0..g.len())
            .filter(|&i| !self.grid.is_free(i))
            .map(|i| g.center_of(i))
            .collect();
        let (lo, hi) = (
            g.origin,
            g.origin + nalgebra::Vector2::new(g.width as f64, g.height as f64) * g.resolution,
        );
        let on_map = pts
            .iter()
            .all(|q| q.x >= lo.x && q.y >= lo.y && q.x < hi.x && q.y < hi.y);
        let segs: Vec<(Point2, Point2)> = if pts.len() == 1 {
            vec![(pts[0], pts[0])]
        } else {
            pts.windows(2).map(|w| (w[0], w[1])).collect()
        };
        // The correction's contract: live points kept at the radius exactly, the static map (which the plan
        // itself may touch at exactly the radius) with `STATIC_SLACK_M` of slack.
        let mut best = f64::INFINITY;
        for (a, b) in segs {
            for o in &statics {
                best = best.min(point_segment_distance(*o, a, b) + super::world::STATIC_SLACK_M);
            }
            for o in &self.live {
                best = best.min(point_segment_distance(*o, a, b));
            }
        }
        (best, on_map)
    }
}

/// A free `w × h` m map at 0.05 m with a wall of two cells around it.
/// The polyline `pts` from arc length `s` on (its last point alone when `s` is past its end).
pub(crate) fn after_arc(pts: &[Point2], s: f64) -> Vec<Point2> {
    let mut run = 0.0;
    for (k, w) in pts.windows(2).enumerate() {
        let len = (w[1] - w[0]).norm();
        if run + len >= s {
            let f = if len > 0.0 {
                ((s - run) / len).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut out = vec![w[0] + (w[1] - w[0]) * f];
            out.extend_from_slice(&pts[k + 1..]);
            return out;
        }
        run += len;
    }
    pts.last().map(|q| vec![*q]).unwrap_or_default()
}

pub(crate) fn walled(w: f64, h: f64) -> OccupancyGrid {
    let g = GridGeometry::new(
        (w / 0.05).round() as usize,
        (h / 0.05).round() as usize,
        0.05,
        Point2::origin(),
    )
    .expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(0.0, 0.0, w, 0.1, CellState::Occupied);
    grid.fill_rect(0.0, h - 0.1, w, h, CellState::Occupied);
    grid.fill_rect(0.0, 0.0, 0.1, h, CellState::Occupied);
    grid.fill_rect(w - 0.1, 0.0, w, h, CellState::Occupied);
    grid
}

/// Points filling a disk (spacing about `step`).
pub(crate) fn blob(c: Point2, radius: f64, step: f64) -> Vec<Point2> {
    let n = (radius / step).ceil() as i32;
    let mut out = Vec::new();
    for i in -n..=n {
        for j in -n..=n {
            let q = c + nalgebra::Vector2::new(f64::from(i) * step, f64::from(j) * step);
            if (q - c).norm() <= radius {
                out.push(q);
            }
        }
    }
    out
}

/// Distance from `q` to the polyline.
pub(crate) fn to_path(q: Point2, path: &[Point2]) -> f64 {
    path.windows(2)
        .map(|w| point_segment_distance(q, w[0], w[1]))
        .fold(f64::INFINITY, f64::min)
}

/// Angle (degrees) between two directions.
fn angle_deg(a: crate::geom::Vector2, b: crate::geom::Vector2) -> f64 {
    crate::geom::heading_change(a, b).to_degrees()
}

#[test]
fn lane_with_a_cluster_is_optimised_clear_and_joins_smoothly() {
    let site = Site::new(walled(20.0, 8.0), blob(Point2::new(6.0, 4.05), 0.2, 0.05));
    let world = site.world();
    let p = CorrectParams::default();
    let path = vec![Point2::new(1.0, 4.0), Point2::new(19.0, 4.0)];
    let robot = Point2::new(4.0, 4.0);
    let breaches = judge(&path, 0, robot, &world, &p);
    assert_eq!(breaches.len(), 1, "{breaches:?}");
    let b = breaches[0];
    let (sa, sb) = (1.0 + 18.0 * b.start.t, 1.0 + 18.0 * b.end.t);
    assert!(sa < 6.0 && sb > 6.0, "breach {sa}..{sb} m should hold the cluster");
    assert!(b.min_clearance_m < p.robot_radius_m);
    let r = repair(&path, &b, &world, &p).expect("repair");
    assert_eq!(r.kind, RepairKind::Optimised);
    assert!(r.cost_after <= r.cost_before);
    let (clear, on_map) = site.oracle(&r.waypoints);
    assert!(on_map && clear >= p.robot_radius_m, "clearance {clear}");
    // Anchors on the original path, joins tangent to it.
    let (first, last) = (r.waypoints[0], r.waypoints[r.waypoints.len() - 1]);
    assert!(to_path(first, &path) < 1e-9 && to_path(last, &path) < 1e-9);
    let dir = path[1] - path[0];
    let n = r.waypoints.len();
    assert!(angle_deg(r.waypoints[1] - r.waypoints[0], dir) < 3.0);
    assert!(angle_deg(r.waypoints[n - 1] - r.waypoints[n - 2], dir) < 3.0);
    // Heading changes gently from the join onwards (no kink at the first free point).
    assert!(angle_deg(r.waypoints[2] - r.waypoints[1], dir) < 15.0);
    let out = apply(&path, &r);
    assert_eq!(out[..r.from], path[..r.from]);
    assert_eq!(out[out.len() - (path.len() - r.to)..], path[r.to..]);
    let (clear, _) = site.oracle(&out[r.from.saturating_sub(1)..(r.from + n + 1).min(out.len())]);
    assert!(clear >= p.robot_radius_m);
    // After the repair nothing ahead is in breach.
    assert!(
        judge(&out, 0, robot, &world, &p)
            .iter()
            .all(|b| b.min_clearance_m >= p.robot_radius_m)
    );
}

#[test]
fn clean_path_has_no_breach() {
    let site = Site::new(walled(20.0, 8.0), blob(Point2::new(6.0, 6.5), 0.2, 0.05));
    let world = site.world();
    let path = vec![Point2::new(1.0, 4.0), Point2::new(19.0, 4.0)];
    assert!(judge(&path, 0, Point2::new(4.0, 4.0), &world, &CorrectParams::default()).is_empty());
    // A cluster beyond the circle is not judged yet.
    let site = Site::new(walled(20.0, 8.0), blob(Point2::new(12.0, 4.0), 0.2, 0.05));
    let world = site.world();
    assert!(judge(&path, 0, Point2::new(4.0, 4.0), &world, &CorrectParams::default()).is_empty());
}

#[test]
fn a_wall_across_the_corridor_is_skipped_without_collision() {
    let mut grid = walled(20.0, 6.0);
    grid.fill_rect(0.0, 0.0, 20.0, 2.0, CellState::Occupied);
    grid.fill_rect(0.0, 4.0, 20.0, 6.0, CellState::Occupied);
    let wall: Vec<Point2> = (0..=44).map(|i| Point2::new(10.0, 1.9 + f64::from(i) * 0.05)).collect();
    let site = Site::new(grid, wall);
    let world = site.world();
    let p = CorrectParams::default();
    let path = vec![Point2::new(1.0, 3.0), Point2::new(19.0, 3.0)];
    let breaches = judge(&path, 0, Point2::new(7.5, 3.0), &world, &p);
    assert_eq!(breaches.len(), 1, "{breaches:?}");
    let r = repair(&path, &breaches[0], &world, &p).expect("repair");
    assert_eq!(r.kind, RepairKind::Skipped);
    assert_eq!(r.to, path.len(), "nothing beyond the wall is reachable");
    let (clear, on_map) = site.oracle(&r.waypoints);
    assert!(on_map && clear >= p.robot_radius_m);
    assert!(to_path(r.waypoints[0], &path) < 1e-9);
    assert!(r.waypoints[0].x >= 7.5 && r.waypoints[0].x < 10.0 - p.robot_radius_m);
    assert!(!r.skipped.is_empty());
}

#[test]
fn a_gap_in_the_wall_further_on_is_rejoined_by_a_skip() {
    // Corridor closed by a live wall; the plan comes back through a parallel corridor reached by a door
    // behind the robot.
    let mut grid = walled(20.0, 10.0);
    grid.fill_rect(0.0, 4.0, 20.0, 6.0, CellState::Occupied);
    grid.fill_rect(2.0, 4.0, 3.0, 6.0, CellState::Free);
    let wall: Vec<Point2> = (0..=80).map(|i| Point2::new(10.0, 0.0 + f64::from(i) * 0.05)).collect();
    let site = Site::new(grid, wall);
    let world = site.world();
    let p = CorrectParams::default();
    let path = vec![
        Point2::new(4.0, 2.0),
        Point2::new(18.0, 2.0),
        Point2::new(18.0, 2.5),
        Point2::new(18.5, 2.5),
        Point2::new(18.5, 8.0),
        Point2::new(4.0, 8.0),
    ];
    let b = judge(&path, 0, Point2::new(8.0, 2.0), &world, &p);
    assert_eq!(b.len(), 1);
    let r = repair(&path, &b[0], &world, &p).expect("repair");
    assert_eq!(r.kind, RepairKind::Skipped);
    assert!(r.to < path.len(), "rejoins the plan in the upper corridor");
    let (clear, on_map) = site.oracle(&r.waypoints);
    assert!(on_map && clear >= p.robot_radius_m);
    let last = r.waypoints[r.waypoints.len() - 1];
    assert!(last.y > 6.0 && to_path(last, &path) < 1e-9, "{last:?}");
}

#[test]
fn a_u_shaped_obstacle_needs_a_detour() {
    let mut grid = walled(20.0, 10.0);
    // A cup open towards the robot: bottom at x = 8, arms back to x = 6.
    grid.fill_rect(8.0, 3.5, 8.2, 6.5, CellState::Occupied);
    grid.fill_rect(6.0, 3.5, 8.2, 3.7, CellState::Occupied);
    grid.fill_rect(6.0, 6.3, 8.2, 6.5, CellState::Occupied);
    let site = Site::new(grid, Vec::new());
    let world = site.world();
    let p = CorrectParams::default();
    let path = vec![Point2::new(1.0, 5.0), Point2::new(19.0, 5.0)];
    let b = judge(&path, 0, Point2::new(5.3, 5.0), &world, &p);
    assert_eq!(b.len(), 1, "{b:?}");
    let r = repair(&path, &b[0], &world, &p).expect("repair");
    assert_eq!(r.kind, RepairKind::Detour);
    let (clear, on_map) = site.oracle(&r.waypoints);
    assert!(on_map && clear >= p.robot_radius_m);
    let (first, last) = (r.waypoints[0], r.waypoints[r.waypoints.len() - 1]);
    assert!(to_path(first, &path) < 1e-9 && to_path(last, &path) < 1e-9);
    assert!(first.x >= 5.3 - 1e-9, "never before the robot");
}

#[test]
fn bad_input_is_rejected() {
    let site = Site::new(walled(10.0, 10.0), Vec::new());
    let world = site.world();
    let p = CorrectParams::default();
    let b = Breach {
        start: PathPos::new(0, 0.2),
        end: PathPos::new(0, 0.3),
        cost: 1.0,
        min_clearance_m: 0.0,
        earliest: PathPos::new(0, 0.0),
    };
    assert!(matches!(
        repair(&[Point2::new(1.0, 1.0)], &b, &world, &p),
        Err(CorrectError::BadPath(_))
    ));
    let nan = [Point2::new(1.0, 1.0), Point2::new(f64::NAN, 1.0)];
    assert!(matches!(repair(&nan, &b, &world, &p), Err(CorrectError::BadPath(_))));
    let path = [Point2::new(1.0, 1.0), Point2::new(5.0, 1.0)];
    let off = Breach {
        start: PathPos::new(3, 0.0),
        ..b
    };
    assert!(matches!(
        repair(&path, &off, &world, &p),
        Err(CorrectError::BadBreach(_))
    ));
    let bad = CorrectParams { w_obs: 0.0, ..p };
    assert!(matches!(
        repair(&path, &b, &world, &bad),
        Err(CorrectError::InvalidParam { .. })
    ));
    assert!(judge(&path, 0, Point2::new(f64::NAN, 0.0), &world, &p).is_empty());
    assert!(judge(&path, 5, Point2::new(1.0, 1.0), &world, &p).is_empty());
    // Starting inside the wall: the anchor itself collides.
    let into = [Point2::new(0.05, 5.0), Point2::new(5.0, 5.0)];
    let b = judge(&into, 0, into[0], &world, &p);
    assert!(!b.is_empty());
    assert!(matches!(
        repair(&into, &b[0], &world, &p),
        Err(CorrectError::AnchorInCollision { .. })
    ));
}

#[test]
fn apply_splices() {
    let path: Vec<Point2> = (0..6).map(|i| Point2::new(f64::from(i), 0.0)).collect();
    let r = Repair {
        from: 2,
        to: 4,
        waypoints: vec![Point2::new(1.5, 0.0), Point2::new(2.5, 1.0), Point2::new(3.5, 0.0)],
        kind: RepairKind::Optimised,
        iterations: 0,
        cost_before: 0.0,
        cost_after: 0.0,
        skipped: Vec::new(),
        escape: None,
    };
    let out = apply(&path, &r);
    assert_eq!(out.len(), 2 + 3 + 2);
    assert_eq!(out[..2], path[..2]);
    assert_eq!(out[5..], path[4..]);
    let stop = Repair { to: 99, ..r };
    assert_eq!(apply(&path, &stop).len(), 5);
}

/// Convergence trace of the optimiser on a bench-like case (run with `--ignored --nocapture`).
#[test]
#[ignore = "diagnostic"]
fn trace_convergence() {
    use super::cost::WindowCost;
    use super::lbfgs::minimize;
    use super::optimize::{Window, weights};
    use super::path::Arclen;
    for (n, radius) in [(20usize, 0.13), (200, 0.4), (2000, 1.26)] {
        let mut s = 99u64 + n as u64;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 1_000_000) as f64 / 1_000_000.0
        };
        let c = Point2::new(10.0, 5.05);
        let live: Vec<Point2> = (0..n)
            .map(|_| {
                let (a, r) = (next() * std::f64::consts::TAU, radius * next().sqrt());
                c + nalgebra::Vector2::new(r * a.cos(), r * a.sin())
            })
            .collect();
        let site = Site::new(walled(20.0, 10.0), live);
        let world = site.world();
        let p = CorrectParams::default();
        let path = vec![Point2::new(1.0, 5.0), Point2::new(19.0, 5.0)];
        let b = judge(&path, 0, Point2::new(10.0 - radius - 2.0, 5.0), &world, &p);
        let o = optimise(&path, &b[0], &world, &p).expect("ok");
        println!(
            "n {n}: optimise -> {:?}",
            o.as_ref().map(|o| (o.iterations, o.waypoints.len()))
        );
        let arc = Arclen::new(&path);
        let half = radius + p.d_safe() + 1.05;
        let win = Window::new(&arc, 9.0 - half, 9.0 + half, p.spacing_m).expect("window");
        let mut cost = WindowCost::new(win.head, win.tail, weights(&p, win.h), &world, win.free.len());
        let x0: Vec<f64> = win
            .free
            .iter()
            .enumerate()
            .flat_map(|(i, q)| {
                let t = i as f64 / win.free.len() as f64;
                [
                    q.x,
                    q.y + (radius + 0.45) * (std::f64::consts::PI * t).sin().powi(2).sqrt(),
                ]
            })
            .collect();
        let f0 = cost.value(&x0);
        let mut line = format!("  f0 {f0:.4}:");
        for k in 1..=40 {
            let m = minimize(&mut cost, &x0, k, 6, 1e-3, 0.0);
            line += &format!(" {:.4}", m.f);
        }
        println!("{line}");
    }
}

/// Window-by-window trace of a bench-like case with background clutter (run with `--ignored --nocapture`).
#[test]
#[ignore = "diagnostic"]
fn trace_windows_bench_like() {
    let mut s = 7u64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % 1_000_000) as f64 / 1_000_000.0
    };
    let mut background = Vec::new();
    while background.len() < 8000 {
        let (x, y) = (0.5 + next() * 19.0, 0.5 + next() * 19.0);
        if (y - 10.0).abs() < 2.0 {
            continue;
        }
        let ang = next() * std::f64::consts::PI;
        for k in 0..40 {
            let t = f64::from(k) * 0.05;
            background.push(Point2::new(x + t * ang.cos(), y + t * ang.sin()));
        }
    }
    for n in [20usize, 200, 2000] {
        let radius = (n as f64 / (std::f64::consts::PI * 400.0)).sqrt();
        let robot = Point2::new(6.0, 10.0);
        let centre = Point2::new(robot.x + 2.5 + radius, 10.05);
        let mut live = background.clone();
        for _ in 0..n {
            let (a, r) = (next() * std::f64::consts::TAU, radius * next().sqrt());
            live.push(centre + nalgebra::Vector2::new(r * a.cos(), r * a.sin()));
        }
        let site = Site::new(walled(20.0, 20.0), live);
        let world = site.world();
        let p = CorrectParams::default();
        let path = vec![Point2::new(1.0, 10.0), Point2::new(19.0, 10.0)];
        let b = judge(&path, 0, robot, &world, &p);
        println!("n {n}: breach {:?}", b.first().map(|b| (b.start, b.end)));
        for w in super::repair::trace_windows(&path, &b[0], &world, &p) {
            println!(
                "  window {:.2}..{:.2}: {} iterations, feasible {}, J {:.2} -> {:.2}",
                w.0, w.1, w.2, w.3, w.4, w.5
            );
        }
    }
}

/// `worth_publishing`'s decision boundary: a collision (breach clearance under the radius) is always
/// published; a margin-only breach only for an optimised patch whose clearance (capped at d_safe) beats the
/// breach's by more than 1 cm.
#[test]
fn worth_publishing_boundary() {
    // One live point at (5, 5) in a 10 m box: a straight patch at height c above it has clearance c.
    let site = Site::new(walled(10.0, 10.0), vec![Point2::new(5.0, 5.0)]);
    let world = site.world();
    let p = CorrectParams::default();
    let (r, d_safe) = (p.robot_radius_m, p.d_safe());
    let patch = |kind: RepairKind, c: f64| Repair {
        from: 1,
        to: 2,
        waypoints: vec![Point2::new(4.0, 5.0 + c), Point2::new(6.0, 5.0 + c)],
        kind,
        iterations: 0,
        cost_before: 0.0,
        cost_after: 0.0,
        skipped: Vec::new(),
        escape: None,
    };
    // The patches' clearances are what the rule measures.
    for c in [0.29, 0.305, 0.309, 0.311, 0.32, 0.5] {
        let got = min_clearance(&patch(RepairKind::Optimised, c).waypoints, &world, d_safe);
        assert!((got - c.min(d_safe)).abs() < 1e-9, "clearance {got} for a patch at {c}");
    }
    let breach = |m: f64| Breach {
        start: PathPos::new(0, 0.4),
        end: PathPos::new(0, 0.6),
        cost: 0.1,
        min_clearance_m: m,
        earliest: PathPos::new(0, 0.0),
    };
    let worth = |m: f64, kind: RepairKind, c: f64| worth_publishing(&breach(m), &patch(kind, c), &world, &p);
    use RepairKind::{Detour, Optimised, Skipped};
    // A collision: every kind, even a patch that clears no better than the breach.
    for kind in [Optimised, Detour, Skipped] {
        assert!(worth(0.0, kind, r), "{kind:?} for a collision");
        assert!(worth(r - 1e-4, kind, r), "{kind:?} just under the radius");
    }
    assert!(worth(0.2, Optimised, 0.2));
    // At the radius and above it is a margin-only breach: a detour or skip never is, however clear.
    for m in [r, r + 0.01, d_safe - 0.001] {
        assert!(!worth(m, Detour, 0.5), "detour at {m}");
        assert!(!worth(m, Skipped, 0.5), "skip at {m}");
    }
    // An optimised patch must beat the breach by more than 1 cm.
    assert!(worth(r, Optimised, r + 0.011));
    assert!(worth(r, Optimised, 0.32));
    assert!(!worth(r, Optimised, r + 0.009));
    assert!(!worth(r, Optimised, 0.305));
    assert!(!worth(r, Optimised, r));
    assert!(worth(0.33, Optimised, 0.5));
    // Its clearance counts only up to d_safe, so within 1 cm of d_safe nothing is worth it.
    assert!(!worth(d_safe - 0.009, Optimised, 0.5));
    assert!(!worth(d_safe, Optimised, 0.5));
    assert!(worth(d_safe - 0.011, Optimised, 0.5));
}
