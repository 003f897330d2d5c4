//! RFICP speed planning (seed 000 §V) on a finished path: smooth it ([`crate::smooth`]), sample it, give
//! every sample the speed its attribute asks for ([`dwell`]), bound the acceleration ([`time_param`]),
//! simulate the deposit and correct the speeds ([`refine`]), then time-stamp the waypoints and measure
//! coverage, collisions and dwell uniformity again (`metrics`).
//!
//! [`profile_path`] is the entry point; it post-processes `pipeline::plan`'s waypoints and never changes
//! which cells the path covers except by corner rounding that loses none.

pub mod attribute;
pub mod dwell;
pub mod estimate;
pub mod field;
pub mod limits;
pub mod refine;
pub mod samples;
pub mod time_param;

#[cfg(test)]
mod proptests;

pub use attribute::{AttributeBlob, AttributeMap};
pub use dwell::DwellLaw;
pub use limits::SpeedLimits;
pub use samples::PathSamples;

use crate::error::{PlannerError, Result};
use crate::geom::Point2;
use crate::metrics::dwell::DwellMetrics;
use crate::metrics::{PlanMetrics, evaluate};
use crate::pipeline::Waypoint;
use crate::smooth::{SmoothParams, SmoothedPath, round_corners_where};
use crate::space::CoverageSpace;

/// Knobs of [`profile_path`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedParams {
    /// Speed and acceleration limits.
    pub limits: SpeedLimits,
    /// Corner rounding; `None` keeps the path as it is.
    pub smooth: Option<SmoothParams>,
    /// Largest distance between output waypoints, metres; `None` = tool_width / 4 (half the kernel σ).
    pub spacing_m: Option<f64>,
    /// Closed-loop refinement steps (0 = the open-loop law). Without an attribute map there is nothing to
    /// follow and no refinement: v_max, capped by curvature and acceleration.
    pub refine_iterations: usize,
    /// Share of the open-loop duration the refinement may add to make the deposit uniform (0.5 = up to 50 %
    /// longer); see [`refine::refine`].
    pub extra_time: f64,
    /// The attribute range `(lowest, highest)` the speed law is set for ([`DwellLaw::for_range`]); `None` =
    /// the range over the space's coverable cells. A fleet passes its whole site's range, so that every
    /// robot serves the same attribute with the same dwell, whatever part it got.
    pub attribute_range: Option<(f64, f64)>,
}

impl SpeedParams {
    /// Defaults for `limits` and a tool of width `tool_width_m`: smoothing on, 10 refinement steps, up to 50 % extra time.
    pub fn new(limits: SpeedLimits, tool_width_m: f64) -> Self {
        Self {
            limits,
            smooth: Some(SmoothParams::for_tool(tool_width_m)),
            spacing_m: None,
            refine_iterations: 10,
            extra_time: 0.5,
            attribute_range: None,
        }
    }

    /// The largest distance between output waypoints for a tool `tool_width_m` wide (see `spacing_m`).
    pub fn spacing_for(&self, tool_width_m: f64) -> f64 {
        self.spacing_m.unwrap_or(tool_width_m / 4.0)
    }
}

/// A waypoint with its speed and time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimedWaypoint {
    /// Position, kind and region.
    pub waypoint: Waypoint,
    /// Speed at this waypoint, m/s.
    pub speed_mps: f64,
    /// Time from the start of the path, seconds.
    pub time_s: f64,
    /// Arc length from the start of the path, metres.
    pub arc_m: f64,
}

/// A profiled path and what it achieves.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedProfile {
    /// The smoothed, sampled, timed path.
    pub waypoints: Vec<TimedWaypoint>,
    /// DESIGN §6 metrics of the smoothed path (coverage, collisions…).
    pub metrics: PlanMetrics,
    /// Dwell uniformity and duration.
    pub dwell: DwellMetrics,
    /// The speed law used (k, C_target, λ).
    pub law: DwellLaw,
    /// Corners rounded by smoothing.
    pub rounded_corners: usize,
    /// Corners kept sharp.
    pub sharp_corners: usize,
    /// True when smoothing was discarded because the smoothed path did worse than the input.
    pub smoothing_reverted: bool,
    /// Dwell CV before refinement (open-loop law); NaN without an attribute map (as the CVs of `dwell`).
    pub open_loop_dwell_cv: f64,
}

impl SpeedProfile {
    /// The positions.
    pub fn points(&self) -> Vec<Point2> {
        self.waypoints.iter().map(|w| w.waypoint.position).collect()
    }
}

