//! Curvature-based protrusion removal (seed 000 §IV.A.4).
//!
//! 1. Thresholds (eq. 9): K_th = μ_K + α σ_K and H_th = μ_H + β σ_H, with μ and σ taken over the magnitudes
//!    |K| and |H| (the test below compares magnitudes, so the statistics do too) of the measured cells not yet
//!    flagged, and never below the curvature of the smallest spike worth removing, one cell raised by
//!    [`SmoothParams::min_spike_cells`] · g over flat ground: H ≥ 2·min_spike_cells / g, K ≥ H² — by default
//!    a curvature radius of one cell, sharper than the grid can represent. The floor keeps a surface of uniform
//!    curvature (a sphere cap, σ = 0) and every hill broader than a few cells free of outliers, whatever g.
//! 2. Outliers: measured cells with |K| > K_th or |H| > H_th, K and H taken with the grid mirrored at its border
//!    ([`Border::Mirror`]) so that a spike on the border is judged as one inside.
//! 3. Laplacian smoothing of the outliers only (eq. 10): z ← z + λ_i (z̄ − z), where z̄ is what a weighted plane
//!    through the measured 8-neighbours predicts at the cell — the neighbours' weighted mean wherever the
//!    weights are symmetric, and still exact on a slope where they are not (at the border, next to gaps).
//! 4. Iterative refinement: detect, smooth, recompute K and H near what moved, and repeat until no outlier is
//!    left to move (or `max_iterations`). When new cells were flagged the thresholds are recomputed without
//!    the flagged ones (sigma clipping: once the largest spikes are out, σ shrinks and the smaller ones show).
//!    A flagged cell stays in the smoothing until its ρ (below) falls under [`SmoothParams::release`]
//!    (hysteresis), so a spike is brought down to a fraction of the smallest spike worth removing, not just
//!    under the threshold. Only cells over a threshold move, and only while they are: a hill whose curvature is
//!    under the thresholds keeps its shape (a relaxation run to convergence on every flagged cell would pull a
//!    noisy hill flat like a membrane).
//! 5. Preservation of critical features — our reading of "λ varies based on local curvature values":
//!    - λ_i = λ · ι_i, where ι_i ∈ [0, 1] is how alike the cell's curvature is in every direction: the second
//!      differences κ_a = (z₊ₐ + z₋ₐ − 2z)/|a|² along the 4 axes through it (2 straight, 2 diagonal; a missing
//!      or unmeasured neighbour extrapolated from the other side), ι = min κ / max κ when all bend the same way,
//!      else 0.
//!      An isolated spike or pit
//!      has ι ≈ 1 and is flattened; a kerb edge, a ridge, a ditch — linear features a ground robot must still
//!      see — bend along one axis only (ι ≈ 0) and keep their height, as do the cells next to a spike.
//!    - Neighbour weights in z̄ shrink with the neighbour's curvature: ω_j = d_j⁻² / (1 + ρ_j²), ρ_j the larger
//!      of |K_j|/K_th and |H_j|/H_th, so a spike's new height leans on calm ground, not on other outliers.
//!
//! Cells that are not outliers, and outliers with λ_i = 0, keep their height bit for bit.

use super::curvature::{Border, CurvatureMap, FundamentalForms, derivatives_with};
use super::plane::fit_plane;
use crate::error::{PlannerError, Result, finite};
use crate::map::GridGeometry;

/// Knobs of the protrusion removal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothParams {
    /// α of eq. 9 (Gaussian curvature), standard deviations.
    pub alpha: f64,
    /// β of eq. 9 (mean curvature), standard deviations.
    pub beta: f64,
    /// λ of eq. 10, in (0, 1].
    pub lambda: f64,
    /// Height of the smallest one-cell spike worth removing, in cells (× the cell size): it sets the
    /// thresholds' floor.
    pub min_spike_cells: f64,
    /// A flagged cell is smoothed until ρ = max(|K|/K_th, |H|/H_th) falls under this, in (0, 1].
    pub release: f64,
    /// Most detect-and-smooth iterations.
    pub max_iterations: usize,
    /// Smoothing stops when no height moved more than this in an iteration, metres.
    pub tolerance_m: f64,
}

impl Default for SmoothParams {
    fn default() -> Self {
        Self {
            alpha: 3.0,
            beta: 3.0,
            lambda: 0.8,
            min_spike_cells: 0.5,
            release: 0.05,
            max_iterations: 100,
            tolerance_m: 1e-6,
        }
    }
}

