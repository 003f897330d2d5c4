//! IKD-SWOpt (seed 000 Alg. 2): the sliding window around a breach and its optimisation.
//!
//! A [`Window`] is a stretch `[s0, s1]` (arc length, metres) of the original path. Its ends are the anchors
//! `A = P(s0)` and `B = P(s1)`, on the original path; the neighbours `A + h·u_A` and `B − h·u_B` (u the
//! direction of the anchor's segment, h the spacing) are fixed too, so the patch leaves and rejoins the
//! original path in position and heading. The points between are the variables: the original path resampled
//! at the spacing. They are minimised by L-BFGS ([`super::lbfgs`]) on the cost of [`super::cost`], from the
//! original points and from two *lateral starts* (each point pushed sideways, left or right, just far enough
//! to clear d_safe, then spread into a tent of slope 1 so neighbours follow): a cluster sitting on the path
//! gives the original points no useful gradient (the nearest obstacle point flips from side to side inside
//! it), and the lateral starts choose the side. Only starts whose cost does not exceed the original points'
//! are tried, so the result's cost never exceeds `cost_before`.

use crate::geom::{Point2, Vector2};

use super::cost::{Obstacles, Weights, WindowCost};
use super::lbfgs::Minimum;
use super::params::CorrectParams;
use super::path::Arclen;
use super::verify::verify;
use super::world::World;

/// L-BFGS memory (curvature pairs kept).
pub(crate) const MEMORY: usize = 6;
/// L-BFGS stops when no gradient component exceeds this (J per metre of displacement; the obstacle term's
/// gradient is 4·w_obs·h·deficit/margin², so this is a sub-micrometre penetration at the defaults).
pub(crate) const G_TOL: f64 = 1e-3;
/// L-BFGS stops when two iterations in a row lower J by less than this fraction: past that the patch moves
/// by well under a millimetre (the first, Newton-like step does most of the work; the tail only settles
/// which points touch the d_safe hinge), and `verify` decides feasibility anyway.
pub(crate) const F_REL_TOL: f64 = 1e-3;

/// Most intervals a window is resampled into.
const MAX_POINTS: usize = 1000;

/// A window of the original path: anchors, fixed heading neighbours and the original free points.
#[derive(Debug, Clone)]
pub(crate) struct Window {
    /// Arc length of the start anchor, metres.
    pub(crate) s0: f64,
    /// Arc length of the end anchor, metres.
    pub(crate) s1: f64,
    /// Start anchor and its heading neighbour.
    pub(crate) head: [Point2; 2],
    /// End anchor's heading neighbour and the end anchor.
    pub(crate) tail: [Point2; 2],
    /// The original path at the free points (spacing `h`).
    pub(crate) free: Vec<Point2>,
    /// Spacing, metres.
    pub(crate) h: f64,
}

impl Window {
    /// The window `[s0, s1]` of `arc` resampled at about `spacing` metres (at least one free point).
    pub(crate) fn new(arc: &Arclen<'_>, s0: f64, s1: f64, spacing: f64) -> Option<Self> {
        let len = s1 - s0;
        if len.is_nan() || len <= 0.0 || arc.segments() == 0 {
            return None;
        }
        // At most MAX_POINTS intervals whatever the spacing (bounded work on any input).
        let m = ((len / spacing).ceil().min(MAX_POINTS as f64) as usize).max(4);
        let h = len / m as f64;
        let seg0 = start_segment(arc, s0);
        let seg1 = end_segment(arc, s1);
        let u0 = seg_dir(arc, seg0)?;
        let u1 = seg_dir(arc, seg1)?;
        let a = arc.point_at(s0);
        let b = arc.point_at(s1);
        let free = (2..=m - 2).map(|j| arc.point_at(s0 + h * j as f64)).collect();
        Some(Self {
            s0,
            s1,
            head: [a, a + u0 * h],
            tail: [b - u1 * h, b],
            free,
            h,
        })
    }

    /// All points of the window for free points `free`.
    pub(crate) fn with_free(&self, free: &[Point2]) -> Vec<Point2> {
        let mut out = Vec::with_capacity(free.len() + 4);
        out.extend_from_slice(&self.head);
        out.extend_from_slice(free);
        out.extend_from_slice(&self.tail);
        out
    }
}

/// Segment k with s[k] < s ≤ s[k+1] (segment 0 for s = 0), skipping zero-length segments.
pub(crate) fn start_segment(arc: &Arclen<'_>, s: f64) -> usize {
    let n = arc.segments();
    (0..n)
        .find(|&k| arc.s[k] < s && s <= arc.s[k + 1])
        .or_else(|| (0..n).find(|&k| arc.s[k + 1] > arc.s[k]))
        .unwrap_or(0)
}

/// Segment k with s[k] ≤ s < s[k+1] (the last non-empty segment for s = total), skipping zero-length ones.
pub(crate) fn end_segment(arc: &Arclen<'_>, s: f64) -> usize {
    let n = arc.segments();
    (0..n)
        .find(|&k| arc.s[k] <= s && s < arc.s[k + 1])
        .or_else(|| (0..n).rev().find(|&k| arc.s[k + 1] > arc.s[k]))
        .unwrap_or(0)
}

/// Unit direction of segment k.
fn seg_dir(arc: &Arclen<'_>, k: usize) -> Option<Vector2> {
    let d = arc.path.get(k + 1)? - arc.path.get(k)?;
    let len = d.norm();
    (len > 0.0).then(|| d / len)
}

