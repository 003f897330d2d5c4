//! ROS 2 type names: the `pkg/msg/Type` form (MCAP schema names) and the DDS form rmw_zenoh puts in keys.

/// nav_msgs/msg/Odometry.
pub const ODOMETRY: &str = "nav_msgs/msg/Odometry";
/// sensor_msgs/msg/PointCloud2.
pub const POINT_CLOUD2: &str = "sensor_msgs/msg/PointCloud2";
/// sensor_msgs/msg/LaserScan.
pub const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";
/// nav_msgs/msg/Path.
pub const PATH: &str = "nav_msgs/msg/Path";
/// geometry_msgs/msg/PoseStamped.
pub const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";

/// DDS name of nav_msgs/msg/Odometry, as in rmw_zenoh key expressions.
pub const DDS_ODOMETRY: &str = "nav_msgs::msg::dds_::Odometry_";
/// DDS name of sensor_msgs/msg/PointCloud2.
pub const DDS_POINT_CLOUD2: &str = "sensor_msgs::msg::dds_::PointCloud2_";
/// DDS name of sensor_msgs/msg/LaserScan.
pub const DDS_LASER_SCAN: &str = "sensor_msgs::msg::dds_::LaserScan_";
/// DDS name of nav_msgs/msg/Path.
pub const DDS_PATH: &str = "nav_msgs::msg::dds_::Path_";
