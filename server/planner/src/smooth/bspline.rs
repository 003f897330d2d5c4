//! Clamped uniform B-spline curves in the plane (seed 000 eq. 20): C(u) = Σ P_i N_{i,k}(u), u ∈ [0, 1],
//! evaluated by de Boor's algorithm, with first and second derivatives from the derivative curves.

use crate::error::{PlannerError, Result};
use crate::geom::{Point2, Vector2};

/// A clamped B-spline of degree `k` over control points in the map frame (metres). The curve starts at the
/// first control point and ends at the last, tangent to the control polygon there.
#[derive(Debug, Clone, PartialEq)]
pub struct BSpline {
    degree: usize,
    knots: Vec<f64>,
    control: Vec<Vector2>,
}

impl BSpline {
    /// A clamped, uniformly knotted B-spline of `degree` (≥ 1) over `control` (at least degree + 1 points).
    pub fn clamped(control: &[Point2], degree: usize) -> Result<Self> {
        if degree == 0 || control.len() < degree + 1 {
            return Err(PlannerError::InvalidParam {
                name: "bspline",
                reason: format!(
                    "degree {degree} needs at least {} control points, got {}",
                    degree + 1,
                    control.len()
                ),
            });
        }
        let n = control.len();
        let inner = n - degree - 1;
        let mut knots = vec![0.0; degree + 1];
        knots.extend((1..=inner).map(|j| j as f64 / (inner + 1) as f64));
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Ok(Self {
            degree,
            knots,
            control: control.iter().map(|p| p.coords).collect(),
        })
    }

    /// The derivative curve (degree − 1), as a curve of vectors; `None` for degree 1's derivative of a
    /// derivative.
    fn derivative_curve(&self) -> Option<Self> {
        if self.degree == 0 {
            return None;
        }
        let k = self.degree;
        let control = (0..self.control.len() - 1)
            .map(|i| {
                let dt = self.knots[i + k + 1] - self.knots[i + 1];
                if dt > 0.0 {
                    (self.control[i + 1] - self.control[i]) * (k as f64 / dt)
                } else {
                    Vector2::zeros()
                }
            })
            .collect();
        Some(Self {
            degree: k - 1,
            knots: self.knots[1..self.knots.len() - 1].to_vec(),
            control,
        })
    }

    /// Point at parameter `u` (clamped to [0, 1]).
    pub fn point(&self, u: f64) -> Point2 {
        Point2::from(self.eval(u))
    }

    fn eval(&self, u: f64) -> Vector2 {
        let k = self.degree;
        let n = self.control.len();
        let u = if u.is_finite() { u.clamp(0.0, 1.0) } else { 0.0 };
        // Knot span s with knots[s] ≤ u < knots[s+1], the last span for u = 1.
        let mut s = k;
        while s + 1 < n && self.knots[s + 1] <= u {
            s += 1;
        }
        let mut d: Vec<Vector2> = (0..=k).map(|j| self.control[j + s - k]).collect();
        for r in 1..=k {
            for j in (r..=k).rev() {
                let i = j + s - k;
                let den = self.knots[i + k + 1 - r] - self.knots[i];
                let a = if den > 0.0 { (u - self.knots[i]) / den } else { 0.0 };
                d[j] = d[j - 1] * (1.0 - a) + d[j] * a;
            }
        }
        d[k]
    }

    /// Position, first and second derivative with respect to u at `u`.
    pub fn derivatives(&self, u: f64) -> (Point2, Vector2, Vector2) {
        let d1 = self.derivative_curve();
        let d2 = d1.as_ref().and_then(Self::derivative_curve);
        let first = d1.map_or_else(Vector2::zeros, |c| c.eval(u));
        let second = d2.map_or_else(Vector2::zeros, |c| {
            if c.control.is_empty() {
                Vector2::zeros()
            } else {
                c.eval(u)
            }
        });
        (self.point(u), first, second)
    }

    /// Unsigned curvature at `u`, 1/m (0 where the curve stalls).
    pub fn curvature(&self, u: f64) -> f64 {
        let (_, d1, d2) = self.derivatives(u);
        let speed = d1.norm();
        if speed < 1e-12 {
            return 0.0;
        }
        (d1.x * d2.y - d1.y * d2.x).abs() / (speed * speed * speed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_ends_and_straight_control_polygon() {
        let pts: Vec<Point2> = (0..6).map(|i| Point2::new(f64::from(i), 0.0)).collect();
        let c = BSpline::clamped(&pts, 3).expect("ok");
        assert!((c.point(0.0) - pts[0]).norm() < 1e-12);
        assert!((c.point(1.0) - pts[5]).norm() < 1e-12);
        for k in 0..=10 {
            let u = f64::from(k) / 10.0;
            assert!(c.point(u).y.abs() < 1e-12);
            assert!(c.curvature(u) < 1e-9);
        }
        assert!(BSpline::clamped(&pts[..3], 3).is_err());
    }

    #[test]
    fn quadratic_with_three_points_is_the_bezier() {
        let p = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0)];
        let c = BSpline::clamped(&p, 2).expect("ok");
        let m = c.point(0.5);
        assert!((m - Point2::new(0.75, 0.25)).norm() < 1e-12);
        let (_, d1, d2) = c.derivatives(0.5);
        assert!((d1 - Vector2::new(1.0, 1.0)).norm() < 1e-12);
        assert!((d2 - Vector2::new(-2.0, 2.0)).norm() < 1e-12);
        // Curvature of B(t) at 0.5: |(1,1)×(−2,2)| / |(1,1)|³ = 4 / 2^{1.5}.
        assert!((c.curvature(0.5) - 4.0 / 2f64.powf(1.5)).abs() < 1e-12);
    }

    #[test]
    fn cubic_matches_a_numeric_derivative() {
        let p = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(2.0, 1.0),
            Point2::new(2.0, 2.0),
            Point2::new(3.0, 3.0),
        ];
        let c = BSpline::clamped(&p, 3).expect("ok");
        for u in [0.1, 0.3, 0.5, 0.77] {
            let h = 1e-6;
            let num = (c.point(u + h) - c.point(u - h)) / (2.0 * h);
            let (_, d1, _) = c.derivatives(u);
            assert!((num - d1).norm() < 1e-5, "{u}: {num} vs {d1}");
        }
    }
}
