//! Key layouts of ROS 2 robots on Zenoh, so a ROS 2 robot needs no adapter (ECOSYSTEM.md "ROS 2 robots over
//! Zenoh"): zenoh-bridge-ros2dds (`[namespace/]{robot}/odom`) and rmw_zenoh
//! (`{domain}/{robot}/odom/nav_msgs::msg::dds_::Odometry_/RIHS01_…`). Topics: `odom` (nav_msgs/Odometry),
//! `points` (sensor_msgs/PointCloud2), `scan` (sensor_msgs/LaserScan), all CDR with the 4-byte header.

use serde::{Deserialize, Serialize};

use super::{KeyError, KeySpace, Stream, parse_robot_leaf, validate_name, validate_path};
use crate::ros::type_hash;
use crate::ros::type_name::{DDS_LASER_SCAN, DDS_ODOMETRY, DDS_POINT_CLOUD2};

/// How a fleet's robots name their keys; selectable per fleet in the daemon config as
/// `{kind = "native"}`, `{kind = "bridge_ros2dds", namespace = "ns"}` or `{kind = "rmw_zenoh", domain = 0}`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Ros2Mapping {
    /// SHIFT's own keys of DESIGN §5.4 (`{prefix}/{fleet}/robots/{robot}/odom|cloud|scan`).
    #[default]
    Native,
    /// zenoh-bridge-ros2dds: key = `[namespace/]{robot}/{odom|points|scan}`, the ROS topic without its
    /// leading slash.
    BridgeRos2dds {
        /// The bridge's `namespace` (one or more chunks, slashes at either end ignored); none by default.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        namespace: Option<String>,
    },
    /// rmw_zenoh: key = `{domain}/{robot}/{topic}/{dds type}/{type hash}`.
    RmwZenoh {
        /// ROS_DOMAIN_ID, default 0.
        #[serde(default)]
        domain: u32,
    },
}

/// ROS topic leaf, the stream it carries, and its DDS type name.
const TOPICS: [(&str, Stream, &str); 3] = [
    ("odom", Stream::Odom, DDS_ODOMETRY),
    ("points", Stream::Cloud, DDS_POINT_CLOUD2),
    ("scan", Stream::Scan, DDS_LASER_SCAN),
];

fn namespace_of(namespace: &Option<String>) -> Option<&str> {
    namespace
        .as_deref()
        .map(|n| n.trim_matches('/'))
        .filter(|n| !n.is_empty())
}

/// An rmw_zenoh type-hash chunk: `RIHS01_` and 64 hex digits, or Humble's `TypeHashNotSupported`.
fn is_type_hash(chunk: &str) -> bool {
    chunk == "TypeHashNotSupported"
        || chunk
            .strip_prefix("RIHS01_")
            .is_some_and(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()))
}

impl Ros2Mapping {
    /// Checks the bridge namespace (chunks that are valid names).
    pub fn validate(&self) -> Result<(), KeyError> {
        match self {
            Self::BridgeRos2dds { namespace } => {
                namespace_of(namespace).map_or(Ok(()), |n| validate_path("namespace", n))
            }
            Self::Native | Self::RmwZenoh { .. } => Ok(()),
        }
    }

    /// The key expressions to subscribe to for this fleet's robot data, with the stream each carries. Native
    /// uses `keys`; the ROS layouts do not (their keys are not under the prefix). Liveliness is not in this list:
    /// native robots announce themselves on [`KeySpace::all_alive`].
    pub fn subscriptions(&self, keys: &KeySpace) -> Vec<(String, Stream)> {
        match self {
            Self::Native => {
                vec![
                    (keys.all_odom(), Stream::Odom),
                    (keys.all_cloud(), Stream::Cloud),
                    (keys.all_scan(), Stream::Scan),
                ]
            }
            Self::BridgeRos2dds { namespace } => {
                let ns = namespace_of(namespace).map(|n| format!("{n}/")).unwrap_or_default();
                TOPICS
                    .iter()
                    .map(|&(topic, stream, _)| (format!("{ns}*/{topic}"), stream))
                    .collect()
            }
            Self::RmwZenoh { domain } => TOPICS
                .iter()
                .map(|&(topic, stream, dds)| (format!("{domain}/*/{topic}/{dds}/*"), stream))
                .collect(),
        }
    }

