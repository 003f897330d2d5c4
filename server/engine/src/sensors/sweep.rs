//! What a laser scan saw *through*: each ray crossed free space from the laser up to its return (or up to the
//! laser's reach when it met nothing). The live map uses it to forget obstacles that are no longer there — a
//! person who walked across an aisle leaves a trail of points that would otherwise stand as a wall until the
//! horizon expires them (Nav2's obstacle layer clears by ray tracing for the same reason).
//!
//! Only scans carry this: a PointCloud2 has no ray structure here, so cloud points leave by the horizon.
//!
//! Which rays count as free: a finite range within `[range_min, range_max]` is free up to that range; `+inf`
//! (REP 117: no return within reach) is free up to `range_max`; NaN, `-inf` and ranges below `range_min` (the
//! laser saw nothing it could measure, or something too close) clear nothing.

use shift_proto::ros::LaserScan;

use super::geometry::SensorOffset;
use crate::robots::Pose2;

/// Longest reach a sweep trusts, metres (a scan declaring more is clipped to this).
pub const MAX_REACH_M: f64 = 30.0;

/// A scan's rays in the map frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// The laser's position, map frame, metres.
    pub origin: [f64; 2],
    /// Heading of ray 0, map frame, radians.
    pub angle_min: f64,
    /// Angle between rays, radians (non-zero; negative for a clockwise scan).
    pub increment: f64,
    /// Per ray, how far it saw free space, metres (0: nothing).
    pub reach: Vec<f32>,
}

impl Sweep {
    /// The sweep of `scan` taken by a robot at `pose` with its laser at `offset`, or `None` when the scan's
    /// geometry is unusable (non-finite or zero increment, no rays, a non-positive reach).
    pub fn of_scan(scan: &LaserScan, pose: Pose2, offset: SensorOffset) -> Option<Self> {
        let increment = f64::from(scan.angle_increment);
        let angle_min = f64::from(scan.angle_min);
        let (lo, hi) = (f64::from(scan.range_min), f64::from(scan.range_max).min(MAX_REACH_M));
        let usable = increment.is_finite()
            && increment != 0.0
            && angle_min.is_finite()
            && lo.is_finite()
            && hi > 0.0
            && hi >= lo
            && !scan.ranges.is_empty()
            && [pose.x, pose.y, pose.yaw].iter().all(|v| v.is_finite());
        if !usable {
            return None;
        }
        let reach = scan
            .ranges
            .iter()
            .map(|&r| {
                let r = f64::from(r);
                let free = if r == f64::INFINITY {
                    hi
                } else if r.is_finite() && r >= lo {
                    r.min(hi)
                } else {
                    0.0
                };
                free as f32
            })
            .collect();
        let (s, c) = pose.yaw.sin_cos();
        Some(Self {
            origin: [
                pose.x + c * offset.x_m - s * offset.y_m,
                pose.y + s * offset.x_m + c * offset.y_m,
            ],
            angle_min: pose.yaw + offset.yaw_rad + angle_min,
            increment,
            reach,
        })
    }

    /// The farthest any ray saw, metres.
    pub fn max_reach(&self) -> f64 {
        self.reach.iter().copied().fold(0.0_f32, f32::max).into()
    }

    /// True when the rays either side of the bearing of `p` (map frame) both saw free space more than `margin`
    /// beyond it: whatever was at `p` is gone. Points within `margin` of the laser are never judged.
    pub fn sees_past(&self, p: [f64; 2], margin: f64) -> bool {
        let (dx, dy) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        let d = dx.hypot(dy);
        if !d.is_finite() || d <= margin {
            return false;
        }
        let turn = std::f64::consts::TAU;
        // Fractional ray index of the bearing, counted in the scan's own direction.
        let rel = (dy.atan2(dx) - self.angle_min).rem_euclid(turn);
        let rel = if self.increment > 0.0 { rel } else { turn - rel };
        let mut f = rel / self.increment.abs();
        // A bearing on a ray, up to rounding of the scan's f32 angles, is that ray's alone.
        if (f - f.round()).abs() < 1e-6 {
            f = f.round();
        }
        let n = self.reach.len();
        let (i0, i1) = (f.floor(), f.ceil());
        if i1 >= n as f64 {
            return false;
        }
        let need = (d + margin) as f32;
        self.reach[i0 as usize] > need && self.reach[i1 as usize] > need
    }
}