/// What optimising one window gave.
#[derive(Debug, Clone)]
pub(crate) struct Optimised {
    /// All window points, anchors included.
    pub(crate) points: Vec<Point2>,
    /// J of the original window points.
    pub(crate) cost_before: f64,
    /// J of `points` (≤ `cost_before`).
    pub(crate) cost_after: f64,
    /// L-BFGS iterations over every start tried.
    pub(crate) iterations: u32,
    /// Whether `points` passed [`verify`].
    pub(crate) feasible: bool,
}

/// The weights of `p` for a window of spacing `h`.
pub(crate) fn weights(p: &CorrectParams, h: f64) -> Weights {
    Weights {
        w_len: p.w_len,
        w_smooth: p.w_smooth,
        w_obs: p.w_obs,
        d_safe: p.d_safe(),
        margin: p.margin_m,
        h,
    }
}

fn flatten(pts: &[Point2]) -> Vec<f64> {
    pts.iter().flat_map(|q| [q.x, q.y]).collect()
}

fn unflatten(x: &[f64]) -> Vec<Point2> {
    x.chunks_exact(2).map(|c| Point2::new(c[0], c[1])).collect()
}

/// A lateral start: each free point moved along the window's left normal (`side` = 1) or right normal
/// (`side` = −1) by the least multiple of `step` that clears `target` (up to `max_offset`), spread as a
/// tent of slope 1 and brought to 0 at the fixed ends.
fn lateral_start<O: Obstacles>(
    win: &Window,
    obstacles: &O,
    side: f64,
    target: f64,
    step: f64,
    max_offset: f64,
) -> Vec<Point2> {
    let all = win.with_free(&win.free);
    let n = win.free.len();
    let normal = |i: usize| -> Vector2 {
        // Point i of `free` is point i + 2 of `all`.
        let d = all[i + 3] - all[i + 1];
        let len = d.norm();
        if len > 0.0 {
            Vector2::new(-d.y, d.x) / len * side
        } else {
            Vector2::zeros()
        }
    };
    let clearance = |q: Point2| obstacles.nearest(q).map_or(f64::INFINITY, |(_, d)| d);
    let mut need = vec![0.0; n];
    for (i, q) in win.free.iter().enumerate() {
        // Sphere tracing along the normal: clearance is 1-Lipschitz, so no offset before o + (target − c)
        // can clear the target, and the jump never passes the first clear offset.
        let nv = normal(i);
        let mut o = 0.0;
        loop {
            let c = clearance(q + nv * o);
            if c >= target || o > max_offset {
                break;
            }
            o += (target - c).max(step);
        }
        need[i] = o.min(max_offset);
    }
    // Tent envelope: O_i = max_j need_j − |i − j|·h, and at most the distance to either fixed end.
    let mut off = need.clone();
    for i in 1..n {
        off[i] = off[i].max(off[i - 1] - win.h);
    }
    for i in (0..n.saturating_sub(1)).rev() {
        off[i] = off[i].max(off[i + 1] - win.h);
    }
    (0..n)
        .map(|i| {
            let to_end = win.h * ((i + 1).min(n - i) as f64);
            win.free[i] + normal(i) * off[i].min(to_end)
        })
        .collect()
}

/// Optimises one window: from the original points and the two lateral starts (best first, only those not
/// costlier than the original), keeping the first verified optimum, else the cheapest (with our L-BFGS, as
/// the repair runs it; tests call it directly).
#[cfg(test)]
pub(crate) fn optimise_window<O: Obstacles>(
    win: &Window,
    obstacles: &O,
    world: &World<'_>,
    p: &CorrectParams,
) -> Optimised {
    optimise_window_with(win, obstacles, world, p, &mut |cost, x0| {
        super::lbfgs::minimize(cost, x0, p.max_iterations, MEMORY, G_TOL, F_REL_TOL)
    })
}

/// [`optimise_window`] with another minimiser (bench comparisons): `solve(cost, x0)` must return a point
/// no costlier than `x0`, with its cost.
pub(crate) fn optimise_window_with<O, S>(
    win: &Window,
    obstacles: &O,
    world: &World<'_>,
    p: &CorrectParams,
    solve: &mut S,
) -> Optimised
where
    O: Obstacles,
    S: FnMut(&mut WindowCost<'_, O>, &[f64]) -> Minimum,
{
    let w = weights(p, win.h);
    let mut cost = WindowCost::new(win.head, win.tail, w, obstacles, win.free.len());
    let max_offset = 0.5 * (win.s1 - win.s0);
    let x_orig = flatten(&win.free);
    let cost_before = cost.value(&x_orig);
    let step = (0.5 * world.resolution()).max(0.5 * p.margin_m);
    let target = p.d_safe() + 0.5 * p.margin_m;
    let mut starts: Vec<(f64, Vec<f64>)> = vec![(cost_before, x_orig)];
    for side in [1.0, -1.0] {
        let x = flatten(&lateral_start(win, obstacles, side, target, step, max_offset));
        let c = cost.value(&x);
        if c <= cost_before {
            starts.push((c, x));
        }
    }
    starts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut iterations = 0;
    let mut best: Option<Optimised> = None;
    for (_, x0) in starts {
        let min = solve(&mut cost, &x0);
        iterations += min.iterations;
        let points = win.with_free(&unflatten(&min.x));
        let feasible = verify(&points, world, p.robot_radius_m);
        let cand = Optimised {
            points,
            cost_before,
            cost_after: min.f,
            iterations,
            feasible,
        };
        if feasible {
            return cand;
        }
        if best.as_ref().is_none_or(|b| cand.cost_after < b.cost_after) {
            best = Some(cand);
        }
    }
    let mut out = best.unwrap_or(Optimised {
        points: win.with_free(&win.free),
        cost_before,
        cost_after: cost_before,
        iterations,
        feasible: false,
    });
    out.iterations = iterations;
    out
}
