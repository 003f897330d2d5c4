//! The repair entry point: optimiser windows, then detour windows, then the skip (see the
//! [module docs](super)).

use crate::geom::Point2;

use super::cost::WindowCost;
use super::detour::{LocalGrid, shortcut_chain};
use super::error::CorrectError;
use super::escape::EscapeCase;
use super::judge::{Breach, sample_step};
use super::lbfgs::{Minimum, Objective, minimize};
use super::local::LocalObstacles;
use super::optimize::{F_REL_TOL, G_TOL, MEMORY, Window, end_segment, optimise_window_with, start_segment, weights};
use super::params::CorrectParams;
use super::path::Arclen;
use super::verify::{segment_clear, verify};
use super::world::{STATIC_SLACK_M, World};
use super::{Repair, RepairKind};

/// Most cells of a detour's search box.
const DETOUR_MAX_CELLS: usize = 90_000;
/// Most cells of a skip's search box.
const SKIP_MAX_CELLS: usize = 250_000;

/// Replaces the stretch of `path` around `breach` (from [`super::judge`]) by a patch that keeps the robot
/// radius everywhere ([`verify`]). Tries IKD-SWOpt windows of growing length (up to `p.max_window_m`), then
/// local A* detours over the same windows, then a skip to the first reachable point up to
/// `p.skip_search_m` further along the plan, and finally a stop at the start anchor. The patch never starts
/// before `breach.earliest`.
///
/// Fails on invalid params, an unusable path (fewer than two points, a non-finite point, zero length) or
/// breach, an inconsistent world, or a start anchor that is itself in collision; never returns a patch that
/// comes closer than the radius, with one exception: a start anchor closer than the radius to live obstacles
/// only (the robot saw something late and is already inside the band) gets an escape instead of the error when
/// one exists ([`super::Escape`]: never closer than the anchor is, the radius back within a short way).
pub fn repair(path: &[Point2], breach: &Breach, world: &World<'_>, p: &CorrectParams) -> Result<Repair, CorrectError> {
    match repair_keeping(path, breach, world, p) {
        Err(CorrectError::AnchorInCollision { x, y, clearance_m }) => EscapeCase::new(world, p, Point2::new(x, y))
            .and_then(|case| {
                let rep = repair_keeping(path, breach, world, &case.thin).ok()?;
                case.accept(rep, path, breach, world, p)
            })
            .ok_or(CorrectError::AnchorInCollision { x, y, clearance_m }),
        other => other,
    }
}

/// [`repair`] without the escape: every patch keeps `p.robot_radius_m` from its start anchor on.
fn repair_keeping(
    path: &[Point2],
    breach: &Breach,
    world: &World<'_>,
    p: &CorrectParams,
) -> Result<Repair, CorrectError> {
    let (r, s_a, s_b) = prepare(path, breach, world, p)?;
    let mut plan = r.windows(s_a, s_b)?;
    if let Some(rep) = r.optimise(&mut plan) {
        return Ok(rep);
    }
    if let Some(rep) = r.detour(&mut plan) {
        return Ok(rep);
    }
    Ok(r.skip(&plan))
}

/// Only the IKD-SWOpt stage of [`repair`]: the optimised patch of the first window (of growing length)
/// whose optimum passes [`verify`], or `None` when no window up to `p.max_window_m` gives one. Same errors
/// as [`repair`].
pub fn optimise(
    path: &[Point2],
    breach: &Breach,
    world: &World<'_>,
    p: &CorrectParams,
) -> Result<Option<Repair>, CorrectError> {
    let (r, s_a, s_b) = prepare(path, breach, world, p)?;
    let mut plan = r.windows(s_a, s_b)?;
    Ok(r.optimise(&mut plan))
}

/// Bench hook, not API ([`super::hooks`]): [`optimise`] with another minimiser in place of our L-BFGS.
/// `solve(objective, x0)` minimises the window cost (`objective.eval` gives J and its gradient; its
/// `precondition` is ours to use or ignore) from `x0` and must return a point no costlier than `x0`.
#[doc(hidden)]
pub fn optimise_with(
    path: &[Point2],
    breach: &Breach,
    world: &World<'_>,
    p: &CorrectParams,
    solve: &mut dyn FnMut(&mut dyn Objective, &[f64]) -> Minimum,
) -> Result<Option<Repair>, CorrectError> {
    let (r, s_a, s_b) = prepare(path, breach, world, p)?;
    let mut plan = r.windows(s_a, s_b)?;
    Ok(r.optimise_with(&mut plan, &mut |cost, x0| solve(cost, x0)))
}

