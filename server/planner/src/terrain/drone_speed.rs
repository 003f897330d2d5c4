//! Speeds and times along a drone plan: the RFICP speed law (seed 001, the same [`DwellLaw`] as ground plans)
//! on the lanes, curvature caps in 3-D, and the forward–backward acceleration pass.
//!
//! - On a lane the tool works: the speed is the law's v = λ C_target / (k A) for the attribute A under the
//!   point (A = 1 everywhere without an attribute map, which is v_max), so dirtier or drier ground is flown
//!   slower and gets more deposit per square metre.
//! - Everywhere the speed is capped by the path's curvature, √(a_lat / κ), with κ the turning curvature of the
//!   3-D polyline measured over chords of at least [`CURVATURE_CHORD_M`] each side (the angle between the
//!   chords over their mean length): the 90° corners where a lane meets its turn and the vertical bends over a
//!   ridge slow the drone alike, while the centimetre roughness of a LiDAR surface sampled every half metre
//!   (which would read as sharp bends between neighbouring waypoints) does not.
//! - Climbs and descents are capped apart ([`VerticalLimits`], as autopilots cap them: ArduPilot's
//!   `WPNAV_SPEED_UP` and `WPNAV_SPEED_DN`): over a segment that rises by g metres per metre flown the speed is at
//!   most climb / g (descent / |g| going down), at both its ends, so the vertical speed stays within the limit.
//!   v_min wins where the two disagree (a grade steeper than limit / v_min), and the figure is reported.
//! - The first and last points are at v_min, as on the ground.
//! - Then the fastest profile under those caps and a_max ([`limit_acceleration`]), and its times.
//!
//! The closed-loop refinement that ground plans get ([`crate::speed::refine`]) measures deposit on the map
//! grid of a 2-D plan; a drone's lanes are spaced on the surface so their swaths tile it without overlap, and
//! the open-loop law is already exact there (each point is swept by one lane).

use super::DronePlan;
use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use crate::speed::samples::curvature_cap;
use crate::speed::time_param::{limit_acceleration, times};
use crate::speed::{AttributeMap, DwellLaw, SpeedLimits};

/// A drone's vertical speed limits, m/s; `None` leaves that direction to the 3-D limits alone.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VerticalLimits {
    /// Fastest climb.
    pub climb_mps: Option<f64>,
    /// Fastest descent (a positive number).
    pub descent_mps: Option<f64>,
}

impl VerticalLimits {
    /// Refuses a limit that is not a positive finite number, naming it.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [("max_climb_mps", self.climb_mps), ("max_descent_mps", self.descent_mps)] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return Err(PlannerError::InvalidParam {
                    name,
                    reason: format!("{v} is not a positive speed"),
                });
            }
        }
        Ok(())
    }

    /// Fastest speed along a segment rising `grade` metres per metre flown (∞ when unlimited).
    fn cap(&self, grade: f64) -> f64 {
        let limit = if grade > 0.0 { self.climb_mps } else { self.descent_mps };
        match limit {
            Some(l) if grade.abs() > 1e-12 => l / grade.abs(),
            _ => f64::INFINITY,
        }
    }
}

/// Speeds and times of a drone plan, one per point of [`DronePlan::path`].
#[derive(Debug, Clone, PartialEq)]
pub struct DroneProfile {
    /// Speed at each point, m/s, in [v_min, v_max].
    pub speed_mps: Vec<f64>,
    /// Time of each point from the start, seconds.
    pub time_s: Vec<f64>,
    /// The law that set the lane speeds.
    pub law: DwellLaw,
}