/// A test scan: `ranges` from `angle_min`, `increment` apart, valid between 0.1 and 10 m.
#[cfg(test)]
pub(crate) fn test_scan(ranges: Vec<f32>, angle_min: f32, increment: f32) -> LaserScan {
    LaserScan {
        angle_min,
        angle_max: angle_min + increment * (ranges.len() as f32 - 1.0),
        angle_increment: increment,
        range_min: 0.1,
        range_max: 10.0,
        ranges,
        ..LaserScan::default()
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::PI;

    use super::test_scan as scan;
    use super::*;

    fn at(x: f64, y: f64, yaw: f64) -> Pose2 {
        Pose2 { x, y, yaw, stamp_ns: 0 }
    }

    #[test]
    fn a_ray_that_returned_beyond_a_point_sees_past_it() {
        // 360 rays of 1°, all returning at 4 m, robot at (1, 1) facing +y.
        let s = scan(vec![4.0; 360], -PI, PI / 180.0);
        let sw =
            Sweep::of_scan(&s, at(1.0, 1.0, std::f64::consts::FRAC_PI_2), SensorOffset::default()).expect("usable");
        assert!(sw.sees_past([1.0, 3.0], 0.1), "2 m ahead, return at 4 m");
        assert!(sw.sees_past([-1.5, 1.0], 0.1), "2.5 m to the left");
        assert!(!sw.sees_past([1.0, 4.95], 0.1), "at the return itself");
        assert!(!sw.sees_past([1.0, 7.0], 0.1), "behind the return");
        assert!(!sw.sees_past([1.05, 1.0], 0.1), "too close to the laser to judge");
    }

    #[test]
    fn invalid_ranges_clear_nothing_and_inf_clears_to_the_reach() {
        // Four rays, 90° apart, from +x: 3 m, NaN, +inf, below range_min.
        let s = scan(vec![3.0, f32::NAN, f32::INFINITY, 0.05], 0.0, PI / 2.0);
        let sw = Sweep::of_scan(&s, at(0.0, 0.0, 0.0), SensorOffset::default()).expect("usable");
        assert_eq!(sw.reach, vec![3.0, 0.0, 10.0, 0.0]);
        // Between rays 0 (3 m) and 1 (NaN): not both free.
        assert!(!sw.sees_past([1.0, 1.0], 0.1));
        // Exactly on ray 2 (-x), +inf: free to 10 m.
        assert!(sw.sees_past([-9.0, 0.0], 0.1));
        assert!(!sw.sees_past([-9.95, 0.0], 0.1));
        // Past the last ray (the scan covers 270°): nothing is judged.
        assert!(!sw.sees_past([0.5, -1.0], 0.1));
    }

    #[test]
    fn a_clockwise_scan_and_a_mounted_laser_are_placed() {
        // Rays from +90° clockwise to 0°, on a laser 0.5 m ahead of a robot at the origin facing +x; the ray
        // along +y saw 1 m, the one along +x 5 m.
        let s = scan(vec![1.0, 5.0], PI / 2.0, -PI / 2.0);
        let offset = SensorOffset {
            x_m: 0.5,
            ..SensorOffset::default()
        };
        let sw = Sweep::of_scan(&s, at(0.0, 0.0, 0.0), offset).expect("usable");
        assert_eq!(sw.origin, [0.5, 0.0]);
        assert!(sw.sees_past([2.0, 0.0], 0.1));
        assert!(!sw.sees_past([0.5, 1.5], 0.1), "the +y ray stopped at 1 m");
    }

    #[test]
    fn an_unusable_scan_has_no_sweep() {
        assert!(Sweep::of_scan(&scan(vec![], 0.0, 0.1), at(0.0, 0.0, 0.0), SensorOffset::default()).is_none());
        assert!(Sweep::of_scan(&scan(vec![1.0], 0.0, 0.0), at(0.0, 0.0, 0.0), SensorOffset::default()).is_none());
        assert!(
            Sweep::of_scan(
                &scan(vec![1.0], f32::NAN, 0.1),
                at(0.0, 0.0, 0.0),
                SensorOffset::default()
            )
            .is_none()
        );
        assert!(
            Sweep::of_scan(
                &scan(vec![1.0], 0.0, 0.1),
                at(f64::NAN, 0.0, 0.0),
                SensorOffset::default()
            )
            .is_none()
        );
    }
}
