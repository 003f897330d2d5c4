//! Zenoh key expressions of DESIGN §5.4 (`{prefix}/{fleet}/robots/{robot}/odom` …): builders, wildcards and the
//! parser that tells which robot and stream a received key belongs to. ROS 2 key layouts: [`Ros2Mapping`].

mod ros2;

pub use ros2::Ros2Mapping;

/// What a robot sends: the stream a received key carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stream {
    /// nav_msgs/Odometry CDR or JSON odometry.
    Odom,
    /// sensor_msgs/PointCloud2 CDR.
    Cloud,
    /// sensor_msgs/LaserScan CDR.
    Scan,
    /// The robot's liveliness token.
    Alive,
}

/// A robot name, fleet, prefix or plan id that cannot be part of a key expression.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid {what} `{value}`: {reason}")]
pub struct KeyError {
    /// `robot name`, `fleet`, `prefix`, `plan id` or `namespace`.
    pub what: &'static str,
    /// The rejected value.
    pub value: String,
    /// Why.
    pub reason: &'static str,
}

/// Longest accepted name, bytes (= characters: names are ASCII).
pub const MAX_NAME_BYTES: usize = 64;

/// The one name rule of the whole system, for every name that becomes part of a URL path or a Zenoh key chunk:
/// sites, robots, plan ids, the fleet, each chunk of the key prefix and of a ROS 2 namespace. A name is 1–64
/// characters of `[A-Za-z0-9_-]` (so every ROS 2 name fits; no `/`, no wildcard or verbatim characters, no
/// `.`/`..` path segments, nothing a URL must escape). `what` names the field in the error (`site`,
/// `robot name`, …).
pub fn validate_name(what: &'static str, value: &str) -> Result<(), KeyError> {
    let fail = |reason| {
        Err(KeyError {
            what,
            value: value.to_owned(),
            reason,
        })
    };
    if value.is_empty() {
        return fail("must not be empty");
    }
    if value.len() > MAX_NAME_BYTES {
        return fail("is longer than 64 characters");
    }
    if !value
        .bytes()
        .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
    {
        return fail("may hold only letters, digits, '-' and '_'");
    }
    Ok(())
}

/// Checks a multi-chunk prefix such as `shift` or `acme/site1`: chunks separated by single `/`, each a valid
/// name (so no leading, trailing or doubled `/`).
pub fn validate_path(what: &'static str, value: &str) -> Result<(), KeyError> {
    if value.is_empty() {
        return Err(KeyError {
            what,
            value: value.to_owned(),
            reason: "must not be empty",
        });
    }
    for chunk in value.split('/') {
        validate_name(what, chunk).map_err(|e| KeyError {
            value: value.to_owned(),
            ..e
        })?;
    }
    Ok(())
}

/// The key space of one fleet: every key is `{prefix}/{fleet}/…` (DESIGN §5.4).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct KeySpace {
    /// Key prefix, default `shift`; one or more chunks (`acme/shift`). Checked by [`KeySpace::new`].
    pub prefix: String,
    /// Fleet name, default `default`; one chunk.
    pub fleet: String,
}

impl Default for KeySpace {
    fn default() -> Self {
        Self {
            prefix: "shift".into(),
            fleet: "default".into(),
        }
    }
}

impl KeySpace {
    /// A validated key space.
    pub fn new(prefix: impl Into<String>, fleet: impl Into<String>) -> Result<Self, KeyError> {
        let ks = Self {
            prefix: prefix.into(),
            fleet: fleet.into(),
        };
        ks.validate()?;
        Ok(ks)
    }

    /// Checks prefix and fleet (for a key space built as a struct literal, e.g. from config).
    pub fn validate(&self) -> Result<(), KeyError> {
        validate_path("prefix", &self.prefix)?;
        validate_name("fleet", &self.fleet)
    }

    fn robot_key(&self, robot: &str, leaf: &str) -> Result<String, KeyError> {
        validate_name("robot name", robot)?;
        Ok(format!("{}/{}/robots/{robot}/{leaf}", self.prefix, self.fleet))
    }

    fn all_robots(&self, leaf: &str) -> String {
        format!("{}/{}/robots/*/{leaf}", self.prefix, self.fleet)
    }

    /// `{prefix}/{fleet}/robots/{robot}/odom`: robot → server odometry (nav_msgs/Odometry CDR or JSON).
    pub fn odom(&self, robot: &str) -> Result<String, KeyError> {
        self.robot_key(robot, "odom")
    }

