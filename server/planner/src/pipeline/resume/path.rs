//! The resumed path of one robot: what its previous plan still sweeps of the remainder, in the plan's own
//! order, joined by shortcuts (see the module docs of [`super`]).

use crate::geom::{Point2, polyline_length};
use crate::link::{LinkParams, Linker};
use crate::metrics::coverage::for_each_cell_in_capsule;
use crate::pipeline::{Waypoint, WaypointKind};
use crate::remainder::disc::{Disc, RowSums};
use crate::space::CoverageSpace;

/// One robot's resumed path.
#[derive(Debug, Clone)]
pub struct ResumedPath {
    /// From where the robot is, through every stretch of the previous plan still worth driving, to the
    /// previous plan's last point (its dock).
    pub waypoints: Vec<Waypoint>,
    /// Length of the previous plan driven again, metres.
    pub reused_m: f64,
    /// Stretches of the previous plan kept (runs of consecutive pieces).
    pub runs: usize,
    /// Runs from behind the robot (missed earlier) put where they cost least.
    pub inserted: usize,
    /// Per grid cell: a kept cell this path sweeps (the kept cells it leaves are outside the previous plan's
    /// swath, or on a piece now blocked).
    pub swept: Vec<bool>,
    /// Indices in `waypoints` of the first run's start and the last run's end (`None` without runs): what lies
    /// between is the work, before it the way there and after it the way to the dock.
    pub span: Option<(usize, usize)>,
}

/// A stretch of segment `seg` of the previous path, from `t0` to `t1` (fractions of the segment).
#[derive(Debug, Clone, Copy)]
struct Piece {
    seg: usize,
    t0: f64,
    t1: f64,
}

/// A run of consecutive pieces `first..=last` (indices into the piece list), possibly driven backwards.
#[derive(Debug, Clone)]
struct Run {
    first: usize,
    last: usize,
    points: Vec<Waypoint>,
}

impl Run {
    fn start(&self) -> Point2 {
        self.points[0].position
    }

    fn end(&self) -> Point2 {
        self.points[self.points.len() - 1].position
    }
}

fn at(previous: &[Waypoint], seg: usize, t: f64) -> Point2 {
    let (a, b) = (previous[seg].position, previous[seg + 1].position);
    a + (b - a) * t
}

pub(super) fn transit(position: Point2) -> Waypoint {
    Waypoint {
        position,
        kind: WaypointKind::Transit,
        region: None,
    }
}

/// Cuts every segment of `previous` into pieces no longer than `step` metres.
fn pieces(previous: &[Waypoint], step: f64) -> Vec<Piece> {
    let mut out = Vec::new();
    for seg in 0..previous.len().saturating_sub(1) {
        let d = (previous[seg + 1].position - previous[seg].position).norm();
        let k = ((d / step).ceil() as usize).max(1);
        out.extend((0..k).map(|j| Piece {
            seg,
            t0: j as f64 / k as f64,
            t1: (j + 1) as f64 / k as f64,
        }));
    }
    out
}

