//! Inside one region: the order of its tasks from a given entry, and the region's entry/exit options for
//! the visiting-order problem (each region may be entered at any corner of its lane set; a route may also be
//! driven backwards).

use std::cell::RefCell;
use std::collections::HashMap;

use crate::geom::{Point2, Vector2, direction, pair_key};
use crate::order::{DistanceMatrix, OrderMethod, SolveBudget, TourOption, TourProblem};
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

/// The sweep order: lanes sorted by their offset across the sweep direction (then along it), each driven from
/// its end nearest to the current position; every other task is inserted where it adds the least.
fn route_sweep(tasks: &[Task], angle: f64, entry: Point2) -> RegionRoute {
    let connect = euclidean;
    let d = direction(angle);
    let n = Vector2::new(-d.y, d.x);
    let mut lanes: Vec<usize> = (0..tasks.len())
        .filter(|&k| tasks[k].kind == crate::pattern::TaskKind::Lane)
        .collect();
    let key = |k: usize| {
        let p = tasks[k].points[0];
        ((p.coords.dot(&n) * 1e4).round() as i64, p.coords.dot(&d))
    };
    lanes.sort_by(|&a, &b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });
    // Start from whichever end of the lane stack is nearer the entry.
    let first_near = |ls: &[usize]| {
        ls.first().map_or(f64::INFINITY, |&k| {
            let t = &tasks[k];
            connect(entry, t.points[0]).min(connect(entry, t.points[t.points.len() - 1]))
        })
    };
    let mut rev_lanes = lanes.clone();
    rev_lanes.reverse();
    if first_near(&rev_lanes) < first_near(&lanes) {
        lanes = rev_lanes;
    }
    let mut legs: Vec<Leg> = Vec::with_capacity(tasks.len());
    let mut at = entry;
    for k in lanes {
        let t = &tasks[k];
        let (a, b) = (t.points[0], t.points[t.points.len() - 1]);
        let reversed = connect(at, b) < connect(at, a);
        legs.push(Leg {
            task: k,
            reversed,
            start_vertex: 0,
        });
        at = if reversed { a } else { b };
    }
    // Chained pieces (a spliced ring loop) in their order, the nearest run first, each from its piece
    // nearest to where the route is.
    let mut in_backbone: Vec<bool> = tasks.iter().map(|t| t.kind == crate::pattern::TaskKind::Lane).collect();
    let mut runs = chained_runs(tasks);
    while !runs.is_empty() {
        let Some((r, (_, first, backwards))) = runs
            .iter()
            .map(|run| run_from(tasks, run, at))
            .enumerate()
            .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
        else {
            break;
        };
        let run_legs = run_legs(&runs[r], first, backwards);
        for l in &run_legs {
            in_backbone[l.task] = true;
        }
        at = run_legs.last().map_or(at, |l| l.ends(tasks).1);
        legs.extend(run_legs);
        runs.swap_remove(r);
    }
    // Cheapest insertion of every other task: the cost change of putting leg L between p (the previous
    // leg's end, or the entry) and q (the next leg's start, if any) is |p L.start| + |L.end q| − |p q|.
    let mut ends: Vec<(Point2, Point2)> = legs.iter().map(|l| l.ends(tasks)).collect();
    for k in (0..tasks.len()).filter(|&k| !in_backbone[k]) {
        // Per position: where the route is (p) and the connection to the next leg it replaces (|p q|).
        let at = |pos: usize| if pos == 0 { entry } else { ends[pos - 1].1 };
        let gaps: Vec<Option<(Point2, f64)>> = (0..=legs.len())
            .map(|pos| ends.get(pos).map(|&(q, _)| (q, connect(at(pos), q))))
            .collect();
        let mut best: Option<(f64, usize, Leg)> = None;
        let options = task_options(tasks, k);
        for (j, &(a, b, leg)) in options.iter().enumerate() {
            // A loop driven either way enters and leaves at the same points: the first of equals wins anyway.
            if options[..j].iter().any(|o| o.0 == a && o.1 == b) {
                continue;
            }
            for (pos, gap) in gaps.iter().enumerate() {
                let p = at(pos);
                let delta = match *gap {
                    Some((q, pq)) => connect(p, a) + connect(b, q) - pq,
                    None => connect(p, a),
                };
                if best.is_none_or(|(bd, _, _)| delta < bd) {
                    best = Some((delta, pos, leg));
                }
            }
        }
        if let Some((_, pos, leg)) = best {
            legs.insert(pos, leg);
            ends.insert(pos, leg.ends(tasks));
        }
    }
    let cost = legs_cost(tasks, entry, &legs, &connect);
    let exit = legs.last().map_or(entry, |l| l.ends(tasks).1);
    RegionRoute {
        legs,
        entry,
        exit,
        cost,
    }
}