    /// `{prefix}/{fleet}/robots/{robot}/cloud`: robot → server sensor_msgs/PointCloud2 CDR.
    pub fn cloud(&self, robot: &str) -> Result<String, KeyError> {
        self.robot_key(robot, "cloud")
    }

    /// `{prefix}/{fleet}/robots/{robot}/scan`: robot → server sensor_msgs/LaserScan CDR.
    pub fn scan(&self, robot: &str) -> Result<String, KeyError> {
        self.robot_key(robot, "scan")
    }

    /// `{prefix}/{fleet}/robots/{robot}/plan`: server → robot plan JSON (DESIGN §5.1); also the queryable.
    pub fn plan(&self, robot: &str) -> Result<String, KeyError> {
        self.robot_key(robot, "plan")
    }

    /// `{prefix}/{fleet}/robots/{robot}/plan_path`: server → robot nav_msgs/Path CDR of the plan, map frame.
    pub fn plan_path(&self, robot: &str) -> Result<String, KeyError> {
        self.robot_key(robot, "plan_path")
    }

    /// `{prefix}/{fleet}/robots/{robot}/corrections`: server → robot correction JSON.
    pub fn corrections(&self, robot: &str) -> Result<String, KeyError> {
        self.robot_key(robot, "corrections")
    }

    /// `{prefix}/{fleet}/robots/{robot}/alive`: the robot's liveliness token.
    pub fn alive(&self, robot: &str) -> Result<String, KeyError> {
        self.robot_key(robot, "alive")
    }

    /// `{prefix}/{fleet}/plans/{plan_id}/status`: server → anyone plan status JSON.
    pub fn plan_status(&self, plan_id: &str) -> Result<String, KeyError> {
        validate_name("plan id", plan_id)?;
        Ok(format!("{}/{}/plans/{plan_id}/status", self.prefix, self.fleet))
    }

    /// `{prefix}/{fleet}/robots/*/odom`: every robot's odometry.
    pub fn all_odom(&self) -> String {
        self.all_robots("odom")
    }

    /// `{prefix}/{fleet}/robots/*/cloud`: every robot's clouds.
    pub fn all_cloud(&self) -> String {
        self.all_robots("cloud")
    }

    /// `{prefix}/{fleet}/robots/*/scan`: every robot's laser scans.
    pub fn all_scan(&self) -> String {
        self.all_robots("scan")
    }

    /// `{prefix}/{fleet}/robots/*/alive`: every robot's liveliness token (for a liveliness subscriber).
    pub fn all_alive(&self) -> String {
        self.all_robots("alive")
    }

    /// `{prefix}/{fleet}/plans/*/status`: every plan's status.
    pub fn all_plan_status(&self) -> String {
        format!("{}/{}/plans/*/status", self.prefix, self.fleet)
    }

    /// Every robot's plan key, for the queryable that serves current plans: `{prefix}/{fleet}/robots/*/plan`.
    pub fn all_plan(&self) -> String {
        format!("{}/{}/robots/*/plan", self.prefix, self.fleet)
    }

    /// The robot a plan key (or query on it) is for.
    pub fn robot_of_plan(&self, key: &str) -> Option<String> {
        let rest = key.strip_prefix(self.prefix.as_str())?.strip_prefix('/')?;
        let rest = rest.strip_prefix(self.fleet.as_str())?.strip_prefix("/robots/")?;
        let robot = rest.strip_suffix("/plan")?;
        validate_name("robot name", robot).ok()?;
        Some(robot.to_owned())
    }

    /// The robot and stream of a received key `{prefix}/{fleet}/robots/{robot}/{odom|cloud|scan|alive}` of this
    /// key space; `None` for any other key (another prefix or fleet, another leaf, an invalid robot name).
    pub fn robot_of(&self, key: &str) -> Option<(String, Stream)> {
        let rest = key.strip_prefix(self.prefix.as_str())?.strip_prefix('/')?;
        let rest = rest.strip_prefix(self.fleet.as_str())?.strip_prefix('/')?;
        parse_robot_leaf(rest)
    }
}