    /// The robot and stream of a key received on one of [`subscriptions`](Self::subscriptions); `None` for keys
    /// of another layout, namespace, domain or message type, and for invalid robot names. Native keys are
    /// recognised by their `…/robots/{robot}/{odom|cloud|scan|alive}` tail (the subscription already fixed the
    /// prefix; use [`KeySpace::robot_of`] to check it too).
    pub fn robot_of(&self, key: &str) -> Option<(String, Stream)> {
        match self {
            Self::Native => {
                let mut it = key.rsplitn(4, '/');
                let (leaf, robot, robots) = (it.next()?, it.next()?, it.next()?);
                it.next()?; // the prefix and fleet must be there
                parse_robot_leaf(&format!("{robots}/{robot}/{leaf}"))
            }
            Self::BridgeRos2dds { namespace } => {
                let rest = match namespace_of(namespace) {
                    Some(ns) => key.strip_prefix(ns)?.strip_prefix('/')?,
                    None => key,
                };
                let (robot, topic) = rest.split_once('/')?;
                robot_stream(robot, topic, None)
            }
            Self::RmwZenoh { domain } => {
                let mut parts = key.split('/');
                let (Some(d), Some(robot), Some(topic), Some(dds), Some(hash), None) = (
                    parts.next(),
                    parts.next(),
                    parts.next(),
                    parts.next(),
                    parts.next(),
                    parts.next(),
                ) else {
                    return None;
                };
                if d != domain.to_string() || !is_type_hash(hash) {
                    return None;
                }
                robot_stream(robot, topic, Some(dds))
            }
        }
    }
}

impl Ros2Mapping {
    /// The robot and data stream (odometry, cloud, scan) of a key received on one of
    /// [`subscriptions`](Self::subscriptions); native keys are checked against `keys`' prefix and fleet too.
    /// Liveliness keys and keys of other layouts give `None`.
    pub fn classify(&self, keys: &KeySpace, key: &str) -> Option<(String, Stream)> {
        match self {
            Self::Native => keys.robot_of(key),
            Self::BridgeRos2dds { .. } | Self::RmwZenoh { .. } => self.robot_of(key),
        }
        .filter(|(_, s)| *s != Stream::Alive)
    }

    /// The key `robot` publishes `stream` on in this layout (what a robot, simulator or test puts to); rmw_zenoh
    /// keys carry the Jazzy type hash. Liveliness is native only (`None` for the ROS 2 layouts).
    pub fn robot_key(&self, keys: &KeySpace, robot: &str, stream: Stream) -> Result<Option<String>, KeyError> {
        validate_name("robot name", robot)?;
        let topic = TOPICS.iter().find(|(_, s, _)| *s == stream);
        Ok(match (self, topic) {
            (Self::Native, _) => Some(match stream {
                Stream::Odom => keys.odom(robot)?,
                Stream::Cloud => keys.cloud(robot)?,
                Stream::Scan => keys.scan(robot)?,
                Stream::Alive => keys.alive(robot)?,
            }),
            (_, None) => None,
            (Self::BridgeRos2dds { namespace }, Some((topic, _, _))) => Some(match namespace_of(namespace) {
                Some(ns) => format!("{ns}/{robot}/{topic}"),
                None => format!("{robot}/{topic}"),
            }),
            (Self::RmwZenoh { domain }, Some((topic, stream, dds))) => {
                let hash = match stream {
                    Stream::Odom => type_hash::ODOMETRY,
                    Stream::Cloud => type_hash::POINT_CLOUD2,
                    _ => type_hash::LASER_SCAN,
                };
                Some(format!("{domain}/{robot}/{topic}/{dds}/{hash}"))
            }
        })
    }

    /// True when robots announce themselves with a SHIFT liveliness token (native); ROS 2 robots are alive
    /// while their topics are heard.
    pub fn has_liveliness(&self) -> bool {
        matches!(self, Self::Native)
    }
}