/// Checks the input and sets up a repair: the repairer and the breach's arc lengths.
fn prepare<'a, 'w>(
    path: &'a [Point2],
    breach: &Breach,
    world: &'a World<'w>,
    p: &'a CorrectParams,
) -> Result<(Repairer<'a, 'w>, f64, f64), CorrectError> {
    p.validate()?;
    world.check()?;
    if path.len() < 2 {
        return Err(CorrectError::BadPath(format!(
            "{} waypoints; need at least 2",
            path.len()
        )));
    }
    if let Some(i) = path.iter().position(|q| !(q.x.is_finite() && q.y.is_finite())) {
        return Err(CorrectError::BadPath(format!("waypoint {i} is not finite")));
    }
    let arc = Arclen::new(path);
    if arc.total().is_nan() || arc.total() <= 0.0 {
        return Err(CorrectError::BadPath("the path has zero length".into()));
    }
    for (name, pos) in [
        ("start", breach.start),
        ("end", breach.end),
        ("earliest", breach.earliest),
    ] {
        if pos.seg >= arc.segments() || !(0.0..=1.0).contains(&pos.t) {
            return Err(CorrectError::BadBreach(format!(
                "{name} {pos:?} is not on a path of {} segments",
                arc.segments()
            )));
        }
    }
    let (s_a, s_b) = (arc.s_of(breach.start), arc.s_of(breach.end));
    if s_b < s_a {
        return Err(CorrectError::BadBreach(format!(
            "end {:?} lies before start {:?}",
            breach.end, breach.start
        )));
    }
    let s_e = arc.s_of(breach.earliest).min(s_a);
    Ok((
        Repairer {
            arc,
            world,
            p,
            s_e,
            h: sample_step(world, p.robot_radius_m),
        },
        s_a,
        s_b,
    ))
}

/// The windows of one repair and what the stages tried so far.
struct Plan {
    /// Start anchor of the first window (arc length, metres): where a skip starts.
    start: f64,
    /// End of the non-compliant core (arc length, metres).
    core_end: f64,
    /// Windows whose anchors and heading neighbours are clear, shortest first.
    usable: Vec<Window>,
    /// L-BFGS iterations spent.
    iterations: u32,
    /// (cost_before, cost_after) of the first window optimised.
    costs: Option<(f64, f64)>,
}

/// One repair's shared state.
struct Repairer<'a, 'w> {
    arc: Arclen<'a>,
    world: &'a World<'w>,
    p: &'a CorrectParams,
    /// Earliest arc length the patch may start at.
    s_e: f64,
    /// Sample step along the path, metres.
    h: f64,
}

