//! A heading lattice for a robot that drives forward and turns in place, every pose decided by its footprint
//! ([`super::FootprintCheck`]): weighted A* from a pose to a point (and a heading there, if asked).
//!
//! States are the start position moved by whole grid steps, with one of 48 headings: the directions of the
//! grid steps (dx, dy) with |dx|, |dy| ≤ 4 and no common factor (0°, 14°, 18.4°, 26.6°, 33.7°, 36.9°, 45°, …),
//! so a forward move along a heading lands exactly on the lattice. Moves: one such step forward, or a turn in
//! place to the next heading either way (costed by the angle, plus a small penalty per turn). The goal is
//! off the lattice: a state within [`LatticeParams::shot_range_m`] of it tries the straight shot — turn to
//! face the goal, drive to it, turn to the goal heading. The heuristic is the grid distance to the goal over
//! cells where the inscribed disc fits ([`super::guide`]), which also prunes every cell that cannot reach it.
//! A doorway the robot fits through only lengthwise is passed heading through it because only such poses are
//! clear. The path returned is checked again pose by pose ([`super::FootprintCheck::path_free`]).

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use super::check::FootprintCheck;
use super::guide::Guide;
use super::poses::{segment_heading, wrap_angle};
use crate::geom::{Point2, Vector2};

/// Knobs of the lattice search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeParams {
    /// States expanded before the search gives up.
    pub max_expansions: usize,
    /// The search stays within the box round start and goal grown by this much, metres.
    pub window_margin_m: f64,
    /// Cost of turning in place, metres of driving per radian.
    pub turn_cost_m_per_rad: f64,
    /// Extra cost of each turn step, metres (fewer, larger turns).
    pub turn_penalty_m: f64,
    /// Weight of the heuristic (1 = A*; more = faster, longer paths).
    pub heuristic_weight: f64,
    /// States this close to the goal (grid distance, metres) try the straight shot to it.
    pub shot_range_m: f64,
}

impl Default for LatticeParams {
    fn default() -> Self {
        Self {
            max_expansions: 60_000,
            window_margin_m: 2.5,
            turn_cost_m_per_rad: 0.3,
            turn_penalty_m: 0.05,
            heuristic_weight: 1.5,
            shot_range_m: 3.0,
        }
    }
}

/// The lattice's grid steps, counter-clockwise from +x: (dx, dy) with |dx|, |dy| ≤ 4 and no common factor.
pub fn lattice_steps() -> Vec<(i32, i32)> {
    fn gcd(a: i32, b: i32) -> i32 {
        if b == 0 { a } else { gcd(b, a % b) }
    }
    let mut steps: Vec<(i32, i32)> = (-4..=4)
        .flat_map(|dx: i32| (-4..=4).map(move |dy: i32| (dx, dy)))
        .filter(|&(dx, dy)| (dx, dy) != (0, 0) && gcd(dx.abs(), dy.abs()) == 1)
        .collect();
    steps.sort_by(|a, b| {
        let angle = |s: &(i32, i32)| f64::from(s.1).atan2(f64::from(s.0)).rem_euclid(std::f64::consts::TAU);
        angle(a).total_cmp(&angle(b))
    });
    steps
}

/// A searched state: grid steps from the start and a heading index.
type Key = u64;
const OFFSET: i64 = 1 << 23;

fn key(i: i64, j: i64, k: usize) -> Key {
    (((i + OFFSET) as u64) << 32) | (((j + OFFSET) as u64) << 8) | k as u64
}

fn unkey(key: Key) -> (i64, i64, usize) {
    (
        (key >> 32) as i64 - OFFSET,
        ((key >> 8) & 0xFF_FFFF) as i64 - OFFSET,
        (key & 0xFF) as usize,
    )
}

#[derive(Debug, Clone, Copy)]
struct Node {
    g: f64,
    parent: Option<Key>,
    closed: bool,
}

