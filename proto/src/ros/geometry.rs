//! geometry_msgs: Point, Vector3, Quaternion, Pose, Twist and their covariance wrappers.

use super::cdr::{CdrReader, CdrWriter};
use crate::error::CodecError;

/// geometry_msgs/Point: a position, metres, in the frame of the enclosing message's header.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Point {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// z, metres.
    pub z: f64,
}

/// geometry_msgs/Vector3: a free vector (velocities: m/s or rad/s, in the frame the message says).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Vector3 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
}

/// geometry_msgs/Quaternion: an orientation (x, y, z, w; the identity is w = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quaternion {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
    /// w (scalar) component.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

impl Quaternion {
    /// The rotation by `yaw` radians about +z (counter-clockwise seen from above): (0, 0, sin(yaw/2), cos(yaw/2)).
    pub fn from_yaw(yaw: f64) -> Self {
        let half = 0.5 * yaw;
        Self {
            x: 0.0,
            y: 0.0,
            z: half.sin(),
            w: half.cos(),
        }
    }

    /// Heading about +z in radians, in (−π, π] (the z-y-x Euler yaw). Independent of the quaternion's norm;
    /// the zero quaternion gives 0.
    pub fn yaw(&self) -> f64 {
        let Self { x, y, z, w } = *self;
        (2.0 * (w * z + x * y)).atan2(w * w + x * x - y * y - z * z)
    }
}

/// geometry_msgs/Pose: position and orientation, in the frame of the enclosing header.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pose {
    /// Position, metres.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// geometry_msgs/Twist: linear (m/s) and angular (rad/s) velocity.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Twist {
    /// Linear velocity, m/s.
    pub linear: Vector3,
    /// Angular velocity, rad/s.
    pub angular: Vector3,
}

/// geometry_msgs/PoseWithCovariance: a pose and its 6×6 row-major covariance (x, y, z, rot x, rot y, rot z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Row-major 6×6 covariance; units m² and rad².
    pub covariance: [f64; 36],
}

impl Default for PoseWithCovariance {
    fn default() -> Self {
        Self {
            pose: Pose::default(),
            covariance: [0.0; 36],
        }
    }
}

/// geometry_msgs/TwistWithCovariance: a twist and its 6×6 row-major covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Row-major 6×6 covariance; units (m/s)² and (rad/s)².
    pub covariance: [f64; 36],
}

impl Default for TwistWithCovariance {
    fn default() -> Self {
        Self {
            twist: Twist::default(),
            covariance: [0.0; 36],
        }
    }
}

fn read3(r: &mut CdrReader<'_>, what: &'static str) -> Result<[f64; 3], CodecError> {
    r.f64_array::<3>(what)
}

impl Point {
    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        let [x, y, z] = read3(r, "Point")?;
        Ok(Self { x, y, z })
    }
    pub(crate) fn write(&self, w: &mut CdrWriter) {
        w.f64_array(&[self.x, self.y, self.z]);
    }
}

impl Vector3 {
    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        let [x, y, z] = read3(r, "Vector3")?;
        Ok(Self { x, y, z })
    }
    pub(crate) fn write(&self, w: &mut CdrWriter) {
        w.f64_array(&[self.x, self.y, self.z]);
    }
}

impl Quaternion {
    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        let [x, y, z, w] = r.f64_array::<4>("Quaternion")?;
        Ok(Self { x, y, z, w })
    }
    pub(crate) fn write(&self, w: &mut CdrWriter) {
        w.f64_array(&[self.x, self.y, self.z, self.w]);
    }
}

impl Pose {
    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        Ok(Self {
            position: Point::read(r)?,
            orientation: Quaternion::read(r)?,
        })
    }
    pub(crate) fn write(&self, w: &mut CdrWriter) {
        self.position.write(w);
        self.orientation.write(w);
    }
}

impl Twist {
    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        Ok(Self {
            linear: Vector3::read(r)?,
            angular: Vector3::read(r)?,
        })
    }
    pub(crate) fn write(&self, w: &mut CdrWriter) {
        self.linear.write(w);
        self.angular.write(w);
    }
}

impl PoseWithCovariance {
    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        Ok(Self {
            pose: Pose::read(r)?,
            covariance: r.f64_array("PoseWithCovariance.covariance")?,
        })
    }
    pub(crate) fn write(&self, w: &mut CdrWriter) {
        self.pose.write(w);
        w.f64_array(&self.covariance);
    }
}

impl TwistWithCovariance {
    pub(crate) fn read(r: &mut CdrReader<'_>) -> Result<Self, CodecError> {
        Ok(Self {
            twist: Twist::read(r)?,
            covariance: r.f64_array("TwistWithCovariance.covariance")?,
        })
    }
    pub(crate) fn write(&self, w: &mut CdrWriter) {
        self.twist.write(w);
        w.f64_array(&self.covariance);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn yaw_round_trips_and_ignores_scale() {
        for yaw in [0.0, 0.3, -1.2, PI / 2.0, 3.0, -3.0] {
            let q = Quaternion::from_yaw(yaw);
            assert!((q.yaw() - yaw).abs() < 1e-12, "{yaw}");
            let scaled = Quaternion {
                x: q.x * 3.0,
                y: q.y * 3.0,
                z: q.z * 3.0,
                w: q.w * 3.0,
            };
            assert!((scaled.yaw() - yaw).abs() < 1e-12, "{yaw}");
        }
        assert_eq!(
            Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 0.0
            }
            .yaw(),
            0.0
        );
        // A 90° roll does not change the heading.
        let roll = Quaternion {
            x: (PI / 4.0).sin(),
            y: 0.0,
            z: 0.0,
            w: (PI / 4.0).cos(),
        };
        assert!(roll.yaw().abs() < 1e-12);
    }
}