impl<'w> Repairer<'_, 'w> {
    /// Compliant as the judge means it: d_safe from live obstacles, the radius from the static map.
    fn compliant(&self, s: f64) -> bool {
        let q = self.arc.point_at(s);
        let d = self.p.d_safe();
        self.world.inside(q)
            && self.world.live_clearance_upto(q, d) >= d
            && self.world.static_clearance_upto(q, d) >= self.p.robot_radius_m - STATIC_SLACK_M
    }

    /// Moves `s` back (dir −1) or forward (dir 1) in steps of h while the path is non-compliant, within
    /// [lo, hi].
    fn to_compliant(&self, mut s: f64, dir: f64, lo: f64, hi: f64) -> f64 {
        while !self.compliant(s) {
            let next = s + dir * self.h;
            if next < lo || next > hi {
                return if dir < 0.0 { lo } else { hi };
            }
            s = next;
        }
        s
    }

    /// The least sideways offset (metres, to one side for the whole stretch) that takes the points of the
    /// path between arc lengths ca and cb clear of d_safe: min over both sides of the max over the points of
    /// the sphere-traced offset along the path normal. Capped at half the longest window.
    fn lateral_need(&self, ca: f64, cb: f64) -> f64 {
        let p = self.p;
        let cap = 0.5 * p.max_window_m;
        let target = p.d_safe() + 0.5 * p.margin_m;
        let step = (0.5 * self.world.resolution()).max(0.5 * p.margin_m);
        // A heuristic for the window's size: points a quarter metre apart are enough.
        let n = (((cb - ca) / p.spacing_m.max(0.25)).ceil() as usize).max(1);
        let mut need = [0.0f64; 2];
        for j in 0..=n {
            let s = ca + (cb - ca) * j as f64 / n as f64;
            let pos = self.arc.pos_at(s);
            let (a, b) = (
                self.arc.path[pos.seg],
                self.arc.path[(pos.seg + 1).min(self.arc.path.len() - 1)],
            );
            let d = b - a;
            let len = d.norm();
            if len <= 0.0 {
                continue;
            }
            let normal = nalgebra::Vector2::new(-d.y, d.x) / len;
            let q = self.arc.point(pos);
            for (k, side) in [1.0, -1.0].into_iter().enumerate() {
                let mut o = 0.0;
                loop {
                    let c = self.world.clearance_fast(q + normal * (side * o));
                    if c >= target || o > cap {
                        break;
                    }
                    o += (target - c).max(step);
                }
                need[k] = need[k].max(o.min(cap));
            }
        }
        need[0].min(need[1])
    }

    /// The windows to try, longest last, and the end of the non-compliant core.
    fn windows(&self, s_a: f64, s_b: f64) -> Result<Plan, CorrectError> {
        let p = self.p;
        let total = self.arc.total();
        // The whole non-compliant stretch around the breach (judging may have clipped it at its circle).
        let ca = self.to_compliant(s_a, -1.0, self.s_e, s_a);
        let cb = self.to_compliant(s_b, 1.0, s_b, (s_b + p.max_window_m).min(total));
        let core = cb - ca;
        // Adaptive start: the patch leaves the path at about 45° (the lateral starts' tent), so the window
        // must extend past the core by at least the sideways distance that clears it.
        let base = (3.0 * p.d_safe())
            .max(1.0)
            .max(4.0 * p.spacing_m)
            .max(1.25 * self.lateral_need(ca, cb) + p.spacing_m);
        let mut exts = vec![base];
        while core + 2.0 * exts[exts.len() - 1] * 1.6 < p.max_window_m {
            let e = exts[exts.len() - 1] * 1.6;
            exts.push(e);
        }
        let last = 0.5 * (p.max_window_m - core);
        if last > exts[exts.len() - 1] {
            exts.push(last);
        }
        let mut windows: Vec<(f64, f64)> = Vec::new();
        for e in exts {
            let s0 = self.to_compliant((ca - e).max(self.s_e), -1.0, self.s_e, total);
            let s1 = self.to_compliant((cb + e).min(total), 1.0, 0.0, total);
            if windows.last().is_none_or(|w| w.0 != s0 || w.1 != s1) {
                windows.push((s0, s1));
            }
        }
        // The skip starts from the latest clear start anchor; when none is clear the robot's own stretch is
        // in collision and nothing can start there.
        let clear = |s0: f64| self.world.clear_of(self.arc.point_at(s0), p.robot_radius_m);
        let Some(start) = windows.iter().map(|w| w.0).find(|&s0| clear(s0)) else {
            let s0 = windows.iter().map(|w| w.0).fold(f64::INFINITY, f64::min);
            let a = self.arc.point_at(s0);
            return Err(CorrectError::AnchorInCollision {
                x: a.x,
                y: a.y,
                clearance_m: if self.world.inside(a) {
                    self.world.clearance_upto(a, p.robot_radius_m)
                } else {
                    0.0
                },
            });
        };
        let usable: Vec<Window> = windows
            .iter()
            .filter_map(|&(s0, s1)| Window::new(&self.arc, s0, s1, p.spacing_m))
            .filter(|w| {
                w.head
                    .iter()
                    .chain(&w.tail)
                    .all(|q| self.world.clear_of(*q, p.robot_radius_m))
            })
            .collect();
        Ok(Plan {
            start,
            core_end: cb,
            usable,
            iterations: 0,
            costs: None,
        })
    }

    /// IKD-SWOpt over the plan's windows.
    fn optimise(&self, plan: &mut Plan) -> Option<Repair> {
        let p = self.p;
        self.optimise_with(plan, &mut |cost, x0| {
            minimize(cost, x0, p.max_iterations, MEMORY, G_TOL, F_REL_TOL)
        })
    }

    /// IKD-SWOpt over the plan's windows, minimising with `solve`.
    fn optimise_with<S>(&self, plan: &mut Plan, solve: &mut S) -> Option<Repair>
    where
        S: for<'c, 'l> FnMut(&mut WindowCost<'c, LocalObstacles<'l, 'w>>, &[f64]) -> Minimum,
    {
        let p = self.p;
        for win in &plan.usable {
            let (lo, hi) = bbox(&win.with_free(&win.free));
            let reach = 0.5 * (win.s1 - win.s0) + p.d_safe() + p.margin_m;
            let pad = Point2::new(reach, reach).coords;
            let local = LocalObstacles::new(self.world, lo - pad, hi + pad, p.d_safe() + p.margin_m);
            let opt = optimise_window_with(win, &local, self.world, p, solve);
            plan.iterations += opt.iterations;
            if plan.costs.is_none() {
                plan.costs = Some((opt.cost_before, opt.cost_after));
            }
            if opt.feasible {
                return Some(self.patch(
                    win.s0,
                    win.s1,
                    opt.points,
                    RepairKind::Optimised,
                    plan.iterations,
                    (opt.cost_before, opt.cost_after),
                ));
            }
        }
        None
    }

    /// A* detours over the plan's windows.
    fn detour(&self, plan: &mut Plan) -> Option<Repair> {
        let before = plan.costs.map_or(0.0, |c| c.0);
        for win in &plan.usable {
            if let Some(points) = self.detour_window(win) {
                let after = self.polyline_cost(&points, win.h);
                return Some(self.patch(
                    win.s0,
                    win.s1,
                    points,
                    RepairKind::Detour,
                    plan.iterations,
                    (before, after),
                ));
            }
        }
        None
    }

    /// The repair for a patch from arc length s0 to s1.
    fn patch(
        &self,
        s0: f64,
        s1: f64,
        waypoints: Vec<Point2>,
        kind: RepairKind,
        iterations: u32,
        (cost_before, cost_after): (f64, f64),
    ) -> Repair {
        let (from, to) = self.range(s0, s1);
        let skipped = if kind == RepairKind::Skipped {
            self.arc.slice(s0, s1)
        } else {
            Vec::new()
        };
        Repair {
            from,
            to,
            waypoints,
            kind,
            iterations,
            cost_before,
            cost_after,
            skipped,
            escape: None,
        }
    }

    /// The replaced waypoint range for a patch from arc length s0 to s1.
    fn range(&self, s0: f64, s1: f64) -> (usize, usize) {
        let n = self.arc.path.len();
        let k0 = start_segment(&self.arc, s0);
        let from = if s0 <= self.arc.s[k0] { k0 } else { k0 + 1 };
        let k1 = end_segment(&self.arc, s1);
        let to = if s1 >= self.arc.total() { n } else { k1 + 1 };
        (from.min(n), to.clamp(from.min(n), n))
    }

    /// J (eq. 18) of a polyline resampled at spacing about `h`, its two first and last points fixed.
    fn polyline_cost(&self, points: &[Point2], h: f64) -> f64 {
        let arc = Arclen::new(points);
        let Some(win) = Window::new(&arc, 0.0, arc.total(), h) else {
            return 0.0;
        };
        let mut c = WindowCost::new(win.head, win.tail, weights(self.p, win.h), self.world, win.free.len());
        let x: Vec<f64> = win.free.iter().flat_map(|q| [q.x, q.y]).collect();
        c.value(&x)
    }

    /// A* detour over a window: anchor, heading neighbour, shortcut cell path, heading neighbour, anchor.
    fn detour_window(&self, win: &Window) -> Option<Vec<Point2>> {
        let r = self.p.robot_radius_m;
        let orig = self.arc.slice(win.s0, win.s1);
        let (lo, hi) = bbox(&orig);
        let pad = (0.5 * (win.s1 - win.s0)).clamp(1.0, 4.0);
        let pad = Point2::new(pad, pad).coords;
        let grid = LocalGrid::build(self.world, lo - pad, hi + pad, r, DETOUR_MAX_CELLS)?;
        let start = grid.free_cell(win.head[1])?;
        let goal = grid.free_cell(win.tail[0])?;
        let cells = grid.astar(start, goal)?;
        let points = shortcut_chain(&win.head, &cells, &win.tail, self.world, r);
        verify(&points, self.world, r).then_some(points)
    }

    /// The skip: transit from the start anchor to the first point after the blocked stretch the robot can
    /// reach, or stop at the anchor.
    fn skip(&self, plan: &Plan) -> Repair {
        let (s0, cb) = (plan.start, plan.core_end);
        let iterations = plan.iterations;
        let cost_before = plan.costs.map_or(0.0, |c| c.0);
        let r = self.p.robot_radius_m;
        let total = self.arc.total();
        let a0 = self.arc.point_at(s0);
        let stop = |me: &Self| me.patch(s0, total, vec![a0], RepairKind::Skipped, iterations, (cost_before, 0.0));
        let s_end = (cb + self.p.skip_search_m).min(total);
        if s_end <= cb {
            return stop(self);
        }
        let (lo, hi) = bbox(&self.arc.slice(s0, s_end));
        let pad = Point2::new(1.0, 1.0).coords;
        let Some(grid) = LocalGrid::build(self.world, lo - pad, hi + pad, r, SKIP_MAX_CELLS) else {
            return stop(self);
        };
        let Some(start) = grid.free_cell(a0) else {
            return stop(self);
        };
        let reach = grid.reachable(start);
        let step = self.h.max(0.5 * grid.geo.resolution);
        let mut s = cb;
        while s <= s_end {
            let q = self.arc.point_at(s);
            if let Some(cell) = grid.free_cell(q)
                && reach[cell]
                && self.world.clear_of(q, r)
                && segment_clear(grid.geo.center_of(cell), q, self.world, r)
                && let Some(cells) = grid.astar(start, cell)
            {
                let points = shortcut_chain(&[a0], &cells, &[q], self.world, r);
                if verify(&points, self.world, r) {
                    let after = self.polyline_cost(&points, self.p.spacing_m);
                    let mut rep = self.patch(s0, s, points, RepairKind::Skipped, iterations, (cost_before, after));
                    if s >= total {
                        rep.to = self.arc.path.len();
                    }
                    return rep;
                }
            }
            s += step;
        }
        stop(self)
    }
}