/// A path for the footprint from `from` (at heading `from_yaw`, or free to start at any heading) to `to`
/// (turning there to `to_yaw` when given): the polyline the robot drives forward, turning in place at its
/// vertices, starting at `from` and ending at `to`. `None` when the search finds none within its bounds.
pub fn connect(
    check: &FootprintCheck<'_>,
    from: Point2,
    from_yaw: Option<f64>,
    to: Point2,
    to_yaw: Option<f64>,
    params: &LatticeParams,
) -> Option<Vec<Point2>> {
    if (to - from).norm() < 1e-9 {
        let ok = match (from_yaw, to_yaw) {
            (Some(a), Some(b)) => check.rotation_free(from.x, from.y, a, b),
            (None, Some(b)) => check.pose_free(from.x, from.y, b),
            _ => true,
        };
        return ok.then(|| vec![from]);
    }
    if shot(check, from, from_yaw, to, to_yaw) {
        return Some(vec![from, to]);
    }
    let fp = check.footprint();
    let res = check.grid().geometry.resolution;
    let margin = Vector2::new(params.window_margin_m, params.window_margin_m);
    let lo = Point2::new(from.x.min(to.x), from.y.min(to.y)) - margin;
    let hi = Point2::new(from.x.max(to.x), from.y.max(to.y)) + margin;
    // A clear pose keeps its inscribed disc off every blocked square, so its centre is more than
    // inscribed + half a cell from every blocked centre, and its cell's centre half a diagonal less.
    let open = fp.inscribed_radius_m() + res / 2.0 - res * std::f64::consts::FRAC_1_SQRT_2 - 1e-9;
    let guide = Guide::toward(check.clearance_field(), to, lo, hi, open)?;
    if guide.at(from).is_infinite() {
        return None;
    }
    Search {
        check,
        from,
        to,
        to_yaw,
        res,
        steps: lattice_steps(),
        guide,
        params,
        nodes: HashMap::new(),
        heap: BinaryHeap::new(),
        shots: HashMap::new(),
    }
    .run(from_yaw)
}

/// True when the robot can turn at `from` to face `to`, drive there and turn to `to_yaw`.
fn shot(check: &FootprintCheck<'_>, from: Point2, from_yaw: Option<f64>, to: Point2, to_yaw: Option<f64>) -> bool {
    let Some(phi) = segment_heading(from, to) else {
        return false;
    };
    let start_ok = match from_yaw {
        Some(y) => check.rotation_free(from.x, from.y, y, phi),
        None => check.pose_free(from.x, from.y, phi),
    };
    start_ok && check.segment_free(from, to) && to_yaw.is_none_or(|e| check.rotation_free(to.x, to.y, phi, e))
}

struct Search<'s, 'c> {
    check: &'s FootprintCheck<'c>,
    from: Point2,
    to: Point2,
    to_yaw: Option<f64>,
    res: f64,
    steps: Vec<(i32, i32)>,
    guide: Guide,
    params: &'s LatticeParams,
    nodes: HashMap<Key, Node>,
    heap: BinaryHeap<(Reverse<u64>, Key)>,
    /// Per lattice position: the drive to the goal and the turn there are clear.
    shots: HashMap<(i64, i64), bool>,
}

impl Search<'_, '_> {
    fn position(&self, i: i64, j: i64) -> Point2 {
        self.from + Vector2::new(i as f64, j as f64) * self.res
    }

    fn angle(&self, k: usize) -> f64 {
        let (dx, dy) = self.steps[k];
        f64::from(dy).atan2(f64::from(dx))
    }

    fn relax(&mut self, to: Key, g: f64, parent: Option<Key>) {
        let (i, j, _) = unkey(to);
        let h = self.guide.at(self.position(i, j));
        if !h.is_finite() {
            return;
        }
        match self.nodes.get_mut(&to) {
            Some(n) if n.closed || n.g <= g => return,
            Some(n) => {
                n.g = g;
                n.parent = parent;
            }
            None => {
                self.nodes.insert(
                    to,
                    Node {
                        g,
                        parent,
                        closed: false,
                    },
                );
            }
        }
        let f = g + self.params.heuristic_weight * h;
        self.heap.push((Reverse(f.max(0.0).to_bits()), to));
    }

    fn turn_cost(&self, delta: f64) -> f64 {
        if delta.abs() < 1e-12 {
            0.0
        } else {
            self.params.turn_cost_m_per_rad * delta.abs() + self.params.turn_penalty_m
        }
    }

