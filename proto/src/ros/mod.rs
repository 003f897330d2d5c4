//! ROS 2 messages on the wire (plain CDR with the 4-byte encapsulation header), as robots send them through
//! zenoh-bridge-ros2dds or rmw_zenoh, and the facts MCAP recordings need (type names, hashes, schema texts).
//!
//! Decoders accept either CDR byte order, never panic, and bound every allocation by the payload size and the
//! absurd-size limits below. Encoders write little-endian CDR, byte-identical to the Python `rosbags`
//! serializer (fixtures in `proto/tests/fixtures/`).

pub mod cdr;
pub mod geometry;
pub mod header;
pub mod laser_scan;
pub mod msg_defs;
pub mod odometry;
pub mod path;
pub mod point_cloud2;
pub mod type_hash;
pub mod type_name;

pub use geometry::{Point, Pose, PoseWithCovariance, Quaternion, Twist, TwistWithCovariance, Vector3};
pub use header::{Header, Time};
pub use laser_scan::{LaserScan, decode_laser_scan, encode_laser_scan, scan_points};
pub use odometry::{
    OdomJson, Odometry, Pose2Stamped, decode_odom_payload, decode_odometry, encode_odom_json, encode_odometry,
};
pub use path::{Path, PoseStamped, decode_path, encode_path, encode_plan_path};
pub use point_cloud2::{
    CloudXyz, PointCloud2, PointField, cloud_xyz, decode_cloud_xyz, decode_point_cloud2, encode_point_cloud2,
    encode_point_cloud2_xyz,
};

/// Most points (height × width of a cloud, ranges of a scan) a message may declare: 20 million.
pub const MAX_POINTS: usize = 20_000_000;
/// Most bytes of point data a cloud may declare: 512 MiB.
pub const MAX_CLOUD_BYTES: usize = 512 * 1024 * 1024;
