//! A planar laser at the robot's centre: ranges ray-cast against the hidden world.

use shift_planner::geom::Point2;

use crate::drive::DiffDrive;
use crate::world::World;

/// The scanner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lidar {
    /// Beams over the full turn (counter-clockwise from the robot's heading).
    pub beams: usize,
    /// Shortest range reported, metres.
    pub range_min: f64,
    /// Longest range, metres (beyond it: no return, +inf).
    pub range_max: f64,
}

impl Default for Lidar {
    fn default() -> Self {
        Self {
            beams: 360,
            range_min: 0.05,
            range_max: 10.0,
        }
    }
}

impl Lidar {
    /// Angle between beams, radians.
    pub fn increment(&self) -> f64 {
        std::f64::consts::TAU / self.beams.max(1) as f64
    }

    /// One scan from `body`: a range per beam (`f32::INFINITY` when nothing is within `range_max`).
    pub fn scan(&self, world: &World, body: &DiffDrive) -> Vec<f32> {
        let origin = Point2::new(body.x, body.y);
        (0..self.beams)
            .map(|i| {
                let a = body.yaw + i as f64 * self.increment();
                match world.cast(origin, (a.cos(), a.sin()), self.range_max) {
                    Some(t) if t >= self.range_min => t as f32,
                    Some(_) => self.range_min as f32,
                    None => f32::INFINITY,
                }
            })
            .collect()
    }

    /// The returns of a scan as points in the robot frame (x ahead, y left).
    pub fn points(&self, ranges: &[f32]) -> Vec<(f64, f64)> {
        ranges
            .iter()
            .enumerate()
            .filter(|(_, r)| r.is_finite())
            .map(|(i, &r)| {
                let a = i as f64 * self.increment();
                (f64::from(r) * a.cos(), f64::from(r) * a.sin())
            })
            .collect()
    }
}
