//! A small limited-memory BFGS minimiser with a banded preconditioner and a backtracking Armijo line search.
//!
//! Why our own and not `argmin`: the window problem has a known, banded (pentadiagonal) Hessian for its
//! quadratic terms (J_len, J_smooth) plus a diagonal stiffness from the active obstacle hinges. L-BFGS with
//! that matrix as its initial Hessian H₀ (applied through an O(n) banded Cholesky solve) starts from an exact
//! Newton step for the quadratic part, so it converges in a handful of iterations where a scalar-H₀ L-BFGS
//! needs dozens on a problem conditioned like spacing⁻⁴. argmin's L-BFGS takes only a scalar H₀ and boxes
//! every iterate in its state machinery; this one allocates its buffers once per call and nothing per
//! iteration. The `correct` criterion bench reports the optimiser's time per repair.

/// A smooth objective with a preconditioner.
pub(crate) trait Objective {
    /// f(x), writing ∇f(x) into `g` (same length as `x`).
    fn eval(&mut self, x: &[f64], g: &mut [f64]) -> f64;
    /// Replaces `v` by H₀⁻¹ v, H₀ a positive definite approximation of the Hessian at the last point
    /// evaluated (the current iterate when called).
    fn precondition(&mut self, v: &mut [f64]);
}

/// What a minimisation returned.
#[derive(Debug, Clone)]
pub(crate) struct Minimum {
    /// The best point found.
    pub(crate) x: Vec<f64>,
    /// f at `x`.
    pub(crate) f: f64,
    /// Iterations (accepted steps).
    pub(crate) iterations: u32,
}

