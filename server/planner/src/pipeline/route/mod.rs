//! Inside one region: the order of its tasks from a given entry, and the region's entry/exit options for
//! the visiting-order problem (each region may be entered at any corner of its lane set; a route may also be
//! driven backwards).

mod search;
mod sweep;
#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::collections::HashMap;

use search::SearchProblem;
use sweep::route_sweep;

use crate::geom::{Point2, Vector2, direction, pair_key};
use crate::pattern::Task;
use crate::space::CoverageSpace;

/// One task as driven: which task, from which vertex, in which direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Leg {
    /// Index into the region's tasks.
    pub task: usize,
    /// Drive the vertices backwards.
    pub reversed: bool,
    /// For closed tasks: the vertex where the loop starts and ends.
    pub start_vertex: usize,
}

impl Leg {
    /// Where this leg starts and ends (the same point for a closed loop), without copying its vertices.
    pub fn ends(&self, tasks: &[Task]) -> (Point2, Point2) {
        let t = &tasks[self.task];
        let pts = &t.points;
        if t.is_closed() {
            let p = pts[self.start_vertex % (pts.len() - 1)];
            return (p, p);
        }
        let (first, last) = (pts[0], pts[pts.len() - 1]);
        if self.reversed { (last, first) } else { (first, last) }
    }

    /// The vertices of this leg in driving order.
    pub fn points(&self, tasks: &[Task]) -> Vec<Point2> {
        let t = &tasks[self.task];
        let mut pts = if t.is_closed() {
            let body = &t.points[..t.points.len() - 1];
            let n = body.len();
            let mut v: Vec<Point2> = (0..=n).map(|k| body[(self.start_vertex + k) % n]).collect();
            if self.reversed {
                v.reverse();
            }
            return v;
        } else {
            t.points.clone()
        };
        if self.reversed {
            pts.reverse();
        }
        pts
    }
}

/// A region's route from one entry: legs in order, entry and exit points, length (tasks plus straight
/// connections; real connections are linked later).
#[derive(Debug, Clone, PartialEq)]
pub struct RegionRoute {
    /// Legs in driving order.
    pub legs: Vec<Leg>,
    /// First point.
    pub entry: Point2,
    /// Last point.
    pub exit: Point2,
    /// Estimated length, metres.
    pub cost: f64,
}

impl RegionRoute {
    /// The same route driven backwards.
    /// A reversed closed loop that started at vertex s still starts (and ends) at s.
    pub fn reversed(&self) -> Self {
        let legs = self
            .legs
            .iter()
            .rev()
            .map(|l| Leg {
                reversed: !l.reversed,
                ..*l
            })
            .collect();
        Self {
            legs,
            entry: self.exit,
            exit: self.entry,
            cost: self.cost,
        }
    }
}

/// Options of one task: (entry, exit, leg).
fn task_options(tasks: &[Task], k: usize) -> Vec<(Point2, Point2, Leg)> {
    let t = &tasks[k];
    if t.is_closed() {
        let n = t.points.len() - 1;
        let mut starts: Vec<usize> = (0..4).map(|q| q * n / 4).collect();
        starts.dedup();
        starts
            .into_iter()
            .flat_map(|s| {
                [false, true].map(|rev| {
                    (
                        t.points[s],
                        t.points[s],
                        Leg {
                            task: k,
                            reversed: rev,
                            start_vertex: s,
                        },
                    )
                })
            })
            .collect()
    } else {
        let (a, b) = (t.points[0], t.points[t.points.len() - 1]);
        vec![
            (
                a,
                b,
                Leg {
                    task: k,
                    reversed: false,
                    start_vertex: 0,
                },
            ),
            (
                b,
                a,
                Leg {
                    task: k,
                    reversed: true,
                    start_vertex: 0,
                },
            ),
        ]
    }
}

/// How a region's tasks are ordered: the local search's seed and bounds, and how the routes found are
/// costed. The search plans on straight-line connections.
#[derive(Clone, Copy)]
pub struct RouteSearch<'a> {
    /// Seed of the local search.
    pub seed: u64,
    /// Work bound of the local search (moves).
    pub iterations: u64,
    /// Polled by the local search; true stops it with the best tour so far.
    pub stop: Option<&'a dyn Fn() -> bool>,
    /// The driven length of a connection that its straight length underestimates (`None` when it does not;
    /// infinity when no link exists); used to cost the routes found (see [`region_options`]). `None`:
    /// straight lengths only.
    pub exact: Option<&'a dyn Fn(Point2, Point2) -> Option<f64>>,
}

