//! Sensor geometry: robot-frame points and laser returns → points in the map frame.
//!
//! Frame policy: a scan is in the laser frame, which sits at a fixed offset (x, y, yaw; `zenoh.scan_offset_*`)
//! in the robot frame; the robot frame is placed by the robot's pose at the scan's stamp (interpolated from its
//! odometry). A scan's `header.frame_id` is not looked at. Scan points get z = 0: a 2-D scan marks obstacles at
//! any height. A cloud in the robot frame is moved by the pose at its stamp (x, y, yaw; z is kept).

use shift_proto::ros::{LaserScan, scan_points};

use crate::robots::Pose2;

/// What the z of placed points measures, which decides how the live map's obstacle height band applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heights {
    /// A 2-D scan (z = 0): obstacles at any height, no band.
    Planar,
    /// A cloud given in the map frame: z is the map frame's (on a terrain site, absolute: the band is measured
    /// over the ground under each point).
    MapFrame,
    /// A cloud given in the robot frame: z is the height over the ground the robot stands on.
    OverGround,
}

/// Where the laser sits in the robot frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SensorOffset {
    /// Forward of the robot's origin, metres.
    pub x_m: f64,
    /// Left of the robot's origin, metres.
    pub y_m: f64,
    /// Laser heading relative to the robot's, radians counter-clockwise.
    pub yaw_rad: f64,
}

/// The returns of `scan` (ranges within [range_min, range_max], finite) as map-frame points `[x, y, 0]`,
/// metres, for a robot at `pose` with its laser at `offset`.
pub fn scan_to_map(scan: &LaserScan, pose: Pose2, offset: SensorOffset) -> Vec<[f64; 3]> {
    // Laser pose in the map frame: robot pose ∘ offset.
    let (s, c) = pose.yaw.sin_cos();
    let lx = pose.x + c * offset.x_m - s * offset.y_m;
    let ly = pose.y + s * offset.x_m + c * offset.y_m;
    let (ls, lc) = (pose.yaw + offset.yaw_rad).sin_cos();
    scan_points(scan)
        .into_iter()
        .map(|[x, y]| [lx + lc * x - ls * y, ly + ls * x + lc * y, 0.0])
        .collect()
}

/// Robot-frame points `[x, y, z]` (metres) moved into the map frame by the robot's `pose` (z kept).
pub fn robot_to_map(points: &[[f64; 3]], pose: Pose2) -> Vec<[f64; 3]> {
    let (s, c) = pose.yaw.sin_cos();
    points
        .iter()
        .map(|p| [pose.x + c * p[0] - s * p[1], pose.y + s * p[0] + c * p[1], p[2]])
        .collect()
}

#[cfg(test)]
mod tests {
    use std::f64::consts::FRAC_PI_2;

    use super::*;

    fn close(a: &[[f64; 3]], b: &[[f64; 3]]) {
        assert_eq!(a.len(), b.len(), "{a:?} vs {b:?}");
        for (p, q) in a.iter().zip(b) {
            assert!(
                (p[0] - q[0]).abs() < 1e-5 && (p[1] - q[1]).abs() < 1e-5 && p[2] == q[2],
                "{a:?} vs {b:?}"
            );
        }
    }

    #[test]
    fn known_scan_lands_on_hand_computed_points() {
        // Five beams from −90° to +90° every 45°; beam 1 is too short, beam 3 is NaN.
        let scan = LaserScan {
            angle_min: -std::f32::consts::FRAC_PI_2,
            angle_max: std::f32::consts::FRAC_PI_2,
            angle_increment: std::f32::consts::FRAC_PI_4,
            range_min: 0.2,
            range_max: 10.0,
            ranges: vec![1.0, 0.1, 2.0, f32::NAN, 3.0],
            ..LaserScan::default()
        };
        // Robot at (1, 2) facing +y; laser 0.5 m ahead of its centre, mounted straight.
        let pose = Pose2 {
            x: 1.0,
            y: 2.0,
            yaw: FRAC_PI_2,
            stamp_ns: 0,
        };
        let offset = SensorOffset {
            x_m: 0.5,
            y_m: 0.0,
            yaw_rad: 0.0,
        };
        // Laser at (1, 2.5) facing +y. Beam −90° (to the robot's right = +x): 1 m → (2, 2.5).
        // Beam 0° (ahead = +y): 2 m → (1, 4.5). Beam +90° (left = −x): 3 m → (−2, 2.5).
        let want = [[2.0, 2.5, 0.0], [1.0, 4.5, 0.0], [-2.0, 2.5, 0.0]];
        close(&scan_to_map(&scan, pose, offset), &want);

        // The laser mounted backwards (yaw π) at the robot's centre, robot at the origin facing +x:
        // beam 0° points to −x.
        let back = SensorOffset {
            yaw_rad: std::f64::consts::PI,
            ..SensorOffset::default()
        };
        let origin = Pose2 {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            stamp_ns: 0,
        };
        let want = [[0.0, 1.0, 0.0], [-2.0, 0.0, 0.0], [0.0, -3.0, 0.0]];
        close(&scan_to_map(&scan, origin, back), &want);
    }

    #[test]
    fn robot_frame_points_turn_and_move_with_the_pose() {
        let pose = Pose2 {
            x: 1.0,
            y: 2.0,
            yaw: FRAC_PI_2,
            stamp_ns: 0,
        };
        // 1 m ahead of a robot facing +y is 1 m up in the map; 1 m to its left is 1 m towards −x.
        let got = robot_to_map(&[[1.0, 0.0, 0.3], [0.0, 1.0, 0.0]], pose);
        close(&got, &[[1.0, 3.0, 0.3], [0.0, 2.0, 0.0]]);
    }

    #[test]
    fn degenerate_scans_give_no_points_and_never_panic() {
        let pose = Pose2 {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
            stamp_ns: 0,
        };
        for scan in [
            LaserScan::default(),
            LaserScan {
                angle_increment: f32::NAN,
                range_max: 10.0,
                ranges: vec![1.0; 4],
                ..LaserScan::default()
            },
            LaserScan {
                range_min: 5.0,
                range_max: 1.0,
                ranges: vec![2.0; 4],
                ..LaserScan::default()
            },
            LaserScan {
                range_max: f32::INFINITY,
                ranges: vec![f32::INFINITY, -1.0],
                ..LaserScan::default()
            },
        ] {
            let pts = scan_to_map(&scan, pose, SensorOffset::default());
            assert!(pts.iter().all(|p| p.iter().all(|v| v.is_finite())), "{pts:?}");
        }
    }
}
