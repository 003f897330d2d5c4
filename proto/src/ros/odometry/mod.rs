//! nav_msgs/Odometry (CDR), and the odometry payload of DESIGN §5.4 that is either that CDR or JSON.

mod payload;

pub use payload::{OdomJson, Pose2Stamped, decode_odom_payload, encode_odom_json};

use super::cdr::{CdrReader, CdrWriter};
use super::geometry::{PoseWithCovariance, TwistWithCovariance};
use super::header::Header;
use crate::error::CodecError;

/// nav_msgs/Odometry: the pose of `child_frame_id` in `header.frame_id` (usually `odom` or `map`) and its
/// velocity expressed in `child_frame_id` (the robot body: vx forward, vy left, wz counter-clockwise).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Odometry {
    /// Stamp and the frame of the pose.
    pub header: Header,
    /// The robot's body frame, e.g. `base_link`; the twist is expressed in it.
    pub child_frame_id: String,
    /// Pose (metres, quaternion) with covariance.
    pub pose: PoseWithCovariance,
    /// Velocity (m/s, rad/s) with covariance.
    pub twist: TwistWithCovariance,
}

/// Decodes a nav_msgs/Odometry CDR payload (either byte order).
pub fn decode_odometry(bytes: &[u8]) -> Result<Odometry, CodecError> {
    let mut r = CdrReader::new(bytes)?;
    Ok(Odometry {
        header: Header::read(&mut r)?,
        child_frame_id: r.string("Odometry.child_frame_id")?,
        pose: PoseWithCovariance::read(&mut r)?,
        twist: TwistWithCovariance::read(&mut r)?,
    })
}

/// Encodes a nav_msgs/Odometry as little-endian CDR with its header (byte-identical to rosbags).
pub fn encode_odometry(msg: &Odometry) -> Vec<u8> {
    encode_odometry_with(msg, false)
}

/// Encodes a nav_msgs/Odometry in the given CDR byte order (big-endian only for tests and odd peers).
pub fn encode_odometry_with(msg: &Odometry, big_endian: bool) -> Vec<u8> {
    let mut w = CdrWriter::with_endianness(big_endian);
    msg.header.write(&mut w);
    w.string(&msg.child_frame_id);
    msg.pose.write(&mut w);
    msg.twist.write(&mut w);
    w.finish()
}
