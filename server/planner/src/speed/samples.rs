//! The path as the speed profile sees it: points no further apart than a sample spacing, each with the
//! speed cap its curvature allows under the lateral-acceleration bound.

use crate::geom::Point2;
use crate::pipeline::WaypointKind;
use crate::smooth::SmoothedPath;

use super::SpeedLimits;

/// Dense samples of a path (map frame, metres) with per-sample caps (m/s).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PathSamples {
    /// Positions, metres.
    pub points: Vec<Point2>,
    /// What the segment ending at each sample does.
    pub kinds: Vec<WaypointKind>,
    /// Region of each sample (cover samples).
    pub regions: Vec<Option<u32>>,
    /// Length of segment k (sample k to k + 1), metres; one fewer than points.
    pub seg: Vec<f64>,
    /// Whether segment k (sample k to k + 1) works (cover) rather than transits with the tool off.
    pub working: Vec<bool>,
    /// Highest speed at each sample from curvature (and v_min at both ends), m/s, in [v_min, v_max].
    pub caps: Vec<f64>,
}

/// Speed cap for curvature `kappa` (1/m): √(a_lat / κ) in [v_min, v_max]; v_max on straight stretches and
/// v_min at a sharp corner (κ = ∞), where the robot turns on the spot. Where even v_min exceeds the lateral
/// bound, v_min wins: every waypoint keeps v ≥ v_min.
pub fn curvature_cap(kappa: f64, limits: &SpeedLimits) -> f64 {
    if kappa.is_nan() || kappa <= 1e-12 {
        return limits.v_max_mps;
    }
    (limits.a_lat_mps2 / kappa)
        .sqrt()
        .clamp(limits.v_min_mps, limits.v_max_mps)
}

/// Resamples `path` so no segment is longer than `spacing_m` (original points are kept), with caps.
pub fn resample(path: &SmoothedPath, spacing_m: f64, limits: &SpeedLimits) -> PathSamples {
    let mut out = PathSamples::default();
    let wps = &path.waypoints;
    let mut push = |p: Point2, k: WaypointKind, r: Option<u32>, kappa: f64| {
        if let Some(last) = out.points.last() {
            out.seg.push((p - last).norm());
            out.working.push(k == WaypointKind::Cover);
        }
        out.points.push(p);
        out.kinds.push(k);
        out.regions.push(r);
        out.caps.push(curvature_cap(kappa, limits));
    };
    for (i, w) in wps.iter().enumerate() {
        if i > 0 {
            let a = wps[i - 1].position;
            let len = (w.position - a).norm();
            let n = (len / spacing_m).ceil().max(1.0) as usize;
            // Inside a segment: on a curve (both ends curved) the lesser curvature; a sharp vertex is a point
            // (κ = ∞ there only), so a straight segment between two sharp corners is straight inside.
            let inner = |k: f64| if k.is_finite() { k } else { 0.0 };
            let kappa = inner(path.curvature[i - 1]).min(inner(path.curvature[i]));
            for j in 1..n {
                let p = a + (w.position - a) * (j as f64 / n as f64);
                push(p, w.kind, w.region, kappa);
            }
        }
        push(w.position, w.kind, w.region, path.curvature[i]);
    }
    if let Some(c) = out.caps.first_mut() {
        *c = limits.v_min_mps;
    }
    if let Some(c) = out.caps.last_mut() {
        *c = limits.v_min_mps;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::Waypoint;

    #[test]
    fn spacing_and_caps() {
        let limits = SpeedLimits::new(0.1, 1.0, 0.5);
        let w = |x: f64, y: f64| Waypoint {
            position: Point2::new(x, y),
            kind: WaypointKind::Cover,
            region: Some(1),
        };
        let path = SmoothedPath {
            waypoints: vec![w(0.0, 0.0), w(1.0, 0.0), w(1.0, 1.0)],
            curvature: vec![0.0, f64::INFINITY, 0.0],
            rounded: 0,
            kept_sharp: 1,
        };
        let s = resample(&path, 0.3, &limits);
        assert_eq!(s.points.len(), 9);
        assert!(s.seg.iter().all(|&d| d <= 0.3 + 1e-12));
        assert_eq!(s.caps[0], 0.1);
        assert_eq!(s.caps[1], 1.0);
        assert_eq!(s.caps[4], 0.1);
        assert_eq!(s.caps[8], 0.1);
        assert!((curvature_cap(2.0, &limits) - 0.5).abs() < 1e-12);
        // Between two sharp corners the segment is straight inside: full speed there.
        let lane = SmoothedPath {
            waypoints: vec![w(0.0, 0.0), w(0.0, 1.0), w(5.0, 1.0), w(5.0, 2.0)],
            curvature: vec![0.0, f64::INFINITY, f64::INFINITY, 0.0],
            rounded: 0,
            kept_sharp: 2,
        };
        let s = resample(&lane, 0.5, &limits);
        let inside: Vec<f64> = (0..s.points.len())
            .filter(|&k| s.points[k].y == 1.0 && s.points[k].x > 0.0 && s.points[k].x < 5.0)
            .map(|k| s.caps[k])
            .collect();
        assert_eq!(inside.len(), 9);
        assert!(inside.iter().all(|&c| c == 1.0), "{inside:?}");
        assert_eq!(curvature_cap(1000.0, &limits), 0.1);
    }
}
