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
    encode_poses(header, poses.iter().map(|&(x, y, yaw)| (x, y, 0.0, yaw)))
}

/// Encodes a plan as nav_msgs/Path: the poses of [`plan_poses`] at each waypoint's z (metres; the flight
/// altitude of a drone plan, the ground height on a terrain site, 0 on a flat map).
pub fn encode_plan_path(header: &Header, doc: &crate::plan::PlanDocument) -> Vec<u8> {
    let poses = plan_poses(doc);
    encode_poses(
        header,
        poses
            .iter()
            .zip(&doc.waypoints)
            .map(|(&(x, y, yaw), w)| (x, y, w.z, yaw)),
    )
}

/// Poses `(x, y, z metres, yaw radians)` as nav_msgs/Path CDR.
fn encode_poses(header: &Header, poses: impl ExactSizeIterator<Item = (f64, f64, f64, f64)>) -> Vec<u8> {
    let mut w = CdrWriter::new();
    header.write(&mut w);
    w.seq_len(poses.len());
    for (x, y, z, yaw) in poses {
        header.write(&mut w);
        Pose {
            position: Point { x, y, z },
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::{PlanDocument, PlanMetricsDoc, WaypointDoc, WaypointKindDoc};

    #[test]
    fn a_plan_path_carries_each_waypoints_z() {
        let w = |x: f64, y: f64, z: f64| WaypointDoc {
            x,
            y,
            z,
            v: 1.0,
            t: 0.0,
            kind: WaypointKindDoc::Cover,
            region: None,
        };
        let doc = PlanDocument {
            plan_id: "p-1".into(),
            version: 1,
            frame: "map".into(),
            waypoints: vec![w(0.0, 0.0, 131.5), w(1.0, 0.0, 132.0), w(1.0, 1.0, 134.25)],
            regions: Vec::new(),
            metrics: PlanMetricsDoc::default(),
        };
        let header = Header::new(0, "map");
        let path = decode_path(&encode_plan_path(&header, &doc)).expect("decodes");
        let z: Vec<f64> = path.poses.iter().map(|p| p.pose.position.z).collect();
        assert_eq!(z, [131.5, 132.0, 134.25]);
        let yaw: Vec<f64> = path.poses_2d().iter().map(|p| p.2).collect();
        assert!((yaw[0]).abs() < 1e-12 && (yaw[1] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // The planar encoder still writes z = 0.
        let flat = decode_path(&encode_path(&header, &plan_poses(&doc))).expect("decodes");
        assert!(flat.poses.iter().all(|p| p.pose.position.z == 0.0));
    }
}
