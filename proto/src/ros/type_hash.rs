//! ROS 2 Jazzy type hashes (RIHS01, REP-2011) of the messages SHIFT exchanges: part of rmw_zenoh key
//! expressions and of MCAP `topic_type_hash` channel metadata. Computed with the Python `rosbags` type store
//! (`hash_rihs01`), which reproduces the four hashes listed in ECOSYSTEM.md; a test keeps them equal to the
//! fixture generator's output.

/// sensor_msgs/msg/PointCloud2.
pub const POINT_CLOUD2: &str = "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5";
/// nav_msgs/msg/Odometry.
pub const ODOMETRY: &str = "RIHS01_3cc97dc7fb7502f8714462c526d369e35b603cfc34d946e3f2eda2766dfec6e0";
/// nav_msgs/msg/Path.
pub const PATH: &str = "RIHS01_1957a5bb3cee5da65c4e52e52b65a93df227efce4c20f8458b36e73066ca334b";
/// geometry_msgs/msg/PoseStamped.
pub const POSE_STAMPED: &str = "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8";
/// sensor_msgs/msg/LaserScan (computed with rosbags 0.11.9, whose algorithm gives the four hashes above).
pub const LASER_SCAN: &str = "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828";
