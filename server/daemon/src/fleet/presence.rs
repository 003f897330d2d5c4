//! Presence of robots that have no SHIFT liveliness token (ROS 2 mappings: zenoh-bridge-ros2dds, rmw_zenoh).
//! The rule: a robot is alive from its first message on any of its data keys (odometry, cloud, scan) and lost
//! once `robot_timeout_s` pass without one; a later message makes it alive again. The changes reach the
//! engine as the same `RobotLiveliness` events a token would cause.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Last message per robot and whether it is reported alive.
#[derive(Debug)]
pub struct Presence {
    timeout: Duration,
    robots: Mutex<HashMap<String, Seen>>,
}

#[derive(Debug, Clone, Copy)]
struct Seen {
    last: Instant,
    alive: bool,
}

impl Presence {
    /// Robots are lost after `timeout` without a message.
    pub fn new(timeout: Duration) -> Self {
        Self {
            timeout,
            robots: Mutex::new(HashMap::new()),
        }
    }

    /// Records a message from `robot` at `now`; true when the robot was not alive (the caller reports it alive
    /// and confirms with [`Presence::reported_alive`], so a report lost to a full inbox is retried).
    pub fn seen(&self, robot: &str, now: Instant) -> bool {
        let Ok(mut m) = self.robots.lock() else { return false };
        match m.get_mut(robot) {
            Some(s) => {
                s.last = now;
                !s.alive
            }
            None => {
                m.insert(
                    robot.to_owned(),
                    Seen {
                        last: now,
                        alive: false,
                    },
                );
                true
            }
        }
    }

    /// The engine was told `robot` is alive.
    pub fn reported_alive(&self, robot: &str) {
        if let Ok(mut m) = self.robots.lock()
            && let Some(s) = m.get_mut(robot)
        {
            s.alive = true;
        }
    }

    /// Robots alive whose last message is older than the timeout at `now`; they are marked lost.
    pub fn expire(&self, now: Instant) -> Vec<String> {
        let Ok(mut m) = self.robots.lock() else {
            return Vec::new();
        };
        let mut lost = Vec::new();
        for (robot, s) in m.iter_mut() {
            if s.alive && now.saturating_duration_since(s.last) > self.timeout {
                s.alive = false;
                lost.push(robot.clone());
            }
        }
        lost.sort();
        lost
    }

    /// How often [`Presence::expire`] should run: a quarter of the timeout, between 50 ms and 1 s.
    pub fn sweep_every(&self) -> Duration {
        (self.timeout / 4).clamp(Duration::from_millis(50), Duration::from_secs(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alive_on_first_message_lost_after_timeout_back_on_next() {
        let p = Presence::new(Duration::from_secs(2));
        let t0 = Instant::now();
        assert!(p.seen("bot1", t0), "first message: report alive");
        assert!(p.seen("bot1", t0), "not yet confirmed: report again");
        p.reported_alive("bot1");
        assert!(!p.seen("bot1", t0 + Duration::from_secs(1)));
        assert!(
            p.expire(t0 + Duration::from_millis(2900)).is_empty(),
            "1.9 s since the last"
        );
        assert_eq!(p.expire(t0 + Duration::from_millis(3100)), vec!["bot1".to_owned()]);
        assert!(p.expire(t0 + Duration::from_secs(9)).is_empty(), "reported lost once");
        assert!(p.seen("bot1", t0 + Duration::from_secs(10)), "back");
        assert_eq!(p.sweep_every(), Duration::from_millis(500));
    }
}