/// The resumed path on `space` of a robot at `from` that has reached waypoint `reached` of `previous`, with
/// `keep` (one flag per grid cell) still to cover. A piece is kept in the first round when at least
/// `min_new_share` of the coverable ground its tool sweeps is still to cover: the remainder's own rule for "a
/// pass worth driving" ([`crate::remainder::RemainderParams::min_new_share`]; pass the value the remainder
/// was cleaned with). Pieces sweeping less are kept in the second round only for kept cells no kept piece
/// sweeps, so a lane driven beside an undriven one is not driven again for the few cells its neighbour's
/// swath already holds. `None` when a link the path needs cannot be found (the
/// robot cannot get from where it is to what is left, or a piece's ends are no longer valid positions).
pub fn resume_path(
    space: &CoverageSpace,
    keep: &[bool],
    previous: &[Waypoint],
    (reached, from): (usize, Point2),
    min_new_share: f64,
) -> Option<ResumedPath> {
    let g = *space.geometry();
    let half = space.robot.tool_width_m / 2.0;
    let step = space.robot.tool_width_m.max(g.resolution);
    let pieces = pieces(previous, step);
    let ends = |p: &Piece| (at(previous, p.seg, p.t0), at(previous, p.seg, p.t1));
    // Every cell a piece's swath holds lies within half a piece and half a tool of its midpoint, so within
    // `reach` of the centre of the midpoint's cell: a piece with no kept cell there is skipped unwalked (most
    // of the driven part of the plan).
    let near = RowSums::new(&g, |i| keep[i]);
    let reach = Disc::new(step / 2.0 + half + g.resolution, g.resolution);
    let may_sweep = |a: Point2, b: Point2| g.locate(a + (b - a) * 0.5).is_none_or(|c| near.any(&reach, g.index(c)));
    // Round 1: pieces whose swath is mostly still to cover; round 2: any piece sweeping a kept cell no kept
    // piece sweeps yet. A piece a live obstacle now blocks is never kept.
    // (The validity check, the dearest, runs only on pieces the swath test would keep.)
    let mut swept = vec![false; g.len()];
    let mut useful = vec![false; pieces.len()];
    let mut cells: Vec<usize> = Vec::new();
    for (k, p) in pieces.iter().enumerate() {
        let (a, b) = ends(p);
        if !may_sweep(a, b) {
            continue;
        }
        cells.clear();
        let mut ground = 0usize;
        for_each_cell_in_capsule(&g, a, b, half, |i| {
            if keep[i] {
                cells.push(i);
            }
            ground += usize::from(space.coverable[i] || keep[i]);
        });
        let kept = cells.len();
        if kept > 0 && kept as f64 >= min_new_share * ground as f64 && space.segment_ok(a, b) {
            useful[k] = true;
            for &i in &cells {
                swept[i] = true;
            }
        }
    }
    for (k, p) in pieces.iter().enumerate() {
        if useful[k] {
            continue;
        }
        let (a, b) = ends(p);
        if !may_sweep(a, b) {
            continue;
        }
        cells.clear();
        let mut fresh = false;
        for_each_cell_in_capsule(&g, a, b, half, |i| {
            if keep[i] {
                cells.push(i);
                fresh |= !swept[i];
            }
        });
        if fresh && space.segment_ok(a, b) {
            useful[k] = true;
            for &i in &cells {
                swept[i] = true;
            }
        }
    }

    // Runs of consecutive useful pieces, each with the previous plan's waypoints inside it.
    let mut runs: Vec<Run> = Vec::new();
    let mut k = 0;
    while k < pieces.len() {
        if !useful[k] {
            k += 1;
            continue;
        }
        let first = k;
        while k + 1 < pieces.len() && useful[k + 1] {
            k += 1;
        }
        let last = k;
        let (p, q) = (pieces[first], pieces[last]);
        let mut points = vec![transit(at(previous, p.seg, p.t0))];
        for seg in p.seg..=q.seg {
            let t1 = if seg == q.seg { q.t1 } else { 1.0 };
            let w = previous[seg + 1];
            points.push(Waypoint {
                position: at(previous, seg, t1),
                ..w
            });
        }
        runs.push(Run { first, last, points });
        k += 1;
    }
    let reused_m = runs
        .iter()
        .map(|r| polyline_length(&r.points.iter().map(|w| w.position).collect::<Vec<_>>()))
        .sum();

    // Runs ahead of the robot keep their order; runs behind it (missed earlier) go where they cost least.
    let ahead_from = runs.partition_point(|r| pieces[r.first].seg < reached);
    let behind: Vec<Run> = runs.drain(..ahead_from).collect();
    let inserted = behind.len();
    let dock = previous.last().map_or(from, |w| w.position);
    let mut order: Vec<(Run, bool)> = runs.into_iter().map(|r| (r, false)).collect();
    for mut run in behind {
        let mut best = (f64::INFINITY, 0, false);
        for pos in 0..=order.len() {
            let before = if pos == 0 { from } else { order[pos - 1].0.end() };
            let after = if pos == order.len() { dock } else { order[pos].0.start() };
            for reversed in [false, true] {
                let (s, e) = if reversed {
                    (run.end(), run.start())
                } else {
                    (run.start(), run.end())
                };
                let cost = (s - before).norm() + (after - e).norm() - (after - before).norm();
                if cost < best.0 {
                    best = (cost, pos, reversed);
                }
            }
        }
        if best.2 {
            reverse_run(&mut run);
        }
        order.insert(best.1, (run, true));
    }

    // Links: between runs that follow each other on the previous plan, a shortcut no longer than the plan's
    // own way between them (or that way); elsewhere a search.
    let mut linker = Linker::new(space, &LinkParams::for_robot(&space.robot));
    let mut out: Vec<Waypoint> = vec![transit(from)];
    let mut prev: Option<&Run> = None;
    let mut span: Option<(usize, usize)> = None;
    for (run, moved) in &order {
        let a = out[out.len() - 1].position;
        let b = run.start();
        let between = match prev {
            Some(p) if !moved && p.last < run.first => Some(between_points(previous, &pieces, p.last, run.first)),
            _ => None,
        };
        link_into(&mut out, &mut linker, a, b, between.as_deref())?;
        let first = span.map_or(out.len() - 1, |s| s.0);
        out.extend(run.points.iter().skip(1).copied());
        span = Some((first, out.len() - 1));
        prev = (!moved).then_some(run);
    }
    let a = out[out.len() - 1].position;
    let tail = prev
        .filter(|p| p.last + 1 < pieces.len())
        .map(|p| between_points(previous, &pieces, p.last, pieces.len()));
    link_into(&mut out, &mut linker, a, dock, tail.as_deref())?;
    let (waypoints, span) = dedup_keeping(out, span);
    Some(ResumedPath {
        waypoints,
        reused_m,
        runs: order.len(),
        inserted,
        swept,
        span,
    })
}