/// Axis-aligned bounds of points.
fn bbox(points: &[Point2]) -> (Point2, Point2) {
    let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
    let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    for q in points {
        lo = Point2::new(lo.x.min(q.x), lo.y.min(q.y));
        hi = Point2::new(hi.x.max(q.x), hi.y.max(q.y));
    }
    (lo, hi)
}

/// Test hook: the windows of a repair and what optimising each gave (s0, s1, iterations, feasible).
#[cfg(test)]
pub(crate) fn trace_windows(
    path: &[Point2],
    breach: &Breach,
    world: &World<'_>,
    p: &CorrectParams,
) -> Vec<(f64, f64, u32, bool, f64, f64)> {
    let Ok((r, s_a, s_b)) = prepare(path, breach, world, p) else {
        return Vec::new();
    };
    let t = std::time::Instant::now();
    let Ok(plan) = r.windows(s_a, s_b) else {
        return Vec::new();
    };
    println!("    windows() {:?}", t.elapsed());
    plan.usable
        .iter()
        .map(|win| {
            let t = std::time::Instant::now();
            let (lo, hi) = bbox(&win.with_free(&win.free));
            let reach = 0.5 * (win.s1 - win.s0) + p.d_safe() + p.margin_m;
            let pad = Point2::new(reach, reach).coords;
            let local = LocalObstacles::new(world, lo - pad, hi + pad, p.d_safe() + p.margin_m);
            println!("    local cache {:?}", t.elapsed());
            let t = std::time::Instant::now();
            let o = super::optimize::optimise_window(win, &local, world, p);
            println!("    optimise_window {:?}", t.elapsed());
            let t = std::time::Instant::now();
            let _ = verify(&o.points, world, p.robot_radius_m);
            println!("    verify {:?}", t.elapsed());
            let t = std::time::Instant::now();
            let mut cost = super::cost::WindowCost::new(win.head, win.tail, weights(p, win.h), &local, win.free.len());
            let x: Vec<f64> = win.free.iter().flat_map(|q| [q.x, q.y]).collect();
            for _ in 0..100 {
                let _ = cost.value(&x);
            }
            println!("    eval (local) x100 {:?}", t.elapsed());
            let t = std::time::Instant::now();
            let mut cost = super::cost::WindowCost::new(win.head, win.tail, weights(p, win.h), world, win.free.len());
            for _ in 0..100 {
                let _ = cost.value(&x);
            }
            println!("    eval (world) x100 {:?}", t.elapsed());
            (win.s0, win.s1, o.iterations, o.feasible, o.cost_before, o.cost_after)
        })
        .collect()
}