/// Profiles a finished path (`pipeline::PlanOutput::waypoints`) on `space`: smoothing, speeds from
/// `attribute` (A = 1 everywhere when `None`), acceleration limits, closed-loop refinement, times and metrics.
/// The attribute must have the space's grid geometry.
pub fn profile_path(
    space: &CoverageSpace,
    path: &[Waypoint],
    attribute: Option<&AttributeMap>,
    params: &SpeedParams,
) -> Result<SpeedProfile> {
    profile_path_where(space, path, attribute, params, &|_| true)
}

/// [`profile_path`], rounding a corner only where `corner_ok` accepts the curve's samples too (map frame,
/// metres; see [`crate::smooth::round_corners_where`]).
pub fn profile_path_where(
    space: &CoverageSpace,
    path: &[Waypoint],
    attribute: Option<&AttributeMap>,
    params: &SpeedParams,
    corner_ok: &dyn Fn(&[Point2]) -> bool,
) -> Result<SpeedProfile> {
    let limits = params.limits;
    limits.validate()?;
    let g = *space.geometry();
    let uniform;
    let has_attribute = attribute.is_some();
    let attribute = match attribute {
        Some(a) if a.geometry() != &g => {
            return Err(PlannerError::InvalidParam {
                name: "attribute",
                reason: format!(
                    "grid {} × {} at {} m does not match the map's {} × {} at {} m",
                    a.geometry().width,
                    a.geometry().height,
                    a.geometry().resolution,
                    g.width,
                    g.height,
                    g.resolution
                ),
            });
        }
        Some(a) => a,
        None => {
            uniform = AttributeMap::uniform(g, 1.0);
            &uniform
        }
    };
    let w = space.robot.tool_width_m;
    let spacing = params.spacing_for(w);
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(PlannerError::InvalidParam {
            name: "spacing",
            reason: format!("must be a positive number of metres, got {spacing}"),
        });
    }
    let original: Vec<Point2> = path.iter().map(|w| w.position).collect();
    let before = evaluate(space, &original);
    let sharp_everywhere = || SmoothedPath {
        waypoints: path.to_vec(),
        curvature: (0..path.len()).map(|i| vertex_curvature(&original, i)).collect(),
        rounded: 0,
        kept_sharp: 0,
    };
    let (smoothed, metrics, reverted) = match &params.smooth {
        Some(sp) => {
            let s = round_corners_where(space, path, sp, corner_ok);
            let pts: Vec<Point2> = s.waypoints.iter().map(|w| w.position).collect();
            let m = evaluate(space, &pts);
            if m.collisions > before.collisions || m.covered_coverable_cells < before.covered_coverable_cells {
                (sharp_everywhere(), before, true)
            } else {
                (s, m, false)
            }
        }
        None => (sharp_everywhere(), before, false),
    };
    let samples = samples::resample(&smoothed, spacing, &limits);
    let (a_lo, a_hi) = params
        .attribute_range
        .or_else(|| attribute.range_over(&space.coverable))
        .unwrap_or((1.0, 1.0));
    let law = DwellLaw::for_range(a_lo, a_hi, w, &limits);
    let targets: Vec<f64> = samples
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // Transits run with the tool off: full speed, within the caps.
            let works = (i > 0 && samples.working[i - 1]) || samples.working.get(i).copied().unwrap_or(false);
            if works {
                law.speed(attribute.at_point(*p))
            } else {
                limits.v_max_mps
            }
        })
        .collect();
    let metric_floor = metric_attribute_floor(a_hi, &limits);
    let (speeds, dwell, open_loop_dwell_cv) = if has_attribute {
        let refined = refine::refine(
            space,
            &samples,
            attribute,
            &law,
            &limits,
            metric_floor,
            targets,
            params.refine_iterations,
            params.extra_time,
        );
        // The refinement simulated the kept speeds' deposit and the constant-speed one on these samples, as
        // `metrics::dwell::evaluate_dwell` would (a test holds them equal); the duration is filled in below.
        let dwell = DwellMetrics {
            dwell_cv: refined.dwell_cv,
            dwell_cv_const_speed: refined.constant_speed_cv,
            duration_s: 0.0,
        };
        (refined.speeds_mps, dwell, refined.open_loop_cv)
    } else {
        // No attribute map: the fastest profile the limits allow, and no uniformity figures (DESIGN §6 defines
        // dwell CV against an attribute map; against A = 1 it would cost deposit fields over the whole grid
        // for a figure nobody reads).
        let speeds = refine::capped_speeds(&samples, &targets, limits.a_max_mps2);
        let dwell = DwellMetrics {
            dwell_cv: f64::NAN,
            dwell_cv_const_speed: f64::NAN,
            duration_s: 0.0,
        };
        (speeds, dwell, f64::NAN)
    };
    let t = time_param::times(&speeds, &samples.seg);
    let dwell = DwellMetrics {
        duration_s: t.last().copied().unwrap_or(0.0),
        ..dwell
    };
    Ok(SpeedProfile {
        waypoints: timed(&samples, &speeds, &t),
        metrics,
        dwell,
        law,
        rounded_corners: smoothed.rounded,
        sharp_corners: smoothed.kept_sharp,
        smoothing_reverted: reverted,
        open_loop_dwell_cv,
    })
}