impl DroneProfile {
    /// Duration of the whole flight, seconds.
    pub fn duration_s(&self) -> f64 {
        self.time_s.last().copied().unwrap_or(0.0)
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Shortest chord each side of a point its curvature is measured over, metres.
pub const CURVATURE_CHORD_M: f64 = 1.0;

/// Turning curvature at `b` between `a` and `c` (1/m): the angle between the chords over their mean length; 0
/// where a chord has no length.
fn turning_curvature(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let (u, v) = (sub(b, a), sub(c, b));
    let (lu, lv) = (norm(u), norm(v));
    if lu < 1e-12 || lv < 1e-12 {
        return 0.0;
    }
    let cos = ((u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) / (lu * lv)).clamp(-1.0, 1.0);
    cos.acos() / (0.5 * (lu + lv))
}

/// Profiles `plan` under `limits` and `vertical`, slowing its lanes where `attribute` (any grid in the map frame;
/// A = 1 everywhere when `None`) is high.
pub fn profile_drone(
    plan: &DronePlan,
    attribute: Option<&AttributeMap>,
    limits: &SpeedLimits,
    vertical: &VerticalLimits,
) -> Result<DroneProfile> {
    limits.validate()?;
    vertical.validate()?;
    let p = &plan.path;
    if p.len() != plan.on_lane.len() {
        return Err(PlannerError::InvalidParam {
            name: "on_lane",
            reason: format!("{} flags for {} points", plan.on_lane.len(), p.len()),
        });
    }
    let (a_lo, a_hi) = attribute
        .and_then(|a| a.range_over(&vec![true; a.geometry().len()]))
        .unwrap_or((1.0, 1.0));
    let law = DwellLaw::for_range(a_lo, a_hi, plan.tool_width_m, limits);
    let n = p.len();
    let seg: Vec<f64> = p.windows(2).map(|w| norm(sub(w[1], w[0]))).collect();
    let arc: Vec<f64> = std::iter::once(0.0)
        .chain(seg.iter().scan(0.0, |acc, s| {
            *acc += s;
            Some(*acc)
        }))
        .collect();
    // Each segment's vertical cap, applied at both its ends.
    let climb: Vec<f64> = p
        .windows(2)
        .zip(&seg)
        .map(|(w, &s)| {
            if s > 1e-12 {
                vertical.cap((w[1][2] - w[0][2]) / s)
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let caps: Vec<f64> = (0..n)
        .map(|i| {
            if i == 0 || i + 1 == n {
                return limits.v_min_mps;
            }
            // The chord ends: the nearest points at least CURVATURE_CHORD_M away along the path (or the ends).
            let back = arc[..i]
                .partition_point(|&a| a <= arc[i] - CURVATURE_CHORD_M)
                .saturating_sub(1);
            let ahead = (i + 1 + arc[i + 1..].partition_point(|&a| a < arc[i] + CURVATURE_CHORD_M)).min(n - 1);
            let mut cap = curvature_cap(turning_curvature(p[back], p[i], p[ahead]), limits);
            if plan.on_lane[i] {
                let a = attribute.map_or(1.0, |m| m.at_point(Point2::new(p[i][0], p[i][1])));
                cap = cap.min(law.speed(a));
            }
            cap.min(climb[i - 1]).min(climb[i]).max(limits.v_min_mps)
        })
        .collect();
    let speed_mps = limit_acceleration(&caps, &seg, limits.a_max_mps2);
    let time_s = times(&speed_mps, &seg);
    Ok(DroneProfile { speed_mps, time_s, law })
}

/// Fastest climb and fastest descent of a timed 3-D path, m/s (both ≥ 0): each segment's rise over its time.
pub fn vertical_speeds(path: &[[f64; 3]], time_s: &[f64]) -> (f64, f64) {
    path.windows(2)
        .zip(time_s.windows(2))
        .filter(|(_, t)| t[1] - t[0] > 1e-12)
        .fold((0.0f64, 0.0f64), |(up, down), (w, t)| {
            let vz = (w[1][2] - w[0][2]) / (t[1] - t[0]);
            (up.max(vz), down.max(-vz))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::GridGeometry;
    use crate::speed::AttributeBlob;
    use crate::terrain::{DroneParams, TerrainSurface, plan_lanes};

    fn plan_over(z: impl Fn(f64, f64) -> f64) -> (DronePlan, GridGeometry) {
        let g = GridGeometry::new(81, 41, 0.25, Point2::origin()).expect("geometry");
        let s = TerrainSurface::from_fn(g, z).expect("surface");
        let params = DroneParams {
            tool_width_m: 2.0,
            altitude_offset_m: 3.0,
            ..DroneParams::default()
        };
        (plan_lanes(&s, &params).expect("plan"), g)
    }

    fn limits() -> SpeedLimits {
        SpeedLimits::new(0.5, 5.0, 2.0)
    }

    #[test]
    fn flat_lanes_fly_at_v_max_and_slow_into_the_corners() {
        let (plan, _) = plan_over(|_, _| 1.0);
        let prof = profile_drone(&plan, None, &limits(), &VerticalLimits::default()).expect("profile");
        let v = &prof.speed_mps;
        assert_eq!(v.len(), plan.path.len());
        assert_eq!((v[0], *v.last().expect("last")), (0.5, 0.5));
        // The middle of the first lane (20 m long) is flown at v_max; its corner at its end is slow.
        let lane0 = plan.on_lane.iter().position(|&l| !l).expect("a turn");
        assert!((v[lane0 / 2] - 5.0).abs() < 1e-9, "mid-lane {}", v[lane0 / 2]);
        assert!(v[lane0 - 1] < 1.5, "into the corner {}", v[lane0 - 1]);
        // Every step obeys a_max; times increase; the whole is no faster than the length at v_max.
        let mut len = 0.0;
        for i in 0..v.len() - 1 {
            let s = norm(sub(plan.path[i + 1], plan.path[i]));
            len += s;
            assert!(
                (v[i + 1].powi(2) - v[i].powi(2)).abs() <= 2.0 * 2.0 * s + 1e-9,
                "a_max broken at {i}"
            );
            assert!(prof.time_s[i + 1] > prof.time_s[i]);
        }
        assert!(prof.duration_s() > len / 5.0);
    }

    #[test]
    fn a_dirty_patch_is_flown_slower_and_turns_are_not_slowed_by_it() {
        let (plan, g) = plan_over(|x, _| 0.1 * x);
        let blob = AttributeBlob {
            centre: Point2::new(10.0, 5.0),
            sigma_m: 1.5,
            amplitude: 1.0,
        };
        let attr = AttributeMap::from_blobs(g, &[blob]).expect("attribute");
        let prof = profile_drone(&plan, Some(&attr), &limits(), &VerticalLimits::default()).expect("profile");
        // On the lanes: the higher the attribute, the slower (a lane point near the blob against one far away).
        let near = (0..plan.path.len())
            .filter(|&i| plan.on_lane[i])
            .min_by(|&a, &b| {
                let d = |i: usize| (plan.path[i][0] - 10.0).hypot(plan.path[i][1] - 5.0);
                d(a).total_cmp(&d(b))
            })
            .expect("a lane point");
        let far = (0..plan.path.len())
            // The middle of the first lane: 4 m (2.7 σ) from the blob and 10 m from either corner.
            .find(|&i| plan.on_lane[i] && (plan.path[i][0] - 10.0).abs() < 0.3 && plan.path[i][1] < 2.0)
            .expect("a far lane point");
        assert!(prof.speed_mps[near] < 0.7, "over the blob {}", prof.speed_mps[near]);
        assert!(prof.speed_mps[far] > 4.9, "far from it {}", prof.speed_mps[far]);
        assert!(prof.law.speed(1.0) <= 0.5 + 1e-9, "A = 1 is flown at v_min");
    }

    #[test]
    fn a_ridge_slows_the_drone_where_the_path_bends_over_it() {
        // A sharp ridge across the lanes at x = 10 m: 2 m high over 1 m.
        let (plan, _) = plan_over(|x, _| (2.0 - 4.0 * (x - 10.0).abs()).max(0.0));
        let prof = profile_drone(&plan, None, &limits(), &VerticalLimits::default()).expect("profile");
        let crest = (0..plan.path.len())
            .find(|&i| plan.on_lane[i] && (plan.path[i][0] - 10.0).abs() < 0.2 && i > 2)
            .expect("the crest");
        assert!(prof.speed_mps[crest] < 4.0, "over the crest {}", prof.speed_mps[crest]);
    }

    #[test]
    fn climbs_and_descents_keep_their_own_limits() {
        // Rolling hills across the lanes: grades up to ±0.5 (a 1.5 m swell every 6π m).
        let (plan, _) = plan_over(|x, _| 2.0 + 1.5 * (x / 3.0).sin());
        let free = profile_drone(&plan, None, &limits(), &VerticalLimits::default()).expect("profile");
        let (up, down) = vertical_speeds(&plan.path, &free.time_s);
        assert!(
            up > 1.0 && down > 1.0,
            "unlimited, the hills are flown fast: {up} up, {down} down"
        );
        let vertical = VerticalLimits {
            climb_mps: Some(1.0),
            descent_mps: Some(0.6),
        };
        let held = profile_drone(&plan, None, &limits(), &vertical).expect("profile");
        let (up, down) = vertical_speeds(&plan.path, &held.time_s);
        assert!(up <= 1.0 + 1e-9 && down <= 0.6 + 1e-9, "{up} up, {down} down");
        assert!(held.duration_s() > free.duration_s());
        assert!(held.speed_mps.iter().all(|&v| v >= limits().v_min_mps - 1e-12));
        for bad in [-1.0, 0.0, f64::NAN] {
            let v = VerticalLimits {
                climb_mps: Some(bad),
                descent_mps: None,
            };
            let err = profile_drone(&plan, None, &limits(), &v).expect_err("refused");
            assert!(err.to_string().contains("max_climb_mps"), "{err}");
        }
    }
}
