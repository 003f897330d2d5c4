//! Closing the loop (seed 000 §V.B.5): simulate the deposit field of the profiled path (eq. 21), compare it
//! with the desired field k·A (eq. 22) and correct the speeds by a few fixed-point iterations.
//!
//! The update is Richardson–Lucy's multiplicative step for a non-negative deconvolution: with the simulated
//! deposit D, the desired deposit D* and the coverable mask m, each sample's dwell per metre is multiplied by
//! r_i = [G * (m · D*/D)](p_i) / [G * m](p_i), the kernel-weighted mismatch its own deposit lands on. Where
//! neighbouring passes (boundary passes, steps between lanes, transits) already deposit too much, the robot
//! speeds up; where it falls short, it slows down. Each step is limited to a factor of two, the targets stay
//! in [v_min, v_max], and the acceleration pass runs after every step. The iterate with the lowest dwell CV
//! (metrics::dwell::field_cv) is kept, so refinement never makes the plan worse than the open-loop law.

use crate::metrics::dwell::{constant_speed_cv, field_cv};
use crate::space::CoverageSpace;

use super::AttributeMap;
use super::dwell::DwellLaw;
use super::field::{deposit_field, gaussian_blur, sample_bilinear};
use super::time_param::{limit_acceleration, segment_duration};
use super::{PathSamples, SpeedLimits};

/// Largest factor one iteration may change a sample's speed by.
const MAX_STEP: f64 = 2.0;

/// The dwell CV the refinement aims at, as a share of the same path's CV at constant speed: the issue-18 bar
/// is one half; aiming a fifth inside it leaves room for an independent evaluator's discretisation.
pub const UNIFORMITY_GOAL: f64 = 0.4;

/// Outcome of the refinement.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// Speed per sample, m/s.
    pub speeds_mps: Vec<f64>,
    /// Dwell CV of the kept iterate.
    pub dwell_cv: f64,
    /// Dwell CV of the same path at constant speed ([`constant_speed_cv`]).
    pub constant_speed_cv: f64,
    /// Dwell CV of iteration 0 (the open-loop law).
    pub open_loop_cv: f64,
    /// Index of the kept iterate (0 = open loop).
    pub kept_iteration: usize,
}

/// One simulated profile: speeds after the acceleration pass, their deposit field and its dwell CV.
struct Simulated {
    speeds: Vec<f64>,
    deposit: Vec<f64>,
    cv: f64,
}

struct Simulator<'a> {
    space: &'a CoverageSpace,
    samples: &'a PathSamples,
    attribute: &'a AttributeMap,
    a_max: f64,
    floor: f64,
}

impl Simulator<'_> {
    fn run(&self, targets: &[f64]) -> Simulated {
        let g = self.space.geometry();
        let speeds = capped_speeds(self.samples, targets, self.a_max);
        let durations: Vec<f64> = self
            .samples
            .seg
            .iter()
            .enumerate()
            .map(|(k, s)| {
                if self.samples.working[k] {
                    segment_duration(*s, speeds[k], speeds[k + 1])
                } else {
                    0.0
                }
            })
            .collect();
        let deposit = deposit_field(g, &self.samples.points, &durations, self.space.robot.tool_width_m / 2.0);
        let cv = field_cv(self.space, &deposit, self.attribute, self.floor);
        Simulated { speeds, deposit, cv }
    }
}

/// The speeds a robot drives `samples` at when it aims at `targets` (m/s): each within its sample's cap,
/// then the acceleration pass (`a_max`, m/s²).
pub fn capped_speeds(samples: &PathSamples, targets: &[f64], a_max: f64) -> Vec<f64> {
    let caps: Vec<f64> = targets.iter().zip(&samples.caps).map(|(t, c)| t.min(*c)).collect();
    limit_acceleration(&caps, &samples.seg, a_max)
}