    fn run(mut self, from_yaw: Option<f64>) -> Option<Vec<Point2>> {
        let n = self.steps.len();
        let f = self.from;
        let (ccw, cw) = from_yaw.map_or((0.0, 0.0), |y| self.check.free_turn_arcs(f.x, f.y, y));
        for k in 0..n {
            let theta = self.angle(k);
            match from_yaw {
                None => {
                    if self.check.pose_free(f.x, f.y, theta) {
                        self.relax(key(0, 0, k), 0.0, None);
                    }
                }
                Some(y) => {
                    let delta = wrap_angle(theta - y);
                    if (delta >= 0.0 && delta <= ccw) || (delta < 0.0 && -delta <= cw) {
                        let c = self.turn_cost(delta);
                        self.relax(key(0, 0, k), c, None);
                    }
                }
            }
        }
        let mut expansions = 0;
        while let Some((_, at)) = self.heap.pop() {
            let Some(node) = self.nodes.get_mut(&at) else { continue };
            if node.closed {
                continue;
            }
            node.closed = true;
            let g = node.g;
            expansions += 1;
            if expansions > self.params.max_expansions {
                return None;
            }
            let (i, j, k) = unkey(at);
            let p = self.position(i, j);
            let theta = self.angle(k);
            if self.guide.at(p) <= self.params.shot_range_m && self.shot_from(i, j, theta) {
                return self.path_to(at, from_yaw);
            }
            let (dx, dy) = self.steps[k];
            let (ni, nj) = (i + i64::from(dx), j + i64::from(dy));
            let q = self.position(ni, nj);
            if self.guide.at(q).is_finite() && self.check.segment_free(p, q) {
                let len = f64::from(dx).hypot(f64::from(dy)) * self.res;
                self.relax(key(ni, nj, k), g + len, Some(at));
            }
            for nk in [(k + 1) % n, (k + n - 1) % n] {
                let to = self.angle(nk);
                if self.check.rotation_free(p.x, p.y, theta, to) {
                    let c = self.turn_cost(wrap_angle(to - theta));
                    self.relax(key(i, j, nk), g + c, Some(at));
                }
            }
        }
        None
    }

    /// The straight shot from lattice position (`i`, `j`) at heading `theta` to the goal.
    fn shot_from(&mut self, i: i64, j: i64, theta: f64) -> bool {
        let p = self.position(i, j);
        let Some(phi) = segment_heading(p, self.to) else {
            return false;
        };
        let (check, to, to_yaw) = (self.check, self.to, self.to_yaw);
        let drive = *self.shots.entry((i, j)).or_insert_with(|| {
            check.segment_free(p, to) && to_yaw.is_none_or(|e| check.rotation_free(to.x, to.y, phi, e))
        });
        drive && check.rotation_free(p.x, p.y, theta, phi)
    }

    /// The polyline from the start to the goal through state `last`, straight runs merged, checked again.
    fn path_to(&self, last: Key, from_yaw: Option<f64>) -> Option<Vec<Point2>> {
        let mut keys = vec![last];
        while let Some(parent) = self.nodes.get(keys.last()?).and_then(|n| n.parent) {
            keys.push(parent);
        }
        let mut pts: Vec<Point2> = Vec::with_capacity(keys.len() + 1);
        for &k in keys.iter().rev() {
            let (i, j, _) = unkey(k);
            let p = self.position(i, j);
            if pts.last().is_none_or(|l| (p - l).norm() > 1e-9) {
                pts.push(p);
            }
        }
        pts.push(self.to);
        let merged = merge_straight(&pts);
        if self.check.path_free(&merged, from_yaw, self.to_yaw) {
            return Some(merged);
        }
        self.check.path_free(&pts, from_yaw, self.to_yaw).then_some(pts)
    }
}

/// `pts` without the vertices where the heading does not change.
fn merge_straight(pts: &[Point2]) -> Vec<Point2> {
    let mut out: Vec<Point2> = Vec::with_capacity(pts.len());
    for &p in pts {
        if out.len() >= 2 {
            let (a, b) = (out[out.len() - 2], out[out.len() - 1]);
            if let (Some(h0), Some(h1)) = (segment_heading(a, b), segment_heading(b, p))
                && wrap_angle(h1 - h0).abs() < 1e-9
            {
                out.pop();
            }
        }
        out.push(p);
    }
    out
}