/// Minimises `obj` from `x0` for at most `max_iterations` accepted steps. Monotone: f never increases, so
/// the result's f ≤ f(x0). Stops when the gradient's largest component falls below `g_tol`, when a step
/// decreases f by less than `f_rel_tol` relative, or when the line search finds no decrease.
pub(crate) fn minimize(
    obj: &mut impl Objective,
    x0: &[f64],
    max_iterations: u32,
    memory: usize,
    g_tol: f64,
    f_rel_tol: f64,
) -> Minimum {
    let n = x0.len();
    let mut x = x0.to_vec();
    let mut g = vec![0.0; n];
    let mut f = obj.eval(&x, &mut g);
    let mut iterations = 0;
    if n == 0 || !f.is_finite() {
        return Minimum { x, f, iterations };
    }
    let m = memory.max(1);
    let mut s_hist = vec![vec![0.0; n]; m];
    let mut y_hist = vec![vec![0.0; n]; m];
    let mut rho = vec![0.0; m];
    let mut alpha = vec![0.0; m];
    let (mut stored, mut head) = (0usize, 0usize);
    let mut d = vec![0.0; n];
    let mut x_new = vec![0.0; n];
    let mut g_new = vec![0.0; n];
    while iterations < max_iterations {
        if g.iter().fold(0.0f64, |a, v| a.max(v.abs())) < g_tol {
            break;
        }
        // Two-loop recursion: d = −H ∇f.
        d.copy_from_slice(&g);
        for k in 0..stored {
            let i = (head + m - 1 - k) % m;
            alpha[i] = rho[i] * dot(&s_hist[i], &d);
            axpy(-alpha[i], &y_hist[i], &mut d);
        }
        obj.precondition(&mut d);
        for k in (0..stored).rev() {
            let i = (head + m - 1 - k) % m;
            let beta = rho[i] * dot(&y_hist[i], &d);
            axpy(alpha[i] - beta, &s_hist[i], &mut d);
        }
        d.iter_mut().for_each(|v| *v = -*v);
        let mut slope = dot(&g, &d);
        if !(slope < 0.0) {
            // Not a descent direction (memory gone stale): restart from the preconditioned gradient.
            stored = 0;
            d.copy_from_slice(&g);
            obj.precondition(&mut d);
            d.iter_mut().for_each(|v| *v = -*v);
            slope = dot(&g, &d);
            if !(slope < 0.0) {
                break;
            }
        }
        // Backtracking Armijo line search from the full (Newton-like) step.
        let mut step = 1.0;
        let mut f_new = f64::INFINITY;
        let mut accepted = false;
        for _ in 0..30 {
            for i in 0..n {
                x_new[i] = x[i] + step * d[i];
            }
            f_new = obj.eval(&x_new, &mut g_new);
            if f_new.is_finite() && f_new <= f + 1e-4 * step * slope {
                accepted = true;
                break;
            }
            step *= 0.5;
        }
        if !accepted {
            // Leave the objective's state at the current iterate.
            obj.eval(&x, &mut g_new);
            break;
        }
        iterations += 1;
        // Curvature pair.
        let (s, y) = (&mut s_hist[head], &mut y_hist[head]);
        for i in 0..n {
            s[i] = x_new[i] - x[i];
            y[i] = g_new[i] - g[i];
        }
        let sy = dot(s, y);
        if sy > 1e-12 * dot(y, y).sqrt() * dot(s, s).sqrt() && sy > 0.0 {
            rho[head] = 1.0 / sy;
            head = (head + 1) % m;
            stored = (stored + 1).min(m);
        }
        let decrease = f - f_new;
        std::mem::swap(&mut x, &mut x_new);
        std::mem::swap(&mut g, &mut g_new);
        f = f_new;
        if decrease <= f_rel_tol * f.abs().max(1e-12) {
            break;
        }
    }
    Minimum { x, f, iterations }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[inline]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// A symmetric positive definite pentadiagonal matrix factored as L·Lᵀ (bandwidth 2), for O(n) solves.
#[derive(Debug, Clone, Default)]
pub(crate) struct Banded {
    /// L's diagonal, first and second sub-diagonal.
    l0: Vec<f64>,
    l1: Vec<f64>,
    l2: Vec<f64>,
}

impl Banded {
    /// Factors the matrix with diagonal `d0`, first off-diagonal `d1` (`d1[i]` = A[i][i+1]) and second
    /// off-diagonal `d2`. Returns false when it is not positive definite.
    pub(crate) fn factor(&mut self, d0: &[f64], d1: &[f64], d2: &[f64]) -> bool {
        let n = d0.len();
        self.l0.resize(n, 0.0);
        self.l1.resize(n, 0.0);
        self.l2.resize(n, 0.0);
        for i in 0..n {
            // Row i: A[i][i-2] = d2[i-2], A[i][i-1] = d1[i-1].
            let l2 = if i >= 2 { d2[i - 2] / self.l0[i - 2] } else { 0.0 };
            let l1 = if i >= 1 {
                let mut v = d1[i - 1];
                if i >= 2 {
                    v -= l2 * self.l1[i - 1];
                }
                v / self.l0[i - 1]
            } else {
                0.0
            };
            let diag = d0[i] - l1 * l1 - l2 * l2;
            if !(diag > 0.0) {
                return false;
            }
            self.l0[i] = diag.sqrt();
            self.l1[i] = l1; // L[i][i-1]
            self.l2[i] = l2; // L[i][i-2]
        }
        true
    }

    /// Size of the last factored matrix.
    pub(crate) fn l0_len(&self) -> usize {
        self.l0.len()
    }

    /// Solves A z = v in place, reading `v` with `stride` (entries `v[offset + stride·i]`).
    pub(crate) fn solve_strided(&self, v: &mut [f64], offset: usize, stride: usize) {
        let n = self.l0.len();
        let at = |i: usize| offset + stride * i;
        // Forward: L y = v.
        for i in 0..n {
            let mut s = v[at(i)];
            if i >= 1 {
                s -= self.l1[i] * v[at(i - 1)];
            }
            if i >= 2 {
                s -= self.l2[i] * v[at(i - 2)];
            }
            v[at(i)] = s / self.l0[i];
        }
        // Backward: Lᵀ z = y.
        for i in (0..n).rev() {
            let mut s = v[at(i)];
            if i + 1 < n {
                s -= self.l1[i + 1] * v[at(i + 1)];
            }
            if i + 2 < n {
                s -= self.l2[i + 2] * v[at(i + 2)];
            }
            v[at(i)] = s / self.l0[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f = Σ a_i (x_i − 1)² + coupling, preconditioned by a banded approximation.
    struct Quad {
        band: Banded,
        n: usize,
    }

    impl Objective for Quad {
        fn eval(&mut self, x: &[f64], g: &mut [f64]) -> f64 {
            // A = tridiag(-1, 3, -1) + 0.5 I plus a quartic term.
            let mut f = 0.0;
            for i in 0..self.n {
                let xi = x[i] - 1.0;
                let left = if i > 0 { x[i - 1] - 1.0 } else { 0.0 };
                let right = if i + 1 < self.n { x[i + 1] - 1.0 } else { 0.0 };
                let ax = 3.5 * xi - left - right;
                f += 0.5 * xi * ax + 0.25 * xi.powi(4);
                g[i] = ax + xi.powi(3);
            }
            f
        }
        fn precondition(&mut self, v: &mut [f64]) {
            self.band.solve_strided(v, 0, 1);
        }
    }

    #[test]
    fn banded_solve_matches_dense() {
        let n = 7;
        let d0: Vec<f64> = (0..n).map(|i| 6.0 + i as f64 * 0.1).collect();
        let d1 = vec![-4.0; n - 1];
        let d2 = vec![1.0; n - 2];
        let mut b = Banded::default();
        assert!(b.factor(&d0, &d1, &d2));
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut z = rhs.clone();
        b.solve_strided(&mut z, 0, 1);
        for i in 0..n {
            let mut az = d0[i] * z[i];
            if i >= 1 {
                az += d1[i - 1] * z[i - 1];
            }
            if i + 1 < n {
                az += d1[i] * z[i + 1];
            }
            if i >= 2 {
                az += d2[i - 2] * z[i - 2];
            }
            if i + 2 < n {
                az += d2[i] * z[i + 2];
            }
            assert!((az - rhs[i]).abs() < 1e-10);
        }
    }

    #[test]
    fn converges_on_a_coupled_problem() {
        let n = 20;
        let mut band = Banded::default();
        assert!(band.factor(&vec![3.5; n], &vec![-1.0; n - 1], &vec![0.0; n - 2]));
        let mut q = Quad { band, n };
        let x0 = vec![-2.0; n];
        let mut g = vec![0.0; n];
        let f0 = q.eval(&x0, &mut g);
        let m = minimize(&mut q, &x0, 100, 6, 1e-10, 0.0);
        assert!(m.f <= f0);
        assert!(m.x.iter().all(|v| (v - 1.0).abs() < 1e-6), "{:?}", m.x);
        assert!(m.iterations < 30);
    }
}
