//! `[zenoh]`: the fleet fabric. The default is a peer listening on loopback only with multicast and gossip
//! scouting off — never all interfaces by default (ECOSYSTEM.md).

use serde::Deserialize;
use shift_engine::PoseHistoryParams;
use shift_engine::sensors::SensorParams;
use shift_engine::sensors::geometry::SensorOffset;
use shift_proto::keys::Ros2Mapping;

/// `[zenoh]` of the config file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ZenohConfig {
    /// Open a Zenoh session at all.
    pub enabled: bool,
    /// `peer` or `client` (client joins zenohd routers given in `connect`).
    pub mode: String,
    /// Endpoints to listen on, e.g. `tcp/127.0.0.1:7447`. Empty = in-process only.
    pub listen: Vec<String>,
    /// Endpoints to connect to (routers or peers).
    pub connect: Vec<String>,
    /// First segment of every key (`shift`).
    pub prefix: String,
    /// Fleet name, second segment (`default`).
    pub fleet: String,
    /// The default site of unassigned robots: a robot's clouds and scans feed the site of the plan it is
    /// assigned; a robot with no plan feeds this site, or, when empty, its points are dropped and counted
    /// (`unrouted`).
    pub site: String,
    /// Frame the clouds' points are in when they need no transform.
    pub map_frame: String,
    /// Odometry frames besides `map_frame` whose poses are taken as map-frame poses (a robot localised in the
    /// map that names its frame `odom`); odometry in any other frame is reported and not used.
    pub pose_frames: Vec<String>,
    /// Longest a scan or cloud newer than the robot's newest odometry waits for the odometry that places it,
    /// milliseconds.
    pub sensor_wait_ms: u64,
    /// Most scans and clouds waiting for odometry per robot (the oldest goes first).
    pub sensor_wait_max: usize,
    /// Obstacle height band in the map frame for 3-D clouds, metres.
    pub obstacle_z_min_m: f64,
    /// Upper end of the band, metres.
    pub obstacle_z_max_m: f64,
    /// Down-sampling voxel of the live map, metres.
    pub voxel_m: f64,
    /// Most points a site's live map holds.
    pub max_points: usize,
    /// Voxels not re-observed for this long leave the live map, seconds.
    pub horizon_s: u64,
    /// Clouds waiting per robot; when full the oldest is dropped and counted.
    pub cloud_queue: usize,
    /// Points this close to an obstacle of the static map are that obstacle seen again, not new ones
    /// (metres; 0 keeps them all).
    pub known_tolerance_m: f64,
    /// A LaserScan clears the scan points of the live map its rays saw through by more than this (a walker's
    /// trail; metres; 0 = no clearing, points leave only by the horizon).
    pub clear_margin_m: f64,
    /// How this fleet's robots name their keys: `{kind = "native"}` (DESIGN §5.4 under prefix/fleet),
    /// `{kind = "bridge_ros2dds", namespace = "…"}` or `{kind = "rmw_zenoh", domain = 0}`.
    pub mapping: Ros2Mapping,
    /// ROS 2 mappings have no SHIFT liveliness token: a robot is alive from its first message and lost after
    /// this many seconds without one, seconds.
    pub robot_timeout_s: u64,
    /// Odometry kept per robot to place scans and robot-frame clouds at their stamps, seconds.
    pub pose_history_s: f64,
    /// A scan stamped up to this long after the newest pose (once it has waited `sensor_wait_ms` for odometry
    /// that covers its stamp), or before the oldest, takes that end pose; beyond, it is dropped and counted,
    /// milliseconds.
    pub scan_stamp_tolerance_ms: u64,
    /// Laser position in the robot frame (x forward, y left), metres.
    pub scan_offset_x_m: f64,
    /// See `scan_offset_x_m`.
    pub scan_offset_y_m: f64,
    /// Laser heading in the robot frame, radians counter-clockwise.
    pub scan_offset_yaw_rad: f64,
}

impl Default for ZenohConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            mode: "peer".into(),
            listen: vec!["tcp/127.0.0.1:7447".into()],
            connect: Vec::new(),
            prefix: "shift".into(),
            fleet: "default".into(),
            site: "demo".into(),
            map_frame: "map".into(),
            pose_frames: vec!["odom".into()],
            sensor_wait_ms: 500,
            sensor_wait_max: 32,
            obstacle_z_min_m: 0.05,
            obstacle_z_max_m: 2.0,
            voxel_m: 0.05,
            max_points: 2_000_000,
            horizon_s: 600,
            cloud_queue: 4,
            known_tolerance_m: 0.1,
            clear_margin_m: 0.1,
            mapping: Ros2Mapping::Native,
            robot_timeout_s: 10,
            pose_history_s: 5.0,
            scan_stamp_tolerance_ms: 100,
            scan_offset_x_m: 0.0,
            scan_offset_y_m: 0.0,
            scan_offset_yaw_rad: 0.0,
        }
    }
}

impl ZenohConfig {
    /// The per-robot pose history these settings ask for (at most 100 poses a second of history).
    pub fn pose_history(&self) -> PoseHistoryParams {
        let span_s = if self.pose_history_s.is_finite() {
            self.pose_history_s.clamp(0.1, 600.0)
        } else {
            5.0
        };
        PoseHistoryParams {
            span_ns: (span_s * 1e9) as i64,
            max_poses: ((span_s * 100.0) as usize).max(16),
            tolerance_ns: i64::try_from(self.scan_stamp_tolerance_ms.min(3_600_000)).unwrap_or(0) * 1_000_000,
        }
    }
}

impl ZenohConfig {
    /// The default site of unassigned robots (`None` when `site` is empty).
    pub fn default_site(&self) -> Option<String> {
        (!self.site.is_empty()).then(|| self.site.clone())
    }

    /// How the sensor pipeline places and routes this fleet's data.
    pub fn sensor_params(&self) -> SensorParams {
        SensorParams {
            map_frame: self.map_frame.clone(),
            pose_frames: self.pose_frames.clone(),
            history: self.pose_history(),
            scan_offset: SensorOffset {
                x_m: self.scan_offset_x_m,
                y_m: self.scan_offset_y_m,
                yaw_rad: self.scan_offset_yaw_rad,
            },
            wait_ms: self.sensor_wait_ms.min(60_000),
            wait_max: self.sensor_wait_max.clamp(1, 4096),
            default_site: self.default_site(),
        }
    }

    /// The zenoh configuration: mode, endpoints, scouting off.
    pub fn to_zenoh(&self) -> crate::error::Result<zenoh::Config> {
        if self.mode != "peer" && self.mode != "client" {
            crate::bail!("zenoh.mode must be \"peer\" or \"client\", got {:?}", self.mode);
        }
        let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
        let mut c = zenoh::Config::default();
        let set = |c: &mut zenoh::Config, k: &str, v: &str| {
            c.insert_json5(k, v)
                .map_err(|e| crate::err!("zenoh config {k} = {v}: {e}"))
        };
        set(&mut c, "mode", &format!("{:?}", self.mode))?;
        set(&mut c, "listen/endpoints", &list(&self.listen))?;
        set(&mut c, "connect/endpoints", &list(&self.connect))?;
        set(&mut c, "scouting/multicast/enabled", "false")?;
        set(&mut c, "scouting/gossip/enabled", "false")?;
        Ok(c)
    }
}
