//! Dwell time and speed from the attribute (seed 000 §V.B, eqs. 22–25), with the paper's garbled formulas
//! restated in physical units.
//!
//! **What is deposited.** While the tool works it spreads its effort around the robot with the Gaussian
//! kernel G of eq. 21 (σ = tool_width / 2, kernel in 1/m²), so a point x receives the deposit
//! C(x) = ∫ G(x − p(t)) dt, in tool-seconds per square metre (s/m²). Lanes spaced by the tool width w driven
//! at speed v deposit C = 1 / (v · w) (the Gaussians of neighbouring lanes, 2σ apart, sum to a flat field
//! within about 1 %). The deposit is linear in the dwell time: twice as slow, twice the work.
//!
//! **What is desired (eq. 22).** C_desired = k · A: the work a point needs is proportional to its attribute
//! (twice as dirty, twice the scrubbing). Units: A is dimensionless in [0, 1]; k [s/m²] is the deposit wanted
//! where A = 1.
//!
//! **Eqs. 23–25 restated.** As printed, eq. 23 (1 − e^{−λt} = C_target / (kA)) would make the dwell *fall*
//! as A grows, and eq. 25 (v = λ / ln(kA / C_target)) is not a speed unless λ is one. What they mean: the
//! dwell needed at a point grows with the ratio of desired to baseline deposit, x = k·A / C_target, and the
//! speed is a reference speed divided by that growth. The logarithm belongs to a saturating (first-order)
//! effect; the deposit itself is linear in dwell, and the quantity DESIGN §6 holds uniform is the deposit
//! divided by the attribute, so we use x itself, not ln x:
//!
//! - C_target [s/m²] is the baseline: the deposit of one pass at full speed, C_target = 1 / (w · v_max). It
//!   is the least a point on the path can receive, since every point is passed at least once.
//! - λ [m/s] is the speed that delivers C_target: λ = v_max.
//! - v(x, y) = λ / x = λ · C_target / (k · A(x, y)), clamped to [v_min, v_max]; the dwell per metre of path is
//!   1 / v = w · k · A: proportional to the desire, so deposit / desire is the same everywhere (that is the
//!   physics: equal work per unit of need).
//! - Where k · A ≤ C_target (x ≤ 1, where the paper's logarithm turns ≤ 0 and its speed negative or
//!   infinite) the point needs no more than a full-speed pass already gives: the robot drives at v_max and
//!   the point gets C_target. Equivalently, the desire is raised to C_target there ([`DwellLaw::desired`]),
//!   which is also how the uniformity metric treats nearly clean (A ≈ 0) cells.
//!
//! **Choosing k.** [`DwellLaw::for_range`] picks the time-optimal k: the lowest attribute on the coverable
//! area gets v_max, unless the attribute spans more than v_max / v_min, in which case the highest gets
//! v_min and everything below A_max · v_min / v_max is over-served at v_max (dirty spots are never
//! under-served). A = 1 everywhere therefore means v_max everywhere.

use super::SpeedLimits;

/// The speed law v = λ · C_target / (k · A) of the module docs, with its constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DwellLaw {
    /// k: deposit wanted where A = 1, tool-seconds per m².
    pub k_s_per_m2: f64,
    /// C_target: deposit of one full-speed pass over lanes spaced by the tool width, s/m².
    pub c_target_s_per_m2: f64,
    /// λ: the speed that deposits C_target (= v_max), m/s.
    pub lambda_mps: f64,
    /// Slowest speed, m/s.
    pub v_min_mps: f64,
}

impl DwellLaw {
    /// The time-optimal law for attributes in `[a_lo, a_hi]` (over the coverable area), a tool of width
    /// `tool_width_m` and the robot's speed limits. A range with nothing to do (a_hi ≤ 0) gives v_max
    /// everywhere.
    pub fn for_range(a_lo: f64, a_hi: f64, tool_width_m: f64, limits: &SpeedLimits) -> Self {
        let c_target = 1.0 / (tool_width_m * limits.v_max_mps);
        let ratio = limits.v_min_mps / limits.v_max_mps;
        let floor = a_lo.max(a_hi * ratio);
        let floor = if floor > 1e-9 && floor.is_finite() {
            floor.min(1.0)
        } else {
            1.0
        };
        Self {
            k_s_per_m2: c_target / floor,
            c_target_s_per_m2: c_target,
            lambda_mps: limits.v_max_mps,
            v_min_mps: limits.v_min_mps,
        }
    }

    /// The attribute below which a full-speed pass already over-serves a point: C_target / k.
    pub fn attribute_floor(&self) -> f64 {
        self.c_target_s_per_m2 / self.k_s_per_m2
    }

    /// Desired deposit at attribute `a`, s/m²: k · max(A, floor) (eq. 22 with the full-speed floor).
    pub fn desired(&self, a: f64) -> f64 {
        self.k_s_per_m2 * a.max(self.attribute_floor())
    }

    /// Speed at attribute `a`, m/s, in [v_min, v_max]: λ · C_target / (k · A), v_max where k · A ≤ C_target.
    pub fn speed(&self, a: f64) -> f64 {
        let x = self.k_s_per_m2 * a / self.c_target_s_per_m2;
        if x.is_nan() || x <= 1.0 {
            return self.lambda_mps;
        }
        (self.lambda_mps / x).clamp(self.v_min_mps, self.lambda_mps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> SpeedLimits {
        SpeedLimits::new(0.1, 1.0, 0.5)
    }

    #[test]
    fn narrow_range_anchors_the_lowest_at_v_max() {
        let law = DwellLaw::for_range(0.4, 0.8, 0.5, &limits());
        assert!((law.speed(0.4) - 1.0).abs() < 1e-12);
        assert!((law.speed(0.8) - 0.5).abs() < 1e-12);
        assert_eq!(law.speed(0.1), 1.0);
        // Dwell per metre is proportional to the desire: deposit / desire is constant.
        for a in [0.4, 0.5, 0.8] {
            let deposit = 1.0 / (law.speed(a) * 0.5);
            assert!((deposit / law.desired(a) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn wide_range_anchors_the_highest_at_v_min() {
        let law = DwellLaw::for_range(0.0, 1.0, 0.5, &limits());
        assert!((law.speed(1.0) - 0.1).abs() < 1e-12);
        assert!((law.attribute_floor() - 0.1).abs() < 1e-12);
        assert_eq!(law.speed(0.05), 1.0);
        assert_eq!(law.speed(0.0), 1.0);
        // Uniform attribute: full speed everywhere; no attribute at all: likewise.
        assert_eq!(DwellLaw::for_range(1.0, 1.0, 0.5, &limits()).speed(1.0), 1.0);
        assert_eq!(DwellLaw::for_range(0.0, 0.0, 0.5, &limits()).speed(0.0), 1.0);
    }
}
