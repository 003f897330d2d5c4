//! The sweep order of a region's tasks: lanes by offset across the sweep direction, chained ring pieces round
//! their loop, every other task inserted where it costs least.

use super::{Leg, RegionRoute, euclidean, legs_cost, task_options};
use crate::geom::{Point2, Vector2, direction};
use crate::pattern::Task;

/// The sweep order: lanes sorted by their offset across the sweep direction (then along it), each driven from
/// its end nearest to the current position; every other task is inserted where it adds the least.
pub(super) fn route_sweep(tasks: &[Task], angle: f64, entry: Point2) -> RegionRoute {
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
pub(super) fn chained_runs(tasks: &[Task]) -> Vec<Vec<usize>> {
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
