//! Handing a lost robot's unfinished work to the robots that go on (issue 20, live re-division), without a
//! new division.
//!
//! When a robot is lost with its plan unfinished, the others' plans still resume ([`super`]), and what the
//! lost one had left is its own plan's tail: lanes laid for that ground, in an order already optimised for
//! it. Dividing the whole site again costs seconds on a large site and gives every robot a new path; here
//! the lost plan is resumed like any other (on the receivers' space, leaving out what their resumed paths
//! already sweep), and its work, the *chain* from its first kept run to its last with the plan's own ways
//! between them, is cut into consecutive blocks, one per robot that goes on:
//!
//! - **Who takes what.** Each receiver is placed along the chain where its own path comes nearest
//!   (its *anchor*), and the blocks follow that order, so a robot takes the stretch beside its part. The cuts
//!   minimise the latest finish: each receiver's remaining time, plus its block's time on the lost plan's
//!   profile, plus the way to the block and back (twice the anchor distance at the receiver's top speed).
//!   For a fixed order this is the linear-partition problem; a bisection on the finish time with a greedy
//!   fill solves it exactly for the estimate.
//! - **Where it goes.** A block is inserted into its receiver's path where it adds least: in place of a
//!   transit (the block's ends linked to the transit's ends) or as a detour from a waypoint and back, either
//!   direction. Candidates are linked on the grid cheapest by straight-line cost first, until the best linked
//!   cost is within 5 % of the next candidate's straight-line cost (a lower bound of its linked cost), so an
//!   insertion within 5 % of the cheapest linked one is found with one or two searches where the way is open. Lanes are never cut (blocks start and end at the lost plan's waypoints, and insertions
//!   replace transits only).
//!
//! The caller ([`super::resume_fleet`]) profiles the paths again and applies its usual checks: nothing the
//! plans held left unswept, and no robot finishing so late that a new division would do better.

use crate::divide::FleetRobot;
use crate::error::Result;
use crate::geom::Point2;
use crate::link::{LinkParams, Linker};
use crate::metrics::coverage::for_each_cell_in_capsule;
use crate::pipeline::{Waypoint, WaypointKind};
use crate::remainder::{Remainder, RemainderParams};
use crate::space::CoverageSpace;

use super::Previous;
use super::path::{ResumedPath, reversed, transit};

/// A robot of the fleet lost with its plan unfinished.
#[derive(Debug, Clone, Copy)]
pub struct Lost<'a> {
    /// The robot (its shape decides which robots can take its lanes: only robots of the same shape).
    pub robot: &'a FleetRobot,
    /// Its plan, and the last waypoint it reached (`from`: where it was last seen, or that waypoint).
    pub previous: Previous<'a>,
}

/// The lost plan's work: its resumed runs and the ways between them, timed.
#[derive(Debug, Clone)]
pub(super) struct Chain {
    /// From the first kept run's start to the last kept run's end.
    pub waypoints: Vec<Waypoint>,
    /// Seconds from the chain's start at each waypoint (on the lost plan's profile).
    pub time_s: Vec<f64>,
    /// Per grid cell: a kept cell the lost plan's resumed path sweeps.
    pub swept: Vec<bool>,
}

impl Chain {
    /// The work of `path` (a resumed lost plan) timed by `timeline` ((arc length, seconds) along that path
    /// as driven, [`crate::speed::estimate::drive_timeline`] or a profile's): each waypoint's time is read at
    /// its arc length, scaled to the timeline's length (rounding corners makes it a little shorter). `None`
    /// when the path has no runs.
    pub fn new(path: ResumedPath, timeline: &[(f64, f64)]) -> Option<Self> {
        let (a, b) = path.span?;
        let pts = &path.waypoints;
        let mut arc = vec![0.0; pts.len()];
        for k in 1..pts.len() {
            arc[k] = arc[k - 1] + (pts[k].position - pts[k - 1].position).norm();
        }
        let total = arc[pts.len() - 1];
        let (t_arc, t_end) = timeline.last().copied().unwrap_or((0.0, 0.0));
        let time_at = |s: f64| {
            if total <= 0.0 || timeline.is_empty() {
                return 0.0;
            }
            let s = s / total * t_arc;
            let j = timeline.partition_point(|w| w.0 < s);
            if j == 0 {
                return timeline[0].1;
            }
            let Some(&(hi_s, hi_t)) = timeline.get(j) else {
                return t_end;
            };
            let (lo_s, lo_t) = timeline[j - 1];
            let f = if hi_s > lo_s { (s - lo_s) / (hi_s - lo_s) } else { 0.0 };
            lo_t + f * (hi_t - lo_t)
        };
        let t0 = time_at(arc[a]);
        Some(Self {
            waypoints: pts[a..=b].to_vec(),
            time_s: (a..=b).map(|k| (time_at(arc[k]) - t0).max(0.0)).collect(),
            swept: path.swept,
        })
    }
}

