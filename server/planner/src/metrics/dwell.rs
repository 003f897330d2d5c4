//! Dwell uniformity (DESIGN §6): deposit each segment's duration at the path, blur with a Gaussian of
//! σ = tool_width / 2 (seed 000 eq. 21), divide by the attribute, and take the coefficient of variation
//! (population standard deviation / mean) over coverable cells; the comparison drives the same path at
//! constant speed in the same total time.
//!
//! "Each segment" means each *working* segment: a transit segment (`WaypointKind::Transit`, moving between
//! regions with the tool off, as opposed to `Cover`, "the tool is working") deposits nothing. Counting
//! transits would charge the plan for driving over finished floor with the brush up.
//!
//! Cells where A ≈ 0 want no work at all, so any deposit divided by A would blow up and one clean cell
//! would dominate the figure. The divisor is therefore max(A, `attribute_floor`), where the floor is the
//! attribute that one full-speed pass already serves (`speed::DwellLaw::attribute_floor`: the robot cannot
//! deposit less than that on a cell it must cover). The same floor is used for both figures.

use crate::geom::Point2;
use crate::space::CoverageSpace;
use crate::speed::AttributeMap;
use crate::speed::field::deposit_field;
use crate::speed::time_param::segment_duration;

/// Uniformity figures of a timed path. A profile made without an attribute map does not compute the CVs
/// (they are defined against one): they are NaN there, and only `duration_s` holds.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct DwellMetrics {
    /// CV of deposit / attribute over coverable cells for the profiled speeds (lower is more uniform).
    pub dwell_cv: f64,
    /// The same for constant speed over the same path and total time.
    pub dwell_cv_const_speed: f64,
    /// Time to drive the path, seconds.
    pub duration_s: f64,
}

/// Computes [`DwellMetrics`] of `points` (map frame, metres) driven at `speeds_mps` (one per point, uniform
/// acceleration between points). `working[k]` tells whether segment k (point k to k + 1) works (cover); a
/// missing entry counts as working.
pub fn evaluate_dwell(
    space: &CoverageSpace,
    points: &[Point2],
    speeds_mps: &[f64],
    working: &[bool],
    attribute: &AttributeMap,
    attribute_floor: f64,
) -> DwellMetrics {
    let seg: Vec<f64> = points.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
    let durations: Vec<f64> = seg
        .iter()
        .enumerate()
        .map(|(k, s)| match (speeds_mps.get(k), speeds_mps.get(k + 1)) {
            (Some(a), Some(b)) => segment_duration(*s, *a, *b),
            _ => 0.0,
        })
        .collect();
    let duration_s: f64 = durations.iter().sum();
    let on = |k: usize| working.get(k).copied().unwrap_or(true);
    let deposited: Vec<f64> = durations
        .iter()
        .enumerate()
        .map(|(k, d)| if on(k) { *d } else { 0.0 })
        .collect();
    DwellMetrics {
        dwell_cv: dwell_cv(space, points, &deposited, attribute, attribute_floor),
        dwell_cv_const_speed: constant_speed_cv(space, points, working, attribute, attribute_floor),
        duration_s,
    }
}

/// Dwell CV of `points` driven at one constant speed (the CV does not depend on the speed, so each working
/// segment deposits its length); `working` as in [`evaluate_dwell`].
pub fn constant_speed_cv(
    space: &CoverageSpace,
    points: &[Point2],
    working: &[bool],
    attribute: &AttributeMap,
    attribute_floor: f64,
) -> f64 {
    let durations: Vec<f64> = (points.windows(2).enumerate())
        .map(|(k, w)| {
            if working.get(k).copied().unwrap_or(true) {
                (w[1] - w[0]).norm()
            } else {
                0.0
            }
        })
        .collect();
    dwell_cv(space, points, &durations, attribute, attribute_floor)
}