/// `robots/{robot}/{leaf}` → (robot, stream).
fn parse_robot_leaf(rest: &str) -> Option<(String, Stream)> {
    let mut parts = rest.split('/');
    let (Some("robots"), Some(robot), Some(leaf), None) = (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return None;
    };
    validate_name("robot name", robot).ok()?;
    let stream = match leaf {
        "odom" => Stream::Odom,
        "cloud" => Stream::Cloud,
        "scan" => Stream::Scan,
        "alive" => Stream::Alive,
        _ => return None,
    };
    Some((robot.to_owned(), stream))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builders_follow_design_5_4() {
        let ks = KeySpace::default();
        assert_eq!(ks.odom("r1").as_deref(), Ok("shift/default/robots/r1/odom"));
        assert_eq!(ks.cloud("r1").as_deref(), Ok("shift/default/robots/r1/cloud"));
        assert_eq!(ks.scan("r1").as_deref(), Ok("shift/default/robots/r1/scan"));
        assert_eq!(ks.plan("r1").as_deref(), Ok("shift/default/robots/r1/plan"));
        assert_eq!(ks.plan_path("r1").as_deref(), Ok("shift/default/robots/r1/plan_path"));
        assert_eq!(
            ks.corrections("r1").as_deref(),
            Ok("shift/default/robots/r1/corrections")
        );
        assert_eq!(ks.alive("r1").as_deref(), Ok("shift/default/robots/r1/alive"));
        assert_eq!(ks.plan_status("p-42").as_deref(), Ok("shift/default/plans/p-42/status"));
        assert_eq!(ks.all_odom(), "shift/default/robots/*/odom");
        assert_eq!(ks.all_cloud(), "shift/default/robots/*/cloud");
        assert_eq!(ks.all_alive(), "shift/default/robots/*/alive");
        assert_eq!(ks.all_plan_status(), "shift/default/plans/*/status");
        let acme = KeySpace::new("acme/shift", "north").expect("valid");
        assert_eq!(acme.odom("bot_7").as_deref(), Ok("acme/shift/north/robots/bot_7/odom"));
    }

    /// The one test of the name rule (every other crate calls `validate_name`).
    #[test]
    fn invalid_names_are_rejected() {
        let ks = KeySpace::default();
        for bad in [
            "",
            "a/b",
            "r*",
            "r$1",
            "r#",
            "r?",
            "r 1",
            "@r",
            "tab\t",
            ".",
            "..",
            "r.1",
            "é",
            "a%2Fb",
            &"x".repeat(65),
        ] {
            let err = ks.odom(bad).expect_err(bad);
            assert_eq!(err.what, "robot name");
            assert_eq!(err.value, bad);
            assert!(ks.plan_status(bad).is_err(), "{bad}");
        }
        for good in ["robot-1_a", "R2", "p-42", &"x".repeat(64)] {
            assert!(ks.odom(good).is_ok(), "{good}");
        }
        for (prefix, fleet) in [
            ("", "f"),
            ("/shift", "f"),
            ("shift/", "f"),
            ("a//b", "f"),
            ("sh*ft", "f"),
        ] {
            assert_eq!(
                KeySpace::new(prefix, fleet).map_err(|e| e.what),
                Err("prefix"),
                "{prefix}"
            );
        }
        for fleet in ["", "a/b", "**", "f?"] {
            assert_eq!(
                KeySpace::new("shift", fleet).map_err(|e| e.what),
                Err("fleet"),
                "{fleet}"
            );
        }
        let err = ks.odom("a/b").expect_err("slash");
        assert_eq!(
            err.to_string(),
            "invalid robot name `a/b`: may hold only letters, digits, '-' and '_'"
        );
    }

    #[test]
    fn robot_of_parses_only_this_key_space() {
        let ks = KeySpace::new("acme/shift", "north").expect("valid");
        assert_eq!(
            ks.robot_of("acme/shift/north/robots/r1/odom"),
            Some(("r1".into(), Stream::Odom))
        );
        assert_eq!(
            ks.robot_of("acme/shift/north/robots/r1/cloud"),
            Some(("r1".into(), Stream::Cloud))
        );
        assert_eq!(
            ks.robot_of("acme/shift/north/robots/r1/scan"),
            Some(("r1".into(), Stream::Scan))
        );
        assert_eq!(
            ks.robot_of("acme/shift/north/robots/r1/alive"),
            Some(("r1".into(), Stream::Alive))
        );
        for other in [
            "acme/shift/south/robots/r1/odom",
            "acme/shiftx/north/robots/r1/odom",
            "acme/shift/northx/robots/r1/odom",
            "shift/north/robots/r1/odom",
            "acme/shift/north/robots/r1/plan",
            "acme/shift/north/robots/r1/odom/extra",
            "acme/shift/north/robots//odom",
            "acme/shift/north/robots/@r1/odom",
            "acme/shift/north/plans/p1/status",
            "acme/shift/north",
            "",
        ] {
            assert_eq!(ks.robot_of(other), None, "{other}");
        }
    }
}
