//! Simulated time: steps of simulated time paced against the wall clock at `speedup` simulated seconds per
//! real second, and message stamps on the simulated clock (one epoch, so odometry and scans agree).

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// The simulation's clock.
#[derive(Debug, Clone, Copy)]
pub struct SimClock {
    start: Instant,
    epoch_ns: i64,
    speedup: f64,
}

impl SimClock {
    /// A clock starting now; `speedup` ≤ 0 or non-finite means as fast as the machine goes.
    pub fn start(speedup: f64) -> Self {
        let epoch_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
            .unwrap_or(0);
        Self {
            start: Instant::now(),
            epoch_ns,
            speedup,
        }
    }

    /// The same epoch (stamps unchanged), paced from now on: simulated time 0 is due now.
    pub fn pace_from_now(self) -> Self {
        Self {
            start: Instant::now(),
            ..self
        }
    }

    /// The stamp of simulated time `t` (seconds since the start), nanoseconds since the UNIX epoch.
    pub fn stamp_ns(&self, t: f64) -> i64 {
        self.epoch_ns.saturating_add((t * 1e9) as i64)
    }

    /// The wall-clock instant at which simulated time `t` is due (`None`: no pacing).
    pub fn due(&self, t: f64) -> Option<Instant> {
        (self.speedup.is_finite() && self.speedup > 0.0)
            .then(|| self.start + Duration::from_secs_f64((t / self.speedup).max(0.0)))
    }

    /// Wall-clock seconds since the start.
    pub fn wall_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_and_deadlines_follow_the_speedup() {
        let c = SimClock::start(10.0);
        assert_eq!(c.stamp_ns(1.5) - c.stamp_ns(0.0), 1_500_000_000);
        let due = c.due(20.0).expect("paced");
        assert_eq!(due - c.start, Duration::from_secs(2));
        assert_eq!(SimClock::start(0.0).due(5.0), None);
    }
}
