//! The robot's speed and acceleration limits: what every speed profile and the time objective obey.

use crate::error::{PlannerError, Result};

/// The robot's speed limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLimits {
    /// Slowest speed on the path, m/s (> 0: the robot never stops on the path).
    pub v_min_mps: f64,
    /// Fastest speed, m/s.
    pub v_max_mps: f64,
    /// Largest tangential acceleration or deceleration, m/s².
    pub a_max_mps2: f64,
    /// Largest lateral (centripetal) acceleration in curves, m/s².
    pub a_lat_mps2: f64,
}

impl SpeedLimits {
    /// Limits with the lateral bound equal to `a_max_mps2`.
    pub fn new(v_min_mps: f64, v_max_mps: f64, a_max_mps2: f64) -> Self {
        Self {
            v_min_mps,
            v_max_mps,
            a_max_mps2,
            a_lat_mps2: a_max_mps2,
        }
    }

    /// Checks 0 < v_min ≤ v_max, a_max > 0, a_lat > 0, all finite.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("v_min", self.v_min_mps),
            ("v_max", self.v_max_mps),
            ("a_max", self.a_max_mps2),
            ("a_lat", self.a_lat_mps2),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(PlannerError::InvalidParam {
                    name,
                    reason: format!("must be a positive finite number, got {v}"),
                });
            }
        }
        if self.v_min_mps > self.v_max_mps {
            return Err(PlannerError::InvalidParam {
                name: "v_min",
                reason: format!("{} m/s exceeds v_max {} m/s", self.v_min_mps, self.v_max_mps),
            });
        }
        Ok(())
    }
}

impl Default for SpeedLimits {
    /// v_min 0.1 m/s, v_max 1.0 m/s, a_max = a_lat = 0.5 m/s².
    fn default() -> Self {
        Self::new(0.1, 1.0, 0.5)
    }
}