impl SmoothParams {
    /// Checks the ranges, naming the field that is wrong.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("alpha", self.alpha),
            ("beta", self.beta),
            ("min_spike_cells", self.min_spike_cells),
        ] {
            if finite(name, v)? < 0.0 {
                return Err(PlannerError::InvalidParam {
                    name,
                    reason: format!("must be ≥ 0, got {v}"),
                });
            }
        }
        if !(self.release > 0.0 && self.release <= 1.0) {
            return Err(PlannerError::InvalidParam {
                name: "release",
                reason: format!("must lie in (0, 1], got {}", self.release),
            });
        }
        if !(self.lambda > 0.0 && self.lambda <= 1.0) {
            return Err(PlannerError::InvalidParam {
                name: "lambda",
                reason: format!("must lie in (0, 1], got {}", self.lambda),
            });
        }
        if !(self.tolerance_m.is_finite() && self.tolerance_m > 0.0) {
            return Err(PlannerError::InvalidParam {
                name: "tolerance_m",
                reason: format!("must be a positive number of metres, got {}", self.tolerance_m),
            });
        }
        Ok(())
    }
}

/// The thresholds of eq. 9 as applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvatureThresholds {
    /// K_th, 1/m².
    pub gaussian_per_m2: f64,
    /// H_th, 1/m.
    pub mean_per_m: f64,
}

/// What the smoothing did.
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothReport {
    /// The thresholds of the first round (on all measured cells).
    pub thresholds: CurvatureThresholds,
    /// The thresholds of the last round.
    pub final_thresholds: CurvatureThresholds,
    /// Per cell: flagged as an outlier in some round.
    pub outlier: Vec<bool>,
    /// Outliers whose height changed.
    pub smoothed_cells: usize,
    /// Detect-and-smooth iterations run.
    pub iterations: usize,
}

/// Mean and standard deviation of the finite magnitudes among `values` where `keep` holds.
fn magnitude_stats(values: &[f64], keep: &[bool]) -> (f64, f64) {
    let mags = values
        .iter()
        .zip(keep)
        .filter(|(v, k)| **k && v.is_finite())
        .map(|(v, _)| v.abs());
    let (n, sum, sum2) = mags.fold((0usize, 0.0, 0.0), |(n, s, s2), m| (n + 1, s + m, s2 + m * m));
    if n == 0 {
        return (0.0, 0.0);
    }
    let mean = sum / n as f64;
    (mean, (sum2 / n as f64 - mean * mean).max(0.0).sqrt())
}

/// Thresholds of eq. 9 from the curvature of the cells where `judged` holds, on a grid of `cell_m` metres.
pub fn thresholds(
    curvature: &CurvatureMap,
    judged: &[bool],
    cell_m: f64,
    params: &SmoothParams,
) -> CurvatureThresholds {
    let (mk, sk) = magnitude_stats(&curvature.gaussian, judged);
    let (mh, sh) = magnitude_stats(&curvature.mean, judged);
    let floor = 2.0 * params.min_spike_cells / cell_m;
    CurvatureThresholds {
        gaussian_per_m2: (mk + params.alpha * sk).max(floor * floor),
        mean_per_m: (mh + params.beta * sh).max(floor),
    }
}

/// ρ = max(|K|/K_th, |H|/H_th); over 1 is an outlier. NaN curvature gives 0.
fn exceedance(k: f64, h: f64, t: &CurvatureThresholds) -> f64 {
    let r = (k.abs() / t.gaussian_per_m2).max(h.abs() / t.mean_per_m);
    if r.is_finite() { r } else { 0.0 }
}

