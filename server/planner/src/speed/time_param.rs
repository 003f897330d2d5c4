//! Time parametrisation: the fastest speeds under per-point caps and an acceleration bound (the classic
//! forward–backward pass), and the times they give.
//!
//! Between consecutive points the robot accelerates uniformly, so v² is linear in arc length and a segment
//! of length s between speeds v_i and v_{i+1} takes 2 s / (v_i + v_{i+1}). The result satisfies
//! |v_{i+1}² − v_i²| / (2 s_i) ≤ a_max and v_i ≤ cap_i; it is the pointwise largest profile that does.

/// Largest speeds (m/s) with `v[i] ≤ caps[i]` and `|v[i+1]² − v[i]²| ≤ 2 · a_max · seg[i]`, where `seg[i]` is the
/// length (metres) between point `i` and `i + 1` (`seg.len() == caps.len() − 1`). Caps must be positive.
pub fn limit_acceleration(caps: &[f64], seg: &[f64], a_max_mps2: f64) -> Vec<f64> {
    let mut v = caps.to_vec();
    for i in 0..seg.len().min(v.len().saturating_sub(1)) {
        let reach = (v[i] * v[i] + 2.0 * a_max_mps2 * seg[i]).sqrt();
        if v[i + 1] > reach {
            v[i + 1] = reach;
        }
    }
    for i in (0..seg.len().min(v.len().saturating_sub(1))).rev() {
        let reach = (v[i + 1] * v[i + 1] + 2.0 * a_max_mps2 * seg[i]).sqrt();
        if v[i] > reach {
            v[i] = reach;
        }
    }
    v
}

/// Time of each point from the first (seconds) under uniform acceleration between points.
pub fn times(v: &[f64], seg: &[f64]) -> Vec<f64> {
    let mut t = Vec::with_capacity(v.len());
    let mut now = 0.0;
    if !v.is_empty() {
        t.push(0.0);
    }
    for (i, s) in seg.iter().enumerate().take(v.len().saturating_sub(1)) {
        now += segment_duration(*s, v[i], v[i + 1]);
        t.push(now);
    }
    t
}

/// Seconds to drive `s` metres accelerating uniformly from `v0` to `v1` (m/s, positive).
#[inline]
pub fn segment_duration(s: f64, v0: f64, v1: f64) -> f64 {
    let sum = v0 + v1;
    if sum > 0.0 { 2.0 * s / sum } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramps_into_and_out_of_a_slow_point() {
        let caps = [0.1, 1.0, 1.0, 0.1, 1.0, 1.0];
        let seg = [0.5; 5];
        let v = limit_acceleration(&caps, &seg, 0.5);
        assert_eq!(v[0], 0.1);
        assert!((v[1] - (0.01f64 + 0.5).sqrt()).abs() < 1e-12);
        assert_eq!(v[3], 0.1);
        for i in 0..5 {
            assert!((v[i + 1] * v[i + 1] - v[i] * v[i]).abs() <= 2.0 * 0.5 * seg[i] + 1e-12);
            assert!(v[i] <= caps[i]);
        }
        let t = times(&v, &seg);
        assert_eq!(t[0], 0.0);
        assert!(t.windows(2).all(|w| w[1] > w[0]));
        // Constant speed: t = s / v.
        let t = times(&[0.5, 0.5, 0.5], &[1.0, 2.0]);
        assert!((t[2] - 6.0).abs() < 1e-12);
    }
}