/// The timed waypoints of `samples` driven at `speeds` (m/s), reaching each at `t` (s).
fn timed(samples: &PathSamples, speeds: &[f64], t: &[f64]) -> Vec<TimedWaypoint> {
    let mut arc = 0.0;
    (0..samples.points.len())
        .map(|i| {
            if i > 0 {
                arc += samples.seg[i - 1];
            }
            TimedWaypoint {
                waypoint: Waypoint {
                    position: samples.points[i],
                    kind: samples.kinds[i],
                    region: samples.regions[i],
                },
                speed_mps: speeds[i],
                time_s: t[i],
                arc_m: arc,
            }
        })
        .collect()
}

/// The attribute floor of the dwell-uniformity metric for attributes up to `a_hi`: a_hi · v_min / v_max, the
/// least attribute the robot can still serve in proportion to the most demanding one (below it, one pass at
/// v_max already deposits more than the desire). It depends only on the map and the robot, not on the
/// profile, so the profiled and the constant-speed figures are measured alike.
pub fn metric_attribute_floor(a_hi: f64, limits: &SpeedLimits) -> f64 {
    let f = a_hi * limits.v_min_mps / limits.v_max_mps;
    if f > 1e-9 && f.is_finite() { f.min(1.0) } else { 1.0 }
}

/// Curvature of an unsmoothed polyline at vertex `i`: ∞ at a corner of 1° or more, else 0.
fn vertex_curvature(points: &[Point2], i: usize) -> f64 {
    if i == 0 || i + 1 >= points.len() {
        return 0.0;
    }
    let (a, b) = (points[i] - points[i - 1], points[i + 1] - points[i]);
    if a.norm() < 1e-9 || b.norm() < 1e-9 {
        return 0.0;
    }
    if crate::geom::heading_change(a, b) >= 1f64.to_radians() {
        f64::INFINITY
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::pipeline::WaypointKind;
    use crate::space::RobotShape;

    fn space() -> CoverageSpace {
        let g = GridGeometry::new(40, 20, 0.1, Point2::origin()).expect("valid");
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        CoverageSpace::new(OccupancyGrid::filled(g, CellState::Free), robot, Point2::new(1.0, 1.0)).expect("space")
    }

    #[test]
    fn degenerate_paths_and_bad_input() {
        let s = space();
        let params = SpeedParams::new(SpeedLimits::default(), 0.4);
        assert!(
            profile_path(&s, &[], None, &params)
                .expect("empty")
                .waypoints
                .is_empty()
        );
        let one = [Waypoint {
            position: s.start,
            kind: WaypointKind::Transit,
            region: None,
        }];
        let p = profile_path(&s, &one, None, &params).expect("one point");
        assert_eq!(p.waypoints.len(), 1);
        assert_eq!(p.waypoints[0].time_s, 0.0);
        let bad = SpeedParams::new(SpeedLimits::new(1.0, 0.5, 0.5), 0.4);
        assert!(profile_path(&s, &one, None, &bad).is_err());
        let nan = SpeedParams::new(SpeedLimits::new(0.1, f64::NAN, 0.5), 0.4);
        assert!(profile_path(&s, &one, None, &nan).is_err());
        let other = AttributeMap::uniform(GridGeometry::new(5, 5, 0.1, Point2::origin()).expect("valid"), 0.5);
        assert!(profile_path(&s, &one, Some(&other), &params).is_err());
    }

    #[test]
    fn without_attribute_drives_at_v_max_between_corners() {
        let s = space();
        let w = |x: f64, y: f64| Waypoint {
            position: Point2::new(x, y),
            kind: WaypointKind::Cover,
            region: Some(0),
        };
        let p = profile_path(
            &s,
            &[w(0.3, 1.0), w(3.7, 1.0)],
            None,
            &SpeedParams::new(SpeedLimits::default(), 0.4),
        )
        .expect("profile");
        let top = p.waypoints.iter().map(|w| w.speed_mps).fold(0.0, f64::max);
        // 3.4 m with v_min at both ends and a_max 0.5: the peak is reached in the middle, √(0.01 + 2·0.5·1.7).
        assert!((top - (0.01f64 + 1.7).sqrt().min(1.0)).abs() < 0.05, "{top}");
        assert_eq!(p.waypoints.first().map(|w| w.speed_mps), Some(0.1));
        assert!(p.dwell.duration_s > 3.4);
    }
}