/// ι of cell `i`: min/max of the second differences along the 4 axes through it, when all bend the same way;
/// 0 otherwise, and 0 too when none bends by `min_spike` (what made the cell an outlier lies in a filled gap,
/// not in the data). Where one neighbour of an axis is off the grid or unmeasured, it is extrapolated along the
/// line through the next two cells on the other side (z₋₁ = 3z₁ − 2z₂), which leaves a slope out of it: a spike
/// on the border is still a spike, its neighbours along the border are not, and a steep border is no pit. An
/// axis that cannot be completed is skipped.
fn isotropy(heights: &[f64], measured: &[bool], geometry: &GridGeometry, i: usize, min_spike: f64) -> f64 {
    let c = geometry.cell(i);
    let known = |dx: isize, dy: isize| {
        geometry
            .offset(c, dx, dy)
            .map(|o| geometry.index(o))
            .filter(|&j| measured[j])
            .map(|j| heights[j])
    };
    let mut kappa = [0.0; 4];
    let mut n = 0;
    for (a, (dx, dy)) in [(1, 0), (0, 1), (1, 1), (1, -1)].into_iter().enumerate() {
        let pair = match (known(dx, dy), known(-dx, -dy)) {
            (Some(p), Some(q)) => Some((p, q)),
            (Some(p), None) => known(2 * dx, 2 * dy).map(|p2| (p, 3.0 * p - 2.0 * p2)),
            (None, Some(q)) => known(-2 * dx, -2 * dy).map(|q2| (3.0 * q - 2.0 * q2, q)),
            (None, None) => None,
        };
        let Some((p, q)) = pair else { continue };
        kappa[n] = (p + q - 2.0 * heights[i]) / if a < 2 { 1.0 } else { 2.0 };
        n += 1;
    }
    if n < 2 {
        return 0.0;
    }
    let k = &kappa[..n];
    let sign = k.iter().sum::<f64>().signum();
    let lo = k.iter().map(|v| v * sign).fold(f64::INFINITY, f64::min);
    let hi = k.iter().map(|v| v * sign).fold(0.0, f64::max);
    if hi >= min_spike {
        (lo / hi).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Recomputes K and H (mirrored border) at every cell within 2 of a cell in `changed`.
fn update_curvature(curvature: &mut CurvatureMap, heights: &[f64], geometry: &GridGeometry, changed: &[usize]) {
    let mut seen = std::collections::BTreeSet::new();
    for &i in changed {
        let c = geometry.cell(i);
        for dy in -2..=2 {
            for dx in -2..=2 {
                if let Some(o) = geometry.offset(c, dx, dy) {
                    seen.insert(geometry.index(o));
                }
            }
        }
    }
    for j in seen {
        let (k, h) =
            derivatives_with(heights, geometry, geometry.cell(j), Border::Mirror).map_or((f64::NAN, f64::NAN), |d| {
                let f = FundamentalForms::new(&d);
                (f.gaussian(), f.mean())
            });
        curvature.gaussian[j] = k;
        curvature.mean[j] = h;
    }
}

/// Removes protrusions from a complete height field (no NaN; gaps provisionally filled) in place, changing only
/// measured cells flagged as outliers. `measured` marks cells that hold data (only they are judged, and only
/// they feed the Laplacian).
pub fn smooth_outliers(
    heights: &mut [f64],
    measured: &[bool],
    geometry: &GridGeometry,
    params: &SmoothParams,
) -> Result<SmoothReport> {
    params.validate()?;
    let original = heights.to_vec();
    let mut curvature = CurvatureMap::with_border(heights, geometry, Border::Mirror)?;
    let g = geometry.resolution;
    let first = thresholds(&curvature, measured, g, params);
    let mut t = first;
    let mut outlier = vec![false; geometry.len()];
    // λ_i, set when the cell is flagged: the shape of its neighbourhood then says what it is.
    let mut lambda = vec![0.0; geometry.len()];
    let mut iterations = 0;
    let mut samples = Vec::with_capacity(8);
    let rho = |c: &CurvatureMap, t: &CurvatureThresholds, i: usize| exceedance(c.gaussian[i], c.mean[i], t);
    while iterations < params.max_iterations {
        let mut grew = false;
        for i in 0..geometry.len() {
            if measured[i] && !outlier[i] && rho(&curvature, &t, i) > 1.0 {
                outlier[i] = true;
                lambda[i] = params.lambda * isotropy(heights, measured, geometry, i, params.min_spike_cells * g);
                grew = true;
            }
        }
        iterations += 1;
        let updates: Vec<(usize, f64)> = (0..geometry.len())
            .filter(|&i| lambda[i] > 0.0 && rho(&curvature, &t, i) > params.release)
            .filter_map(|i| {
                let c = geometry.cell(i);
                samples.clear();
                for o in geometry.neighbors8(c) {
                    let j = geometry.index(o);
                    if measured[j] {
                        let (dx, dy) = ((o.x as f64 - c.x as f64) * g, (o.y as f64 - c.y as f64) * g);
                        let r = rho(&curvature, &t, j);
                        samples.push([dx, dy, heights[j], 1.0 / ((dx * dx + dy * dy) * (1.0 + r * r))]);
                    }
                }
                let fit = fit_plane(&samples)?;
                Some((i, heights[i] + lambda[i] * (fit.height - heights[i])))
            })
            .collect();
        let mut moved = 0.0f64;
        for &(i, v) in &updates {
            moved = moved.max((v - heights[i]).abs());
            heights[i] = v;
        }
        let changed: Vec<usize> = updates.iter().map(|u| u.0).collect();
        update_curvature(&mut curvature, heights, geometry, &changed);
        if grew {
            // Sigma clipping: the next detection judges by the cells never flagged.
            let judged: Vec<bool> = measured.iter().zip(&outlier).map(|(&m, &o)| m && !o).collect();
            t = thresholds(&curvature, &judged, g, params);
        } else if moved <= params.tolerance_m {
            break;
        }
    }
    let smoothed_cells = heights.iter().zip(&original).filter(|(a, b)| a != b).count();
    Ok(SmoothReport {
        thresholds: first,
        final_thresholds: t,
        outlier,
        smoothed_cells,
        iterations,
    })
}

#[cfg(test)]
#[path = "smooth_tests.rs"]
mod tests;
