//! `[zenoh]`: the fleet fabric. The default is a peer listening on loopback only with multicast and gossip
//! scouting off — never all interfaces by default (ECOSYSTEM.md).

use serde::Deserialize;

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
    /// Site whose live map this fleet's clouds feed.
    pub site: String,
    /// Frame the clouds' points are in when they need no transform.
    pub map_frame: String,
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
            obstacle_z_min_m: 0.05,
            obstacle_z_max_m: 2.0,
            voxel_m: 0.05,
            max_points: 2_000_000,
            horizon_s: 600,
            cloud_queue: 4,
            known_tolerance_m: 0.1,
        }
    }
}

impl ZenohConfig {
    /// The zenoh configuration: mode, endpoints, scouting off.
    pub fn to_zenoh(&self) -> anyhow::Result<zenoh::Config> {
        if self.mode != "peer" && self.mode != "client" {
            anyhow::bail!("zenoh.mode must be \"peer\" or \"client\", got {:?}", self.mode);
        }
        let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
        let mut c = zenoh::Config::default();
        let set = |c: &mut zenoh::Config, k: &str, v: &str| {
            c.insert_json5(k, v)
                .map_err(|e| anyhow::anyhow!("zenoh config {k} = {v}: {e}"))
        };
        set(&mut c, "mode", &format!("{:?}", self.mode))?;
        set(&mut c, "listen/endpoints", &list(&self.listen))?;
        set(&mut c, "connect/endpoints", &list(&self.connect))?;
        set(&mut c, "scouting/multicast/enabled", "false")?;
        set(&mut c, "scouting/gossip/enabled", "false")?;
        Ok(c)
    }
}
