//! nav_msgs/Path (CDR) of geometry_msgs/PoseStamped: how a plan reaches ROS consumers.

use super::cdr::{CdrReader, CdrWriter};
use super::geometry::{Point, Pose, Quaternion};
use super::header::Header;
use crate::error::CodecError;

/// geometry_msgs/PoseStamped: a pose in `header.frame_id` at `header.stamp`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseStamped {
    /// Stamp and frame of the pose.
    pub header: Header,
    /// Position (metres) and orientation.
    pub pose: Pose,
}

/// nav_msgs/Path: poses in order of travel, all in `header.frame_id`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Path {
    /// Stamp and frame of the path.
    pub header: Header,
    /// The poses.
    pub poses: Vec<PoseStamped>,
}

impl Path {
    /// The path as planar poses: (x metres, y metres, yaw radians) in `header.frame_id`.
    pub fn poses_2d(&self) -> Vec<(f64, f64, f64)> {
        self.poses
            .iter()
            .map(|p| (p.pose.position.x, p.pose.position.y, p.pose.orientation.yaw()))
            .collect()
    }
}

/// A plan's waypoints as nav_msgs/Path poses `(x metres, y metres, yaw radians)` in the plan's frame, the yaw
/// along the path (towards the next waypoint; the last one keeps its predecessor's heading). The daemon's
/// `…/plan_path` messages and the clients' nav_msgs/Path exports are built from this.
pub fn plan_poses(doc: &crate::plan::PlanDocument) -> Vec<(f64, f64, f64)> {
    let w = &doc.waypoints;
    (0..w.len())
        .map(|i| {
            let (a, b) = if i + 1 < w.len() {
                (i, i + 1)
            } else {
                (i.saturating_sub(1), i)
            };
            let yaw = (w[b].y - w[a].y).atan2(w[b].x - w[a].x);
            (w[i].x, w[i].y, if yaw.is_finite() { yaw } else { 0.0 })
        })
        .collect()
}

/// Encodes a planar path as a little-endian nav_msgs/Path CDR payload (byte-identical to rosbags): each pose is
/// (x metres, y metres, yaw radians) in `header.frame_id`, written with z = 0, the quaternion
/// (0, 0, sin(yaw/2), cos(yaw/2)) and a copy of `header`.
pub fn encode_path(header: &Header, poses: &[(f64, f64, f64)]) -> Vec<u8> {
    let mut w = CdrWriter::new();
    header.write(&mut w);
    w.seq_len(poses.len());
    for &(x, y, yaw) in poses {
        header.write(&mut w);
        Pose {
            position: Point { x, y, z: 0.0 },
            orientation: Quaternion::from_yaw(yaw),
        }
        .write(&mut w);
    }
    w.finish()
}

/// Decodes a nav_msgs/Path CDR payload (either byte order).
pub fn decode_path(bytes: &[u8]) -> Result<Path, CodecError> {
    let mut r = CdrReader::new(bytes)?;
    let header = Header::read(&mut r)?;
    // A PoseStamped takes at least 8 (stamp) + 4 (frame length) + 56 (pose) bytes.
    let n = r.seq_len(68, "Path.poses")?;
    let poses = (0..n)
        .map(|_| {
            Ok(PoseStamped {
                header: Header::read(&mut r)?,
                pose: Pose::read(&mut r)?,
            })
        })
        .collect::<Result<Vec<_>, CodecError>>()?;
    Ok(Path { header, poses })
}