/// Runs of at least two consecutive open tasks whose ends meet (the pieces of a spliced ring loop, in
/// driving order).
fn chained_runs(tasks: &[Task]) -> Vec<Vec<usize>> {
    let mut runs: Vec<Vec<usize>> = Vec::new();
    let mut run: Vec<usize> = Vec::new();
    for (k, t) in tasks.iter().enumerate() {
        let open = !t.is_closed() && t.points.len() >= 2;
        let follows = run
            .last()
            .is_some_and(|&j| open && tasks[j].points.last() == t.points.first());
        if !follows {
            if run.len() >= 2 {
                runs.push(std::mem::take(&mut run));
            }
            run.clear();
        }
        if open {
            run.push(k);
        }
    }
    if run.len() >= 2 {
        runs.push(run);
    }
    runs
}

/// The cheapest way to drive a chained run from `at`: forwards or backwards and, when its last piece ends
/// where its first begins, from whichever piece is nearest. Returns the connection cost, the first piece
/// (index into `run`) and whether the run is driven backwards.
fn run_from(tasks: &[Task], run: &[usize], at: Point2) -> (f64, usize, bool) {
    let n = run.len();
    let cyclic = tasks[run[n - 1]].points.last() == tasks[run[0]].points.first();
    let starts = if cyclic { n } else { 1 };
    let mut best = (f64::INFINITY, 0, false);
    for s in 0..starts {
        // Backwards from `s` starts at the end of the piece before it (the last piece of an open run).
        let last = (s + n - 1) % n;
        let options = [
            (tasks[run[s]].points[0], s, false),
            (tasks[run[last]].points[tasks[run[last]].points.len() - 1], last, true),
        ];
        for (p, first, backwards) in options {
            let c = euclidean(at, p);
            if c < best.0 {
                best = (c, first, backwards);
            }
        }
    }
    best
}

/// The legs of `run` driven from its piece `first`, forwards or backwards.
fn run_legs(run: &[usize], first: usize, backwards: bool) -> Vec<Leg> {
    let n = run.len();
    (0..n)
        .map(|i| Leg {
            task: run[if backwards {
                (first + n - i) % n
            } else {
                (first + i) % n
            }],
            reversed: backwards,
            start_vertex: 0,
        })
        .collect()
}

/// Local search over the tasks (generalised TSP, open tour from an entry): the problem is built once per
/// region; only the entry (point 0) changes from one entry to the next.
struct SearchProblem {
    problem: TourProblem,
    points: Vec<Point2>,
    legs_of: Vec<Vec<Leg>>,
}

impl SearchProblem {
    /// The problem of `tasks`, or `None` when their options have more than [`MAX_SEARCH_POINTS`] points.
    fn new(tasks: &[Task]) -> Option<Self> {
        let count: usize = (0..tasks.len()).map(|k| 2 * task_options(tasks, k).len()).sum();
        if count > MAX_SEARCH_POINTS {
            return None;
        }
        let mut points = vec![Point2::origin()];
        let mut legs_of: Vec<Vec<Leg>> = Vec::with_capacity(tasks.len());
        let mut nodes = Vec::with_capacity(tasks.len());
        for k in 0..tasks.len() {
            let opts = task_options(tasks, k);
            let len = tasks[k].length();
            let mut node = Vec::new();
            let mut legs = Vec::new();
            for (entry_p, exit_p, leg) in &opts {
                let e = points.len();
                points.push(*entry_p);
                points.push(*exit_p);
                node.push(TourOption {
                    entry: e,
                    exit: e + 1,
                    cost: len,
                    reverse: 0,
                });
                legs.push(*leg);
            }
            // Reverse pairs: options come in (forward, backward) pairs.
            for (j, o) in node.iter_mut().enumerate() {
                o.reverse = j ^ 1;
            }
            nodes.push(node);
            legs_of.push(legs);
        }
        let dist = DistanceMatrix::from_fn(points.len(), |i, j| euclidean(points[i], points[j]));
        Some(Self {
            problem: TourProblem {
                dist,
                depot: 0,
                nodes,
                closed: false,
            },
            points,
            legs_of,
        })
    }

    /// The searched route from `entry`.
    fn route(&mut self, tasks: &[Task], entry: Point2, search: &RouteSearch<'_>) -> RegionRoute {
        self.points[0] = entry;
        for j in 1..self.points.len() {
            self.problem.dist.set(0, j, euclidean(entry, self.points[j]));
        }
        let tour = OrderMethod::TwoOpt.orderer().solve(
            &self.problem,
            search.seed,
            &SolveBudget {
                max_iterations: search.iterations,
                stop: search.stop,
            },
        );
        let legs: Vec<Leg> = tour
            .order
            .iter()
            .zip(&tour.options)
            .map(|(&n, &o)| self.legs_of[n][o])
            .collect();
        let exit = legs.last().map_or(entry, |l| l.ends(tasks).1);
        RegionRoute {
            legs,
            entry,
            exit,
            cost: tour.cost,
        }
    }
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

#[cfg(test)]
mod tests {
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
}
