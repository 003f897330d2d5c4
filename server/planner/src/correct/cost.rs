//! The window cost of IKD-SWOpt (seed 000 eq. 18) with its analytic gradient:
//!
//! `J = w_len·J_len + w_smooth·J_smooth + w_obs·J_obs` over the window's points `P_0 … P_{n+3}` (two fixed
//! points at each end, `n` free points between, spacing `h` metres):
//!
//! - `J_len = Σ |P_{i+1} − P_i|² / h` — metres; equals the length for evenly spaced points and is smallest
//!   for a straight, evenly spaced window;
//! - `J_smooth = Σ |P_{i+1} − 2 P_i + P_{i−1}|² / h³` — 1/m; the discrete ∫ κ² ds;
//! - `J_obs = Σ_free h · (max(0, d_safe − c(P_i)) / margin)²` — metres; c the clearance from
//!   [`Obstacles::nearest`], with ∂c/∂P = (P − q) / |P − q| for the nearest obstacle point q.
//!
//! J_len and J_smooth are quadratic with a constant pentadiagonal Hessian per coordinate
//! (`2/h · tridiag(−1, 2, −1)` and `2/h³ · [1, −4, 6, −4, 1]`); J_obs adds `2·h / margin²` along the
//! obstacle normal of every point in the hinge. That matrix is the L-BFGS preconditioner.

use crate::geom::{Point2, Vector2};

use super::lbfgs::{BandChol, Objective};
use super::world::World;

/// The nearest obstacle point of a map-frame point, with its distance (metres).
pub(crate) trait Obstacles {
    /// Nearest obstacle point of `p` and its distance; `None` when there is none.
    fn nearest(&self, p: Point2) -> Option<(Point2, f64)>;
}

impl Obstacles for World<'_> {
    #[inline]
    fn nearest(&self, p: Point2) -> Option<(Point2, f64)> {
        self.nearest_obstacle(p)
    }
}

/// Weights and geometry of one window's cost.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Weights {
    pub(crate) w_len: f64,
    pub(crate) w_smooth: f64,
    pub(crate) w_obs: f64,
    pub(crate) d_safe: f64,
    pub(crate) margin: f64,
    /// Point spacing, metres.
    pub(crate) h: f64,
}

/// The cost of a window with fixed `head` (P_0, P_1) and `tail` (P_{n+2}, P_{n+3}); the free points are
/// the variables, interleaved `[x_0, y_0, x_1, y_1, …]`.
pub(crate) struct WindowCost<'o, O: Obstacles> {
    pub(crate) head: [Point2; 2],
    pub(crate) tail: [Point2; 2],
    pub(crate) w: Weights,
    pub(crate) obstacles: &'o O,
    /// Unit obstacle normal of each free point in the obstacle hinge at the last evaluation.
    contact: Vec<Option<Vector2>>,
    band: BandChol,
    pts: Vec<Point2>,
}

impl<'o, O: Obstacles> WindowCost<'o, O> {
    pub(crate) fn new(head: [Point2; 2], tail: [Point2; 2], w: Weights, obstacles: &'o O, n: usize) -> Self {
        Self {
            head,
            tail,
            w,
            obstacles,
            contact: vec![None; n],
            band: BandChol::default(),
            pts: Vec::with_capacity(n + 4),
        }
    }

    /// J of variables `x` without the gradient.
    pub(crate) fn value(&mut self, x: &[f64]) -> f64 {
        let mut g = vec![0.0; x.len()];
        self.eval(x, &mut g)
    }

    /// Factors H₀: the quadratic terms' Hessian on both coordinates (interleaved, bandwidth 4) plus
    /// `2·w_obs·h/margin² · n nᵀ` for every point in the hinge, and a small ridge. False when not positive
    /// definite (then no preconditioning).
    fn refactor(&mut self) -> bool {
        let n = self.contact.len();
        let w = &self.w;
        let a = 2.0 * w.w_len / w.h;
        let b = 2.0 * w.w_smooth / w.h.powi(3);
        let k_obs = 2.0 * w.w_obs * w.h / (w.margin * w.margin);
        let reg = 1e-3 * k_obs + 1e-9 * (a + b);
        self.band.reset(2 * n, 4);
        for v in 0..n {
            for c in 0..2 {
                let i = 2 * v + c;
                self.band.add(i, i, 2.0 * a + 6.0 * b + reg);
                if v >= 1 {
                    self.band.add(i, i - 2, -a - 4.0 * b);
                }
                if v >= 2 {
                    self.band.add(i, i - 4, b);
                }
            }
            if let Some(nv) = self.contact[v] {
                let i = 2 * v;
                self.band.add(i, i, k_obs * nv.x * nv.x);
                self.band.add(i + 1, i + 1, k_obs * nv.y * nv.y);
                self.band.add(i + 1, i, k_obs * nv.x * nv.y);
            }
        }
        self.band.factor()
    }
}