/// Runs `iterations` refinement steps from the open-loop speed targets `targets` (m/s, already within the
/// caps of `samples`). `metric_floor` is the attribute floor of the uniformity metric.
///
/// Each step is one Richardson–Lucy update followed by a common speed factor that sets the plan's duration
/// to the open-loop law's times (1 + e). The open-loop law is time-optimal and leaves no room: the floor of
/// the attribute already drives at v_max, so the over-deposit of passes that overlap and of the slow-downs
/// at corners can only be balanced by dwelling longer elsewhere. `extra_time` is the most the caller lets the
/// plan take for uniformity; the time is then moved to where the deposit is short. (Unbounded, the CV would
/// keep falling by drowning the corners' slow spots in a uniformly slow plan.)
///
/// Time is the objective (DESIGN §6), uniformity a bar: e grows by equal steps from the first iteration's
/// share to `extra_time` at the last, and the refinement stops at the first iterate whose CV is within
/// [`UNIFORMITY_GOAL`] of the constant-speed CV of the same path (the open-loop law itself when it already
/// is). Only when no iterate gets there is the one with the lowest CV kept. So a path pays the extra time
/// its uniformity needs, not a fixed 50 %; and the duration grows smoothly with what a path needs, which a
/// fleet's balance relies on (a fixed surcharge paid or not by the luck of one iterate made two nearly
/// equal parts differ by half).
#[allow(clippy::too_many_arguments)]
pub fn refine(
    space: &CoverageSpace,
    samples: &PathSamples,
    attribute: &AttributeMap,
    law: &DwellLaw,
    limits: &SpeedLimits,
    metric_floor: f64,
    mut targets: Vec<f64>,
    iterations: usize,
    extra_time: f64,
) -> Refined {
    let g = *space.geometry();
    let sigma = space.robot.tool_width_m / 2.0;
    let sim = Simulator {
        space,
        samples,
        attribute,
        a_max: limits.a_max_mps2,
        floor: metric_floor,
    };
    let clamp = |v: f64| v.clamp(limits.v_min_mps, limits.v_max_mps);
    let mask: Vec<f64> = space.coverable.iter().map(|&c| f64::from(u8::from(c))).collect();
    let blurred_mask = gaussian_blur(&g, &mask, sigma);
    let mut current = sim.run(&targets);
    let open_loop_cv = current.cv;
    let open_loop_s = duration(samples, &current.speeds);
    let constant_cv = constant_speed_cv(space, &samples.points, &samples.working, attribute, metric_floor);
    let cv_goal = UNIFORMITY_GOAL * constant_cv;
    let mut best = Refined {
        speeds_mps: current.speeds.clone(),
        dwell_cv: current.cv,
        constant_speed_cv: constant_cv,
        open_loop_cv,
        kept_iteration: 0,
    };
    for it in 1..=iterations {
        if best.dwell_cv <= cv_goal {
            break;
        }
        let deposit = &current.deposit;
        // The CV does not depend on the scale of the desire, so the desire is rescaled to the deposit's
        // total: only its shape is matched.
        let (mut have, mut want) = (0.0, 0.0);
        for (i, &d) in deposit.iter().enumerate() {
            if space.coverable[i] {
                have += d;
                want += law.desired(attribute.at(i));
            }
        }
        let scale = if want > 0.0 { have / want } else { 1.0 };
        let ratio: Vec<f64> = deposit
            .iter()
            .enumerate()
            .map(|(i, &d)| {
                if space.coverable[i] {
                    let want = scale * law.desired(attribute.at(i));
                    want / d.max(want * 1e-3)
                } else {
                    0.0
                }
            })
            .collect();
        let blurred_ratio = gaussian_blur(&g, &ratio, sigma);
        for (i, p) in samples.points.iter().enumerate() {
            // Samples that only end or start transits keep their target (the tool is off there).
            let works = (i > 0 && samples.working[i - 1]) || samples.working.get(i).copied().unwrap_or(false);
            if !works {
                continue;
            }
            let m = sample_bilinear(&g, &blurred_mask, *p);
            if m < 1e-3 {
                continue;
            }
            let r = (sample_bilinear(&g, &blurred_ratio, *p) / m).clamp(1.0 / MAX_STEP, MAX_STEP);
            // Dwell per metre × r  ⇔  speed ÷ r.
            targets[i] = clamp(targets[i] / r);
        }
        let share = extra_time.max(0.0) * it as f64 / iterations as f64;
        targets = fit_duration(samples, &targets, limits, open_loop_s * (1.0 + share));
        current = sim.run(&targets);
        if current.cv < best.dwell_cv {
            best = Refined {
                speeds_mps: current.speeds.clone(),
                dwell_cv: current.cv,
                constant_speed_cv: constant_cv,
                open_loop_cv,
                kept_iteration: it,
            };
        }
    }
    best
}

/// Seconds to drive the samples at `speeds` (uniform acceleration between samples).
fn duration(samples: &PathSamples, speeds: &[f64]) -> f64 {
    samples
        .seg
        .iter()
        .enumerate()
        .map(|(k, s)| segment_duration(*s, speeds[k], speeds[k + 1]))
        .sum()
}

/// The targets times a common factor (clamped to the limits) whose acceleration-limited profile takes
/// `goal_s` seconds, found by bisection on the factor's logarithm (duration falls as the factor grows).
fn fit_duration(samples: &PathSamples, targets: &[f64], limits: &SpeedLimits, goal_s: f64) -> Vec<f64> {
    let scaled = |f: f64| -> Vec<f64> {
        targets
            .iter()
            .map(|v| (v * f).clamp(limits.v_min_mps, limits.v_max_mps))
            .collect()
    };
    let time_of = |t: &[f64]| {
        let caps: Vec<f64> = t.iter().zip(&samples.caps).map(|(a, c)| a.min(*c)).collect();
        duration(samples, &limit_acceleration(&caps, &samples.seg, limits.a_max_mps2))
    };
    let (mut lo, mut hi) = ((1.0f64 / 64.0).ln(), 64f64.ln());
    // 24 halvings of a factor-4096 bracket: the factor is known to 1e-6 relative.
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if time_of(&scaled(mid.exp())) > goal_s {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    scaled(hi.exp())
}
