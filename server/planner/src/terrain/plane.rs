//! Weighted least-squares plane fits z ≈ a + b·dx + c·dy around a cell (gap filling, slope, roughness).

use nalgebra::{Matrix3, Vector3};

/// A plane fitted to samples given relative to a centre point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneFit {
    /// Height of the plane at the centre, metres.
    pub height: f64,
    /// Gradient (∂z/∂x, ∂z/∂y), dimensionless.
    pub gradient: [f64; 2],
    /// Root mean square of the unweighted residuals z − plane, metres.
    pub rms_residual: f64,
    /// False when the support was too thin for a plane and the weighted mean was taken instead.
    pub planar: bool,
}

impl PlaneFit {
    /// Slope of the plane from the horizontal, radians.
    pub fn slope_rad(&self) -> f64 {
        self.gradient[0].hypot(self.gradient[1]).atan()
    }
}

/// Fits a plane to samples `[dx, dy, z, weight]` (metres from the centre, metres, weight > 0). Returns `None`
/// for no sample; a support too thin for a plane (fewer than 3 points, or all on one line) gives the weighted
/// mean with a zero gradient.
pub fn fit_plane(samples: &[[f64; 4]]) -> Option<PlaneFit> {
    let sw: f64 = samples.iter().map(|s| s[3]).sum();
    if samples.is_empty() || sw <= 0.0 {
        return None;
    }
    // Normal equations in coordinates relative to the weighted centroid, which keeps them well conditioned.
    let mx = samples.iter().map(|s| s[3] * s[0]).sum::<f64>() / sw;
    let my = samples.iter().map(|s| s[3] * s[1]).sum::<f64>() / sw;
    let mz = samples.iter().map(|s| s[3] * s[2]).sum::<f64>() / sw;
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for s in samples {
        let (x, y, z, w) = (s[0] - mx, s[1] - my, s[2] - mz, s[3]);
        sxx += w * x * x;
        sxy += w * x * y;
        syy += w * y * y;
        sxz += w * x * z;
        syz += w * y * z;
    }
    let det = sxx * syy - sxy * sxy;
    let scale = (sxx + syy).powi(2);
    let solved = if samples.len() >= 3 && det > 1e-9 * scale && scale > 0.0 {
        let m = Matrix3::new(sw, 0.0, 0.0, 0.0, sxx, sxy, 0.0, sxy, syy);
        m.lu().solve(&Vector3::new(0.0, sxz, syz)).map(|sol| (sol[1], sol[2]))
    } else {
        None
    };
    let (b, c) = solved.unwrap_or((0.0, 0.0));
    let height = mz - b * mx - c * my;
    let rss: f64 = samples
        .iter()
        .map(|s| (s[2] - height - b * s[0] - c * s[1]).powi(2))
        .sum();
    Some(PlaneFit {
        height,
        gradient: [b, c],
        rms_residual: (rss / samples.len() as f64).sqrt(),
        planar: solved.is_some(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_plane_and_measures_residuals() {
        let mut s = Vec::new();
        for i in -2..=2 {
            for j in -2..=2 {
                let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
                s.push([x, y, 2.0 + 0.25 * x - 0.5 * y, 1.0 / (1.0 + x * x + y * y)]);
            }
        }
        let f = fit_plane(&s).expect("fit");
        assert!((f.height - 2.0).abs() < 1e-12);
        assert!((f.gradient[0] - 0.25).abs() < 1e-12 && (f.gradient[1] + 0.5).abs() < 1e-12);
        assert!(f.rms_residual < 1e-12 && f.planar);
        assert!((f.slope_rad() - 0.3125f64.sqrt().atan()).abs() < 1e-12);
        // ±0.1 m alternating noise: the residual RMS is 0.1 m.
        for (k, p) in s.iter_mut().enumerate() {
            p[3] = 1.0;
            p[2] += if k % 2 == 0 { 0.1 } else { -0.1 };
        }
        let f = fit_plane(&s).expect("fit");
        assert!((f.rms_residual - 0.1).abs() < 0.01, "{}", f.rms_residual);
    }

    #[test]
    fn thin_support_falls_back_to_the_mean() {
        assert_eq!(fit_plane(&[]), None);
        let line = [[0.0, 0.0, 1.0, 1.0], [1.0, 0.0, 2.0, 1.0], [2.0, 0.0, 3.0, 1.0]];
        let f = fit_plane(&line).expect("fit");
        assert_eq!(f.gradient, [0.0, 0.0]);
        assert!(!f.planar);
        assert!((f.height - 2.0).abs() < 1e-12);
    }
}