/// Straight-line connection cost (no obstacles).
fn euclidean(a: Point2, b: Point2) -> f64 {
    (b - a).norm()
}

/// True when the straight segment `a`–`b` runs through an obstacle (a wall between two rooms of one region,
/// an obstacle between rings) rather than merely grazing the clearance the way lane ends along a ragged wall
/// do: some point of it, sampled every half radius, is closer than half the radius to a non-free cell (no
/// wall can hide between two samples). Such a step is linked around the obstacle, often metres longer.
pub fn through_obstacle(space: &CoverageSpace, a: Point2, b: Point2) -> bool {
    let d = (b - a).norm();
    let r = space.robot.radius_m;
    let step = (0.5 * r).max(space.geometry().resolution);
    let n = (d / step).ceil() as usize;
    (0..=n).any(|k| !space.has_clearance(a + (b - a) * (k as f64 / n.max(1) as f64), 0.5 * r))
}

/// Orders `tasks` as an open tour starting at `entry`: the better of the local-search tour and the plain
/// sweep order (lanes by offset, nearest end first, other tasks inserted where they cost least) — local search
/// from a nearest-neighbour start can miss the zigzag that is optimal for a monotone region.
pub fn route_from(tasks: &[Task], angle: f64, entry: Point2, search: &RouteSearch<'_>) -> RegionRoute {
    let mut problem = SearchProblem::new(tasks);
    route_with(tasks, angle, entry, search, problem.as_mut())
}

/// [`route_from`] with the search problem of the region's tasks built once for all its entries (`None`:
/// too many points for one search, so the sweep order is searched piece by piece).
fn route_with(
    tasks: &[Task],
    angle: f64,
    entry: Point2,
    search: &RouteSearch<'_>,
    problem: Option<&mut SearchProblem>,
) -> RegionRoute {
    let swept = reanchor_loops(tasks, route_sweep(tasks, angle, entry));
    let searched = match problem {
        Some(problem) => reanchor_loops(tasks, problem.route(tasks, entry, search)),
        // Rings inserted where they cost least and re-anchored are rarely improved by a search limited to
        // four starts per ring; lanes in sweep order are (measured: a 200 m site with speckle, walls/fit lanes
        // 40.6 → 17.8 % overlap; its spiral unchanged and slower).
        None if tasks.iter().any(|t| t.kind == crate::pattern::TaskKind::Lane) => {
            route_in_pieces(tasks, &swept, search)
        }
        None => return swept,
    };
    if swept.cost + 1e-9 < searched.cost {
        swept
    } else {
        searched
    }
}

/// Regions too large for one search are searched in pieces of at most this many entry/exit points.
pub const PIECE_POINTS: usize = 1500;

/// The sweep order `swept` cut into consecutive pieces of at most [`PIECE_POINTS`] points, each searched from
/// where the previous one ends: the sweep keeps the region's large-scale order (lane bands, or where every
/// ring was cheapest to insert), the search repairs what it does badly inside a band (lanes split by
/// speckle and posts, passes).
fn route_in_pieces(tasks: &[Task], swept: &RegionRoute, search: &RouteSearch<'_>) -> RegionRoute {
    let mut legs: Vec<Leg> = Vec::with_capacity(swept.legs.len());
    let mut at = swept.entry;
    let mut piece: Vec<Leg> = Vec::new();
    let mut points = 0;
    let mut flush = |piece: &mut Vec<Leg>, at: &mut Point2| {
        let sub: Vec<Task> = piece.iter().map(|l| tasks[l.task].clone()).collect();
        let local = RouteSearch {
            iterations: (sub.len() as u64).pow(2).clamp(1_000, 200_000),
            ..*search
        };
        match SearchProblem::new(&sub) {
            Some(mut problem) => {
                let r = reanchor_loops(&sub, problem.route(&sub, *at, &local));
                legs.extend(r.legs.iter().map(|l| Leg {
                    task: piece[l.task].task,
                    ..*l
                }));
            }
            // A piece is never larger than one search can take; should it be, it keeps the sweep's order.
            None => legs.extend(piece.iter().copied()),
        }
        *at = legs.last().map_or(*at, |l| l.ends(tasks).1);
        piece.clear();
    };
    for leg in &swept.legs {
        let n = 2 * task_options(tasks, leg.task).len();
        if points + n > PIECE_POINTS && !piece.is_empty() {
            flush(&mut piece, &mut at);
            points = 0;
        }
        piece.push(*leg);
        points += n;
    }
    flush(&mut piece, &mut at);
    let cost = legs_cost(tasks, swept.entry, &legs, &euclidean);
    RegionRoute {
        legs,
        entry: swept.entry,
        exit: at,
        cost,
    }
}