/// A robot that goes on, as the split sees it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Receiver<'a> {
    /// Its resumed path.
    pub waypoints: &'a [Waypoint],
    /// That path's duration, seconds.
    pub duration_s: f64,
    /// Its top speed, m/s (for the way to its block and back).
    pub v_max: f64,
}

/// At most this many points of a path or chain are compared when placing receivers along the chain.
const ANCHOR_SAMPLES: usize = 2000;

/// Every `len / ANCHOR_SAMPLES`-th index, and the last.
fn sampled(len: usize) -> impl Iterator<Item = usize> {
    let step = len.div_ceil(ANCHOR_SAMPLES).max(1);
    (0..len).step_by(step).chain((len > 0).then(|| len - 1))
}

/// The chain waypoint nearest to `path` and that distance.
fn anchor(chain: &[Waypoint], path: &[Waypoint]) -> (usize, f64) {
    let mut best = (0, f64::INFINITY);
    for j in sampled(chain.len()) {
        let c = chain[j].position;
        for i in sampled(path.len()) {
            let d = (path[i].position - c).norm();
            if d < best.1 {
                best = (j, d);
            }
        }
    }
    best
}

/// Cuts the chain into consecutive blocks (see the module docs): per receiver (in the receivers' order) the
/// range of chain waypoints it takes (`a..=b`, sharing each cut waypoint with the next block), or `None`.
pub(super) fn split(chain: &Chain, receivers: &[Receiver<'_>]) -> Vec<Option<(usize, usize)>> {
    let m = chain.waypoints.len();
    if m < 2 || receivers.is_empty() {
        return vec![None; receivers.len()];
    }
    let placed: Vec<(usize, f64)> = receivers
        .iter()
        .map(|r| anchor(&chain.waypoints, r.waypoints))
        .collect();
    let mut order: Vec<usize> = (0..receivers.len()).collect();
    order.sort_by(|&a, &b| placed[a].0.cmp(&placed[b].0).then(placed[a].1.total_cmp(&placed[b].1)));
    let reach_s: Vec<f64> = (receivers.iter().zip(&placed))
        .map(|(r, &(_, d))| {
            if r.v_max > 0.0 {
                2.0 * d / r.v_max
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let t = &chain.time_s;
    // The greedy fill for a finish time `f`: each receiver in order takes the longest block it can finish by
    // `f`; `None` when the chain is not used up.
    let fill = |f: f64| -> Option<Vec<Option<(usize, usize)>>> {
        let mut blocks = vec![None; receivers.len()];
        let mut at = 0;
        for &r in &order {
            if at + 1 >= m {
                break;
            }
            let budget = f - receivers[r].duration_s - reach_s[r];
            if budget <= 0.0 {
                continue;
            }
            let end = t.partition_point(|&x| x - t[at] <= budget).saturating_sub(1).max(at);
            if end > at {
                blocks[r] = Some((at, end));
                at = end;
            }
        }
        (at + 1 >= m).then_some(blocks)
    };
    let lo0 = receivers.iter().map(|r| r.duration_s).fold(f64::INFINITY, f64::min);
    let finite_reach = reach_s.iter().copied().filter(|x| x.is_finite()).fold(0.0, f64::max);
    let hi0 = receivers.iter().map(|r| r.duration_s).fold(0.0, f64::max) + t[m - 1] + finite_reach + 1.0;
    let Some(mut best) = fill(hi0) else {
        return vec![None; receivers.len()];
    };
    let (mut lo, mut hi) = (lo0, hi0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        match fill(mid) {
            Some(b) => {
                best = b;
                hi = mid;
            }
            None => lo = mid,
        }
        if hi - lo < 0.5 {
            break;
        }
    }
    best
}

/// Cells of `swept` (a chain's) that `block` sweeps with a tool `half` a width either side.
pub(super) fn block_cells(
    g: &crate::map::GridGeometry,
    block: &[Waypoint],
    half: f64,
    swept: &[bool],
    mut f: impl FnMut(usize),
) {
    for w in block.windows(2) {
        for_each_cell_in_capsule(g, w[0].position, w[1].position, half, |i| {
            if swept[i] {
                f(i);
            }
        });
    }
}

/// Most insertions linked on the grid (the cheapest by straight-line cost first).
const MAX_LINKED: usize = 8;

/// A linked insertion within this share of the next candidate's lower bound is kept (the search stops).
const NEAR_ENOUGH: f64 = 0.05;

/// Insertions at waypoints closer than this (metres), the same way round, count as one.
const ALIKE_M: f64 = 2.0;

/// One way to insert a block: after waypoint `at`, `replace` the transit that follows it (else a detour
/// back to it), the block `reversed` or not; `cost` in metres added.
#[derive(Debug, Clone, Copy)]
struct Insertion {
    cost: f64,
    at: usize,
    replace: bool,
    reversed: bool,
}

/// `path` with `block` inserted where it adds least (see the module docs), the block's waypoints without
/// their regions (they are the lost plan's). `None` when no candidate can be linked.
pub(super) fn insert(linker: &mut Linker<'_>, path: &[Waypoint], block: &[Waypoint]) -> Option<Vec<Waypoint>> {
    let (Some(first), Some(last)) = (block.first(), block.last()) else {
        return Some(path.to_vec());
    };
    let (bs, be) = (first.position, last.position);
    let mut candidates: Vec<Insertion> = Vec::new();
    for (i, w) in path.iter().enumerate() {
        let p = w.position;
        // A detour costs the same either way round.
        candidates.push(Insertion {
            cost: (bs - p).norm() + (p - be).norm(),
            at: i,
            replace: false,
            reversed: false,
        });
        for reversed in [false, true] {
            let (s, e) = if reversed { (be, bs) } else { (bs, be) };
            if let Some(next) = path.get(i + 1).filter(|n| n.kind == WaypointKind::Transit) {
                let q = next.position;
                candidates.push(Insertion {
                    cost: (s - p).norm() + (q - e).norm() - (q - p).norm(),
                    at: i,
                    replace: true,
                    reversed,
                });
            }
        }
    }
    candidates.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let oriented = |reversed: bool| -> Vec<Waypoint> {
        let b = if reversed {
            self::reversed(block)
        } else {
            block.to_vec()
        };
        b.into_iter().map(|w| Waypoint { region: None, ..w }).collect()
    };
    let mut best: Option<(f64, Vec<Waypoint>)> = None;
    let mut tried: Vec<&Insertion> = Vec::new();
    for c in &candidates {
        // Straight lines bound the linked cost from below: no candidate left can beat the best linked one.
        if tried.len() >= MAX_LINKED || best.as_ref().is_some_and(|(x, _)| *x <= c.cost * (1.0 + NEAR_ENOUGH)) {
            break;
        }
        // A dense path has many waypoints at one place: one search stands for them all.
        let near = |a: usize, b: usize| (path[a].position - path[b].position).norm() < ALIKE_M;
        if tried
            .iter()
            .any(|t| t.reversed == c.reversed && t.replace == c.replace && near(t.at, c.at))
        {
            continue;
        }
        tried.push(c);
        let b = oriented(c.reversed);
        let p = path[c.at].position;
        let back_to = if c.replace { path[c.at + 1].position } else { p };
        // Once a candidate is linked, a search past its cost cannot give a cheaper one: searches stop there.
        let bound = best.as_ref().map_or(f64::INFINITY, |(x, _)| {
            x + if c.replace { (back_to - p).norm() } else { 0.0 }
        });
        let Some(to) = linker.link_within(p, b[0].position, bound) else {
            continue;
        };
        let Some(from) = linker.link_within(b[b.len() - 1].position, back_to, bound) else {
            continue;
        };
        let len = |l: &[Point2]| l.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>();
        let cost = len(&to) + len(&from) - if c.replace { (back_to - p).norm() } else { 0.0 };
        if best.as_ref().is_some_and(|(x, _)| *x <= cost) {
            continue;
        }
        let mut out: Vec<Waypoint> = path[..=c.at].to_vec();
        out.extend(to.into_iter().skip(1).map(transit));
        out.extend(b.into_iter().skip(1));
        out.extend(from.into_iter().skip(1).map(transit));
        out.extend_from_slice(&path[c.at + 1 + usize::from(c.replace)..]);
        out.dedup_by(|b, a| (b.position - a.position).norm() < 1e-9);
        best = Some((cost, out));
    }
    best.map(|(_, p)| p)
}

/// The fleet's resumed plans as [`hand_over`] sees them: per robot its replan space and resumed path, its
/// profiled duration, the index of its shared space, and the robot.
pub(super) struct Resumed<'a> {
    pub paths: &'a mut [(CoverageSpace, ResumedPath)],
    pub durations_s: &'a [f64],
    pub space_of: &'a [usize],
    pub robots: &'a [FleetRobot],
}

/// Hands the unfinished work of lost robot `lost` to the robots resumed on its space (see the module docs):
/// their paths in `resumed` get its blocks, and the answer holds, per robot, the kept cells it took over
/// (empty for the others). `swept` flags what the resumed paths already sweep; `timeline` times the lost
/// plan's resumed path on its space and remainder ((arc length, seconds) along it). `Ok(Err(why))` when it
/// cannot be handed over.
pub(super) fn hand_over(
    lost: &Lost<'_>,
    spaces: &[(CoverageSpace, Remainder)],
    resumed: Resumed<'_>,
    swept: &[bool],
    remainder_params: &RemainderParams,
    timeline: impl FnOnce(&CoverageSpace, &Remainder, &ResumedPath) -> Result<Vec<(f64, f64)>>,
) -> Result<std::result::Result<Vec<Vec<usize>>, String>> {
    let n = resumed.paths.len();
    let prev = lost.previous;
    let Some(g) = spaces.first().map(|(s, _)| *s.geometry()) else {
        return Ok(Err("no robot goes on".into()));
    };
    let on = |s: &CoverageSpace| g.locate(prev.from).is_some_and(|c| s.reachable[g.index(c)]);
    let Some(at) = (spaces.iter()).position(|(s, _)| s.robot == lost.robot.shape && on(s)) else {
        return Ok(Err("no robot of the lost robot's shape can reach its part".into()));
    };
    let receivers: Vec<usize> = (0..n).filter(|&k| resumed.space_of[k] == at).collect();
    if receivers.is_empty() {
        return Ok(Err("no robot of the lost robot's shape can reach its part".into()));
    }
    let (space, rem) = &spaces[at];
    // What the lost plan has left that no resumed path sweeps.
    let keep: Vec<bool> = rem.keep.iter().zip(swept).map(|(&k, &s)| k && !s).collect();
    // Where the lost robot was on its plan (a valid position unless the map changed there).
    let from = if space.point_ok(prev.from) {
        prev.from
    } else {
        super::super::remainder::remainder_space(space, rem, prev.from)?.start
    };
    let Some(path) = super::resume_path(
        space,
        &keep,
        prev.path,
        (prev.reached, from),
        remainder_params.min_new_share,
    ) else {
        return Ok(Err("the lost robot's unfinished lanes cannot be reached".into()));
    };
    let times = timeline(space, rem, &path)?;
    let mut taken = vec![Vec::new(); n];
    let Some(chain) = Chain::new(path, &times) else {
        // Nothing of its plan is left worth driving.
        return Ok(Ok(taken));
    };
    let blocks = {
        let view: Vec<Receiver<'_>> = (receivers.iter())
            .map(|&k| Receiver {
                waypoints: &resumed.paths[k].1.waypoints,
                duration_s: resumed.durations_s[k],
                v_max: resumed.robots[k].limits.v_max_mps,
            })
            .collect();
        split(&chain, &view)
    };
    let half = space.robot.tool_width_m / 2.0;
    // Which receiver last took each cell (receivers take their blocks one after another): each cell once.
    let mut took = vec![u32::MAX; g.len()];
    for (&k, block) in receivers.iter().zip(blocks) {
        let Some((a, b)) = block else { continue };
        let piece = &chain.waypoints[a..=b];
        let (rs, path) = &mut resumed.paths[k];
        let mut linker = Linker::new(rs, &LinkParams::for_robot(&rs.robot));
        let Some(joined) = insert(&mut linker, &path.waypoints, piece) else {
            return Ok(Err("a robot cannot reach its share of the lost robot's lanes".into()));
        };
        path.waypoints = joined;
        path.span = None;
        block_cells(&g, piece, half, &chain.swept, |i| {
            if took[i] != k as u32 {
                took[i] = k as u32;
                taken[k].push(i);
            }
        });
    }
    Ok(Ok(taken))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wp(x: f64, y: f64, kind: WaypointKind) -> Waypoint {
        Waypoint {
            position: Point2::new(x, y),
            kind,
            region: None,
        }
    }

    /// A chain along x of 11 waypoints, 10 s apart.
    fn chain() -> Chain {
        Chain {
            waypoints: (0..=10).map(|k| wp(k as f64, 0.0, WaypointKind::Cover)).collect(),
            time_s: (0..=10).map(|k| 10.0 * k as f64).collect(),
            swept: Vec::new(),
        }
    }

    /// Two receivers at either end of a 100 s chain, one with 20 s left and one with none: the cut meets
    /// where both finish together (20 + 40 = 60), each taking the stretch at its own end, sharing the cut.
    #[test]
    fn the_chain_is_cut_where_the_receivers_finish_together() {
        let near_start = [wp(0.0, 0.0, WaypointKind::Transit)];
        let near_end = [wp(10.0, 0.0, WaypointKind::Transit)];
        let receivers = [
            Receiver {
                waypoints: &near_end,
                duration_s: 0.0,
                v_max: 1.0,
            },
            Receiver {
                waypoints: &near_start,
                duration_s: 20.0,
                v_max: 1.0,
            },
        ];
        let blocks = split(&chain(), &receivers);
        assert_eq!(blocks, vec![Some((4, 10)), Some((0, 4))]);
        // A receiver already busy past the whole chain's time takes nothing.
        let busy = [
            receivers[0],
            Receiver {
                duration_s: 500.0,
                ..receivers[1]
            },
        ];
        assert_eq!(split(&chain(), &busy), vec![Some((0, 10)), None]);
    }

    /// A block goes in place of a transit, or as a detour at a waypoint: every lane of the path is still
    /// driven whole, in its order, and the block's lanes are all there.
    #[test]
    fn an_inserted_block_never_cuts_a_lane() {
        let g = crate::map::GridGeometry::new(200, 100, 0.1, Point2::origin()).expect("grid");
        let grid = crate::map::OccupancyGrid::filled(g, crate::map::CellState::Free);
        let shape = crate::space::RobotShape {
            radius_m: 0.3,
            tool_width_m: 0.6,
        };
        let space = CoverageSpace::new(grid, shape, Point2::new(1.0, 1.0)).expect("space");
        let mut linker = Linker::new(&space, &LinkParams::for_robot(&shape));
        let lanes = |y0: f64, x0: f64, x1: f64| {
            vec![
                wp(x0, y0, WaypointKind::Transit),
                wp(x1, y0, WaypointKind::Cover),
                wp(x1, y0 + 0.6, WaypointKind::Transit),
                wp(x0, y0 + 0.6, WaypointKind::Cover),
            ]
        };
        // Two lanes low on the left, a transit up, two lanes high on the left; the block sits on the right.
        let mut path = lanes(1.0, 1.0, 8.0);
        path.extend(lanes(7.0, 1.0, 8.0));
        let block = lanes(4.0, 12.0, 19.0);
        let out = insert(&mut linker, &path, &block).expect("inserted");
        let covers = |p: &[Waypoint]| -> Vec<(Point2, Point2)> {
            (p.windows(2))
                .filter(|w| w[1].kind == WaypointKind::Cover)
                .map(|w| (w[0].position, w[1].position))
                .collect()
        };
        let got = covers(&out);
        let mut want = covers(&path);
        want.extend(covers(&block));
        assert_eq!(got.len(), want.len(), "{out:?}");
        for lane in &want {
            assert!(
                got.iter()
                    .any(|g| (g.0 - lane.0).norm() < 1e-9 && (g.1 - lane.1).norm() < 1e-9
                        || (g.0 - lane.1).norm() < 1e-9 && (g.1 - lane.0).norm() < 1e-9),
                "{lane:?} missing"
            );
        }
        // The path's own lanes keep their order.
        let own: Vec<_> = got.iter().filter(|l| l.0.x < 10.0).collect();
        assert_eq!(own.len(), 4);
        assert!(own.windows(2).all(|w| w[0].0.y <= w[1].0.y));
        // Every segment is valid, and the path still starts and ends where it did.
        assert!(out.windows(2).all(|w| space.segment_ok(w[0].position, w[1].position)));
        assert_eq!(out.first().map(|w| w.position), path.first().map(|w| w.position));
        assert_eq!(out.last().map(|w| w.position), path.last().map(|w| w.position));
    }
}