/// `points` without consecutive repeats, and the indices of `span` moved with their points.
fn dedup_keeping(points: Vec<Waypoint>, span: Option<(usize, usize)>) -> (Vec<Waypoint>, Option<(usize, usize)>) {
    let mut out: Vec<Waypoint> = Vec::with_capacity(points.len());
    let mut at = vec![0; points.len()];
    for (k, w) in points.into_iter().enumerate() {
        if out.last().is_none_or(|l| (w.position - l.position).norm() >= 1e-9) {
            out.push(w);
        }
        at[k] = out.len() - 1;
    }
    (out, span.map(|(a, b)| (at[a], at[b])))
}

fn reverse_run(run: &mut Run) {
    run.points = reversed(&run.points);
}

/// `points` driven the other way: each waypoint's kind describes the segment ending at it, so reversed the
/// segment ends at its other end (the first point becomes a transit's start).
pub(super) fn reversed(points: &[Waypoint]) -> Vec<Waypoint> {
    let n = points.len();
    (0..n)
        .map(|j| {
            let w = points[n - 1 - j];
            let (kind, region) = if j == 0 {
                (WaypointKind::Transit, None)
            } else {
                (points[n - j].kind, points[n - j].region)
            };
            Waypoint { kind, region, ..w }
        })
        .collect()
}

/// The previous plan's points from the end of piece `after` to the start of piece `before` (`before` may be
/// the piece count: the plan's end).
fn between_points(previous: &[Waypoint], pieces: &[Piece], after: usize, before: usize) -> Vec<Point2> {
    let p = pieces[after];
    let mut pts = vec![at(previous, p.seg, p.t1)];
    let (seg_end, t_end) = match pieces.get(before) {
        Some(q) => (q.seg, q.t0),
        None => (previous.len() - 2, 1.0),
    };
    pts.extend((p.seg + 1..=seg_end).map(|s| previous[s].position));
    pts.push(at(previous, seg_end, t_end));
    pts.dedup_by(|b, a| (*b - *a).norm() < 1e-9);
    pts
}

/// Appends a transit from `a` to `b` to `out` (without `a`, which `out` ends with): a link no costlier than
/// `fallback`'s length when there is one, else `fallback` itself (when it is still valid on `linker`'s space:
/// else any link); with no fallback, a link. `None` when a link is needed and there is none.
fn link_into(
    out: &mut Vec<Waypoint>,
    linker: &mut Linker<'_>,
    a: Point2,
    b: Point2,
    fallback: Option<&[Point2]>,
) -> Option<()> {
    if (b - a).norm() < 1e-9 {
        return Some(());
    }
    let path = match fallback {
        Some(f) => {
            let bound = polyline_length(f);
            // The plan's own way may graze an obstacle where a piece was left out for it (a lane laid at the
            // radius exactly, sampled elsewhere than before): then a way round within a few metres more.
            let valid = f.windows(2).all(|w| linker.space().segment_ok(w[0], w[1]));
            let reach = if valid { bound } else { 2.0 * bound + 2.0 };
            match linker.link_within(a, b, reach) {
                Some(l) if valid && polyline_length(&l) > bound => f.to_vec(),
                Some(l) => l,
                None if valid => f.to_vec(),
                // Something new stands on the plan's way: any way round, or none.
                None => linker.link(a, b)?,
            }
        }
        None => linker.link(a, b)?,
    };
    out.extend(path.into_iter().skip(1).map(transit));
    Some(())
}