/// CV over coverable cells of deposit / max(A, floor) for segment durations `durations` (seconds; zero for
/// segments that do not work).
pub fn dwell_cv(
    space: &CoverageSpace,
    points: &[Point2],
    durations: &[f64],
    attribute: &AttributeMap,
    attribute_floor: f64,
) -> f64 {
    let g = space.geometry();
    let d = deposit_field(g, points, durations, space.robot.tool_width_m / 2.0);
    field_cv(space, &d, attribute, attribute_floor)
}

/// CV over coverable cells of `deposit[i] / max(A_i, floor)` for a deposit field already computed.
pub fn field_cv(space: &CoverageSpace, deposit: &[f64], attribute: &AttributeMap, attribute_floor: f64) -> f64 {
    let floor = attribute_floor.max(1e-6);
    let (mut n, mut sum, mut sum2) = (0usize, 0.0, 0.0);
    for (i, &d) in deposit.iter().enumerate() {
        if !space.coverable[i] {
            continue;
        }
        let r = d / attribute.at(i).max(floor);
        n += 1;
        sum += r;
        sum2 += r * r;
    }
    if n == 0 || sum <= 0.0 {
        return 0.0;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0);
    var.sqrt() / mean
}

/// Spearman rank correlation of two equally long samples (average ranks for ties); 0 when undefined.
pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    if n < 2 {
        return 0.0;
    }
    let (rx, ry) = (ranks(&x[..n]), ranks(&y[..n]));
    let mx = rx.iter().sum::<f64>() / n as f64;
    let my = ry.iter().sum::<f64>() / n as f64;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (a, b) = (rx[i] - mx, ry[i] - my);
        sxy += a * b;
        sxx += a * a;
        syy += b * b;
    }
    if sxx <= 0.0 || syy <= 0.0 {
        return 0.0;
    }
    sxy / (sxx * syy).sqrt()
}

fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let avg = (i + j) as f64 / 2.0;
        for &k in &idx[i..=j] {
            r[k] = avg;
        }
        i = j + 1;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::space::RobotShape;

    #[test]
    fn spearman_cases() {
        assert!((spearman(&[1.0, 2.0, 3.0], &[10.0, 20.0, 30.0]) - 1.0).abs() < 1e-12);
        assert!((spearman(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]) + 1.0).abs() < 1e-12);
        assert_eq!(spearman(&[1.0, 1.0], &[1.0, 2.0]), 0.0);
        assert_eq!(ranks(&[5.0, 1.0, 5.0]), vec![1.5, 0.0, 1.5]);
    }

    #[test]
    fn slowing_where_dirtier_is_more_uniform() {
        // A 6 m × 3 m room, lanes along x; the right half is twice as dirty.
        let g = GridGeometry::new(60, 30, 0.1, Point2::origin()).expect("valid");
        let robot = RobotShape {
            radius_m: 0.25,
            tool_width_m: 0.5,
        };
        let space =
            CoverageSpace::new(OccupancyGrid::filled(g, CellState::Free), robot, Point2::new(0.5, 0.5)).expect("space");
        let attr = AttributeMap::from_values(g, (0..g.len()).map(|i| if i % 60 < 30 { 0.4 } else { 0.8 }).collect())
            .expect("attr");
        let mut pts = Vec::new();
        for k in 0..6 {
            let y = 0.25 + 0.5 * f64::from(k);
            for x in 0..=24 {
                let x = 0.25 + 0.229_166_666 * f64::from(if k % 2 == 0 { x } else { 24 - x });
                pts.push(Point2::new(x, y));
            }
        }
        let v: Vec<f64> = pts.iter().map(|p| if p.x < 3.0 { 1.0 } else { 0.5 }).collect();
        let m = evaluate_dwell(&space, &pts, &v, &[], &attr, 0.4);
        assert!(m.duration_s > 0.0);
        assert!(m.dwell_cv < 0.6 * m.dwell_cv_const_speed, "{m:?}");
    }
}
