//! What each recorded channel is: its schema (name, encoding, text), message encoding and metadata, and the
//! fixed topics of SHIFT's own channels. Ingested messages keep the Zenoh key they came in on as their topic.

use std::collections::BTreeMap;

use shift_proto::keys::Stream;
use shift_proto::ros::{msg_defs, type_hash, type_name};

use super::schemas;

/// Engine inputs ([`shift_engine::recorded::RecordedInput`]).
pub const ENGINE_INPUT: &str = "/shift/engine/events";
/// Engine decisions ([`shift_engine::recorded::RecordedDecisions`]).
pub const ENGINE_DECISIONS: &str = "/shift/engine/decisions";
/// Engine sizes, at the start of every file.
pub const ENGINE_CONFIG: &str = "/shift/engine/config";
/// Plan documents as computed and as delivered.
pub const PLANS: &str = "/shift/plans";
/// Plan status changes.
pub const PLAN_STATUS: &str = "/shift/plan_status";
/// Robot liveliness tokens appearing and going.
pub const LIVELINESS: &str = "/shift/liveliness";

/// A site's occupancy grid topic: `/shift/sites/{site}/occupancy`.
pub fn occupancy(site: &str) -> String {
    format!("/shift/sites/{site}/occupancy")
}

/// A site's measured coverage topic: `/shift/sites/{site}/coverage`.
pub fn coverage(site: &str) -> String {
    format!("/shift/sites/{site}/coverage")
}

/// The kind of a recorded channel; fixes its schema and encodings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Kind {
    /// nav_msgs/msg/Odometry, CDR.
    Odometry,
    /// sensor_msgs/msg/PointCloud2, CDR.
    PointCloud2,
    /// sensor_msgs/msg/LaserScan, CDR.
    LaserScan,
    /// JSON odometry (DESIGN §5.4).
    OdomJson,
    /// Liveliness changes, JSON.
    Liveliness,
    /// Engine inputs, JSON.
    EngineInput,
    /// Engine decisions, JSON.
    EngineDecisions,
    /// Engine sizes, JSON.
    EngineConfig,
    /// Plan documents, JSON.
    PlanDocument,
    /// Plan status, JSON.
    PlanStatus,
    /// foxglove.Grid, JSON.
    Grid,
}

/// A schema record's content.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SchemaSpec {
    /// Schema name (`nav_msgs/msg/Odometry`, `foxglove.Grid`, `shift.EngineInput`).
    pub name: &'static str,
    /// `ros2msg` or `jsonschema`.
    pub encoding: &'static str,
    /// The schema text.
    pub text: &'static str,
}

const ALL: [Kind; 11] = [
    Kind::Odometry,
    Kind::PointCloud2,
    Kind::LaserScan,
    Kind::OdomJson,
    Kind::Liveliness,
    Kind::EngineInput,
    Kind::EngineDecisions,
    Kind::EngineConfig,
    Kind::PlanDocument,
    Kind::PlanStatus,
    Kind::Grid,
];

impl Kind {
    /// Its schema.
    pub fn schema(self) -> SchemaSpec {
        let ros = |name, text| SchemaSpec {
            name,
            encoding: "ros2msg",
            text,
        };
        let json = |name, text| SchemaSpec {
            name,
            encoding: "jsonschema",
            text,
        };
        match self {
            Self::Odometry => ros(type_name::ODOMETRY, msg_defs::ODOMETRY),
            Self::PointCloud2 => ros(type_name::POINT_CLOUD2, msg_defs::POINT_CLOUD2),
            Self::LaserScan => ros(type_name::LASER_SCAN, msg_defs::LASER_SCAN),
            Self::OdomJson => json("shift.OdomJson", schemas::ODOM_JSON),
            Self::Liveliness => json("shift.Liveliness", schemas::LIVELINESS),
            Self::EngineInput => json("shift.EngineInput", schemas::ENGINE_INPUT),
            Self::EngineDecisions => json("shift.EngineDecisions", schemas::ENGINE_DECISIONS),
            Self::EngineConfig => json("shift.EngineConfig", schemas::ENGINE_CONFIG),
            Self::PlanDocument => json("shift.PlanDocument", schemas::PLAN_DOCUMENT),
            Self::PlanStatus => json("shift.PlanStatus", schemas::PLAN_STATUS),
            Self::Grid => json("foxglove.Grid", schemas::FOXGLOVE_GRID),
        }
    }

    /// The kind whose schema has this name.
    pub fn from_schema_name(name: &str) -> Option<Self> {
        ALL.into_iter().find(|k| k.schema().name == name)
    }

    /// `cdr` for ROS messages, else `json`.
    pub fn message_encoding(self) -> &'static str {
        if self.is_ros() { "cdr" } else { "json" }
    }

    /// A ROS 2 message in CDR.
    pub fn is_ros(self) -> bool {
        matches!(self, Self::Odometry | Self::PointCloud2 | Self::LaserScan)
    }

    /// A message a robot put on Zenoh (what `shiftd replay` puts back).
    pub fn is_ingest(self) -> bool {
        self.is_ros() || self == Self::OdomJson
    }

    /// Channel metadata: ROS channels carry `offered_qos_profiles` (empty: Zenoh has no DDS QoS to offer) and
    /// `topic_type_hash` (RIHS01), as rosbag2 writes them.
    pub fn metadata(self) -> BTreeMap<String, String> {
        let hash = match self {
            Self::Odometry => type_hash::ODOMETRY,
            Self::PointCloud2 => type_hash::POINT_CLOUD2,
            Self::LaserScan => type_hash::LASER_SCAN,
            _ => return BTreeMap::new(),
        };
        BTreeMap::from([
            ("offered_qos_profiles".to_owned(), String::new()),
            ("topic_type_hash".to_owned(), hash.to_owned()),
        ])
    }

    /// The kind of an ingested payload on `stream`: odometry is JSON or CDR (told apart like the decoder does:
    /// by encoding, else by a leading `{`); `None` for a stream that is not a message (liveliness).
    pub fn of_payload(stream: Stream, bytes: &[u8], encoding: &str) -> Option<Self> {
        match stream {
            Stream::Odom => {
                let enc = encoding.trim().to_ascii_lowercase();
                let json_enc = enc.starts_with("application/json") || enc.starts_with("text/json");
                let looks_json = bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{');
                Some(if json_enc || (!enc.contains("cdr") && looks_json) {
                    Self::OdomJson
                } else {
                    Self::Odometry
                })
            }
            Stream::Cloud => Some(Self::PointCloud2),
            Stream::Scan => Some(Self::LaserScan),
            Stream::Alive => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schema_names_map_back_and_ros_channels_carry_their_hash() {
        for k in ALL {
            assert_eq!(Kind::from_schema_name(k.schema().name), Some(k));
            assert_eq!(k.metadata().contains_key("topic_type_hash"), k.is_ros());
        }
        assert_eq!(
            Kind::PointCloud2.metadata()["topic_type_hash"],
            "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5"
        );
        assert_eq!(Kind::of_payload(Stream::Odom, b" {\"x\":1}", ""), Some(Kind::OdomJson));
        assert_eq!(
            Kind::of_payload(Stream::Odom, b"{", "application/cdr"),
            Some(Kind::Odometry)
        );
        assert_eq!(Kind::of_payload(Stream::Odom, &[0, 1, 0, 0], ""), Some(Kind::Odometry));
        assert_eq!(Kind::of_payload(Stream::Alive, b"", ""), None);
    }
}