impl<O: Obstacles> Objective for WindowCost<'_, O> {
    fn eval(&mut self, x: &[f64], g: &mut [f64]) -> f64 {
        let w = self.w;
        let mut pts = std::mem::take(&mut self.pts);
        pts.clear();
        pts.extend_from_slice(&self.head);
        pts.extend(x.chunks_exact(2).map(|c| Point2::new(c[0], c[1])));
        pts.extend_from_slice(&self.tail);
        g.iter_mut().for_each(|v| *v = 0.0);
        let n_pts = pts.len();
        // Gradient w.r.t. point i lands in g[2(i−2)..] when point i is free (2 ≤ i < n_pts − 2).
        let free = |i: usize| i >= 2 && i + 2 < n_pts;
        let add = |g: &mut [f64], i: usize, vx: f64, vy: f64| {
            if free(i) {
                g[2 * (i - 2)] += vx;
                g[2 * (i - 2) + 1] += vy;
            }
        };
        let (cl, cs) = (w.w_len / w.h, w.w_smooth / w.h.powi(3));
        let mut f = 0.0;
        for i in 0..n_pts - 1 {
            let d = pts[i + 1] - pts[i];
            f += cl * d.norm_squared();
            add(g, i + 1, 2.0 * cl * d.x, 2.0 * cl * d.y);
            add(g, i, -2.0 * cl * d.x, -2.0 * cl * d.y);
        }
        for i in 1..n_pts - 1 {
            let dd = pts[i + 1] - 2.0 * pts[i].coords + pts[i - 1].coords;
            let dd = dd.coords;
            f += cs * dd.norm_squared();
            add(g, i - 1, 2.0 * cs * dd.x, 2.0 * cs * dd.y);
            add(g, i, -4.0 * cs * dd.x, -4.0 * cs * dd.y);
            add(g, i + 1, 2.0 * cs * dd.x, 2.0 * cs * dd.y);
        }
        let co = w.w_obs * w.h / (w.margin * w.margin);
        for (v, c) in self.contact.iter_mut().enumerate() {
            let p = pts[v + 2];
            *c = None;
            let Some((q, d)) = self.obstacles.nearest(p) else {
                continue;
            };
            let deficit = w.d_safe - d;
            if deficit <= 0.0 {
                continue;
            }
            f += co * deficit * deficit;
            if d > 1e-12 {
                *c = Some((p - q) / d);
                // d(deficit²)/dp = −2 deficit (p − q)/d.
                let k = -2.0 * co * deficit / d;
                g[2 * v] += k * (p.x - q.x);
                g[2 * v + 1] += k * (p.y - q.y);
            }
        }
        self.pts = pts;
        f
    }

    fn precondition(&mut self, v: &mut [f64]) {
        if self.refactor() {
            self.band.solve(v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Dots(Vec<Point2>);

    impl Obstacles for Dots {
        fn nearest(&self, p: Point2) -> Option<(Point2, f64)> {
            self.0
                .iter()
                .map(|q| (*q, (q - p).norm()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let obs = Dots(vec![Point2::new(0.5, 0.1), Point2::new(0.9, -0.2)]);
        let w = Weights {
            w_len: 1.0,
            w_smooth: 0.5,
            w_obs: 50.0,
            d_safe: 0.35,
            margin: 0.05,
            h: 0.1,
        };
        let head = [Point2::new(0.0, 0.0), Point2::new(0.1, 0.0)];
        let tail = [Point2::new(1.4, 0.0), Point2::new(1.5, 0.0)];
        let x: Vec<f64> = (2..14)
            .flat_map(|i| [i as f64 * 0.1, 0.03 * (i as f64).sin()])
            .collect();
        let mut c = WindowCost::new(head, tail, w, &obs, x.len() / 2);
        let mut g = vec![0.0; x.len()];
        c.eval(&x, &mut g);
        for i in 0..x.len() {
            let e = 1e-6;
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[i] += e;
            xm[i] -= e;
            let num = (c.value(&xp) - c.value(&xm)) / (2.0 * e);
            assert!(
                (num - g[i]).abs() < 1e-4 * (1.0 + num.abs()),
                "component {i}: {num} vs {}",
                g[i]
            );
        }
    }
}