/// Robot and stream of `{robot}/{topic}`, checking the DDS type when given.
fn robot_stream(robot: &str, topic: &str, dds: Option<&str>) -> Option<(String, Stream)> {
    validate_name("robot name", robot).ok()?;
    let &(_, stream, dds_type) = TOPICS.iter().find(|(t, _, _)| *t == topic)?;
    if dds.is_some_and(|d| d != dds_type) {
        return None;
    }
    Some((robot.to_owned(), stream))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::type_hash;

    fn ks() -> KeySpace {
        KeySpace::default()
    }

    #[test]
    fn native_uses_the_key_space() {
        let m = Ros2Mapping::Native;
        let subs = m.subscriptions(&ks());
        assert_eq!(
            subs,
            vec![
                ("shift/default/robots/*/odom".to_owned(), Stream::Odom),
                ("shift/default/robots/*/cloud".to_owned(), Stream::Cloud),
                ("shift/default/robots/*/scan".to_owned(), Stream::Scan),
            ]
        );
        assert_eq!(
            m.robot_of("shift/default/robots/r1/cloud"),
            Some(("r1".into(), Stream::Cloud))
        );
        assert_eq!(
            m.robot_of("shift/default/robots/r1/alive"),
            Some(("r1".into(), Stream::Alive))
        );
        assert_eq!(m.robot_of("robots/r1/cloud"), None, "no prefix");
        assert_eq!(m.robot_of("shift/default/robots/r1/plan"), None);
        assert_eq!(m.robot_of("shift/default/bots/r1/odom"), None);
        assert_eq!(m.robot_of("r1/odom"), None);
    }

    #[test]
    fn classify_checks_the_native_key_space_and_skips_liveliness() {
        let acme = KeySpace::new("acme", "north").expect("valid");
        let n = Ros2Mapping::Native;
        assert_eq!(
            n.classify(&acme, "acme/north/robots/r1/scan"),
            Some(("r1".into(), Stream::Scan))
        );
        assert_eq!(n.classify(&acme, "shift/default/robots/r1/scan"), None);
        assert_eq!(n.classify(&acme, "acme/north/robots/r1/alive"), None);
        assert!(n.has_liveliness());
        let b = Ros2Mapping::BridgeRos2dds { namespace: None };
        assert_eq!(b.classify(&acme, "bot1/points"), Some(("bot1".into(), Stream::Cloud)));
        assert!(!b.has_liveliness());
        assert!(!Ros2Mapping::RmwZenoh { domain: 0 }.has_liveliness());
    }

    #[test]
    fn robot_keys_parse_back_in_every_layout() {
        let keys = ks();
        for m in [
            Ros2Mapping::Native,
            Ros2Mapping::BridgeRos2dds { namespace: None },
            Ros2Mapping::BridgeRos2dds {
                namespace: Some("/a/b/".into()),
            },
            Ros2Mapping::RmwZenoh { domain: 42 },
        ] {
            for stream in [Stream::Odom, Stream::Cloud, Stream::Scan] {
                let key = m.robot_key(&keys, "bot1", stream).expect("valid").expect("a key");
                assert_eq!(m.classify(&keys, &key), Some(("bot1".into(), stream)), "{m:?} {key}");
            }
            assert_eq!(
                m.robot_key(&keys, "bot1", Stream::Alive).expect("valid").is_some(),
                m.has_liveliness()
            );
            assert!(m.robot_key(&keys, "a/b", Stream::Odom).is_err());
        }
        let scan = Ros2Mapping::RmwZenoh { domain: 0 }
            .robot_key(&keys, "bot1", Stream::Scan)
            .expect("valid");
        assert_eq!(
            scan.as_deref(),
            Some(
                "0/bot1/scan/sensor_msgs::msg::dds_::LaserScan_/RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828"
            )
        );
    }

    #[test]
    fn bridge_without_namespace() {
        let m = Ros2Mapping::BridgeRos2dds { namespace: None };
        let subs = m.subscriptions(&ks());
        assert_eq!(
            subs,
            vec![
                ("*/odom".to_owned(), Stream::Odom),
                ("*/points".to_owned(), Stream::Cloud),
                ("*/scan".to_owned(), Stream::Scan)
            ]
        );
        assert_eq!(m.robot_of("bot1/odom"), Some(("bot1".into(), Stream::Odom)));
        assert_eq!(m.robot_of("bot1/points"), Some(("bot1".into(), Stream::Cloud)));
        assert_eq!(m.robot_of("bot1/scan"), Some(("bot1".into(), Stream::Scan)));
        for other in [
            "bot1/cloud",
            "bot1/odom/x",
            "odom",
            "/odom",
            "a/b/odom",
            "bot 1/odom",
            "shift/default/robots/r1/odom",
        ] {
            assert_eq!(m.robot_of(other), None, "{other}");
        }
    }

    #[test]
    fn bridge_with_namespace() {
        let m = Ros2Mapping::BridgeRos2dds {
            namespace: Some("/site1/floor2/".into()),
        };
        assert!(m.validate().is_ok());
        let subs = m.subscriptions(&ks());
        assert_eq!(subs[0], ("site1/floor2/*/odom".to_owned(), Stream::Odom));
        assert_eq!(
            m.robot_of("site1/floor2/bot1/scan"),
            Some(("bot1".into(), Stream::Scan))
        );
        assert_eq!(m.robot_of("site1/floor2x/bot1/scan"), None);
        assert_eq!(m.robot_of("site1/bot1/scan"), None);
        assert_eq!(m.robot_of("bot1/scan"), None);
        let bad = Ros2Mapping::BridgeRos2dds {
            namespace: Some("a/*/b".into()),
        };
        assert_eq!(bad.validate().map_err(|e| e.what), Err("namespace"));
    }

    #[test]
    fn rmw_zenoh_keys_carry_domain_type_and_hash() {
        let m = Ros2Mapping::RmwZenoh { domain: 7 };
        let subs = m.subscriptions(&ks());
        assert_eq!(
            subs,
            vec![
                ("7/*/odom/nav_msgs::msg::dds_::Odometry_/*".to_owned(), Stream::Odom),
                (
                    "7/*/points/sensor_msgs::msg::dds_::PointCloud2_/*".to_owned(),
                    Stream::Cloud
                ),
                ("7/*/scan/sensor_msgs::msg::dds_::LaserScan_/*".to_owned(), Stream::Scan),
            ]
        );
        let odom = format!("7/bot1/odom/nav_msgs::msg::dds_::Odometry_/{}", type_hash::ODOMETRY);
        assert_eq!(m.robot_of(&odom), Some(("bot1".into(), Stream::Odom)));
        let cloud = format!(
            "7/bot1/points/sensor_msgs::msg::dds_::PointCloud2_/{}",
            type_hash::POINT_CLOUD2
        );
        assert_eq!(m.robot_of(&cloud), Some(("bot1".into(), Stream::Cloud)));
        let scan = format!(
            "7/bot1/scan/sensor_msgs::msg::dds_::LaserScan_/{}",
            type_hash::LASER_SCAN
        );
        assert_eq!(m.robot_of(&scan), Some(("bot1".into(), Stream::Scan)));
        let humble = "7/bot1/odom/nav_msgs::msg::dds_::Odometry_/TypeHashNotSupported";
        assert_eq!(m.robot_of(humble), Some(("bot1".into(), Stream::Odom)));
        for other in [
            format!("0/bot1/odom/nav_msgs::msg::dds_::Odometry_/{}", type_hash::ODOMETRY),
            format!(
                "7/bot1/odom/sensor_msgs::msg::dds_::PointCloud2_/{}",
                type_hash::ODOMETRY
            ),
            format!("7/bot1/odom/nav_msgs::msg::dds_::Odometry_/{}/x", type_hash::ODOMETRY),
            "7/bot1/odom/nav_msgs::msg::dds_::Odometry_/RIHS01_xyz".to_owned(),
            "7/bot1/odom".to_owned(),
            "bot1/odom".to_owned(),
        ] {
            assert_eq!(m.robot_of(&other), None, "{other}");
        }
    }

    #[test]
    fn config_form_is_snake_case_tagged() {
        let cases = [
            (Ros2Mapping::Native, r#"{"kind":"native"}"#),
            (
                Ros2Mapping::BridgeRos2dds { namespace: None },
                r#"{"kind":"bridge_ros2dds"}"#,
            ),
            (
                Ros2Mapping::BridgeRos2dds {
                    namespace: Some("ns".into()),
                },
                r#"{"kind":"bridge_ros2dds","namespace":"ns"}"#,
            ),
            (
                Ros2Mapping::RmwZenoh { domain: 3 },
                r#"{"kind":"rmw_zenoh","domain":3}"#,
            ),
        ];
        for (m, json) in cases {
            assert_eq!(serde_json::to_string(&m).expect("ser"), json);
            assert_eq!(serde_json::from_str::<Ros2Mapping>(json).expect("de"), m);
        }
        let d: Ros2Mapping = serde_json::from_str(r#"{"kind":"rmw_zenoh"}"#).expect("default domain");
        assert_eq!(d, Ros2Mapping::RmwZenoh { domain: 0 });
        assert!(serde_json::from_str::<Ros2Mapping>(r#"{"kind":"ros1"}"#).is_err());
        assert!(serde_json::from_str::<Ros2Mapping>(r#"{"kind":"rmw_zenoh","domian":3}"#).is_err());
    }
}