/// Re-anchors every closed loop of `route` at its vertex nearest to where the route arrives (the search
/// offers each loop only a few start vertices; a loop ends where it starts, so the nearest vertex also
/// shortens the way on to the next leg). Keeps whichever of the two routes is shorter.
fn reanchor_loops(tasks: &[Task], route: RegionRoute) -> RegionRoute {
    let mut legs = route.legs.clone();
    let mut at = route.entry;
    let mut changed = false;
    for leg in &mut legs {
        let t = &tasks[leg.task];
        if t.is_closed() {
            let body = &t.points[..t.points.len() - 1];
            let nearest = (0..body.len())
                .min_by(|&a, &b| (body[a] - at).norm().total_cmp(&(body[b] - at).norm()))
                .unwrap_or(leg.start_vertex);
            changed |= nearest != leg.start_vertex;
            leg.start_vertex = nearest;
        }
        at = leg.ends(tasks).1;
    }
    if !changed {
        return route;
    }
    let cost = legs_cost(tasks, route.entry, &legs, &euclidean);
    if cost + 1e-9 < route.cost {
        RegionRoute {
            legs,
            exit: at,
            cost,
            ..route
        }
    } else {
        route
    }
}

/// Regions whose tasks offer more entry/exit points than this are routed by the sweep order alone (the
/// search's dense distance matrix has the square of this many entries).
pub const MAX_SEARCH_POINTS: usize = 4000;

/// Cost of driving `legs` from `entry`: task lengths plus connections.
fn legs_cost(tasks: &[Task], entry: Point2, legs: &[Leg], connect: &dyn Fn(Point2, Point2) -> f64) -> f64 {
    let mut at = entry;
    let mut cost = 0.0;
    for l in legs {
        let (first, last) = l.ends(tasks);
        cost += connect(at, first) + tasks[l.task].length();
        at = last;
    }
    cost
}

/// Candidate entries: the task endpoints extreme along the four diagonals of the frame at `angle` (the lane
/// set's corners).
pub fn corner_entries(tasks: &[Task], angle: f64) -> Vec<Point2> {
    let d = direction(angle);
    let n = Vector2::new(-d.y, d.x);
    let ends: Vec<Point2> = tasks
        .iter()
        .flat_map(|t| [t.points[0], t.points[t.points.len() - 1]])
        .collect();
    let mut out: Vec<Point2> = Vec::new();
    for (su, sv) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        let key = |p: &Point2| su * p.coords.dot(&d) + sv * p.coords.dot(&n);
        if let Some(best) = ends.iter().min_by(|a, b| key(a).total_cmp(&key(b)))
            && !out.iter().any(|q| (q - best).norm() < 1e-9)
        {
            out.push(*best);
        }
    }
    out
}

/// All routes of a region worth offering to the visiting-order problem: one per corner entry, and each
/// driven backwards. The search plans on straight-line connections; with [`RouteSearch::exact`], each
/// route's cost is then recomputed with the driven length of every connection it uses that cannot be
/// taken straight, so that the visiting order (and the choice among strategies) sees what the robot will
/// drive — a step through a wall costs the way round, not the wall's thickness.
pub fn region_options(tasks: &[Task], angle: f64, search: &RouteSearch<'_>) -> Vec<RegionRoute> {
    let mut problem = SearchProblem::new(tasks);
    let mut routes: Vec<RegionRoute> = corner_entries(tasks, angle)
        .into_iter()
        .map(|e| route_with(tasks, angle, e, search, problem.as_mut()))
        .collect();
    if let Some(exact) = search.exact {
        // Routes from different corners share most of their steps: each is looked at once.
        let known: RefCell<HashMap<[u64; 4], f64>> = RefCell::default();
        let driven = |a: Point2, b: Point2| {
            let key = pair_key(a, b);
            if let Some(&d) = known.borrow().get(&key) {
                return d;
            }
            let d = exact(a, b).unwrap_or_else(|| euclidean(a, b));
            known.borrow_mut().insert(key, d);
            d
        };
        for r in &mut routes {
            r.cost = legs_cost(tasks, r.entry, &r.legs, &driven);
        }
    }
    let mut out: Vec<RegionRoute> = Vec::with_capacity(2 * routes.len());
    for r in routes {
        let back = r.reversed();
        out.push(r);
        out.push(back);
    }
    out
}
