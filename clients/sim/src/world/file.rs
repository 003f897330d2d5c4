//! The world file other programs write (issue 19's format, kept exactly; optional fields may be added):
//!
//! ```json
//! {"map": "map.yaml",
//!  "obstacles": [{"box": [x0, y0, x1, y1]}, {"disc": [x, y, r]}],
//!  "movers": [{"r": 0.3, "from": [x, y], "to": [x, y], "speed": 0.5}],
//!  "robots": [{"id": "r1", "start": [x, y, yaw], "radius": 0.25, "tool_width": 0.5}]}
//! ```
//!
//! The map path is relative to the world file. Optional robot fields: `v_max`, `a_max` (the plan request's
//! limits, defaults of the API), `w_max` (yaw rate limit, rad/s) and `region` (a polygon the robot's plan is
//! restricted to with `--plan-per-robot`).

use serde::{Deserialize, Serialize};

use crate::error::{SimError, bad};

/// A hidden static obstacle: the daemon does not know it; the robots' scans see it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ObstacleSpec {
    /// Axis-aligned box `[x0, y0, x1, y1]`, metres, map frame.
    #[serde(rename = "box")]
    Box([f64; 4]),
    /// Disc `[x, y, r]`, metres.
    #[serde(rename = "disc")]
    Disc([f64; 3]),
}

/// A disc walking a straight line back and forth between `from` and `to` at `speed`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MoverSpec {
    /// Radius, metres.
    pub r: f64,
    /// One end of its walk.
    pub from: [f64; 2],
    /// The other end.
    pub to: [f64; 2],
    /// Walking speed, m/s.
    pub speed: f64,
}

/// A robot of the world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpecFile {
    /// Its id (a key-safe name).
    pub id: String,
    /// Start pose `[x, y, yaw]` (metres, radians).
    pub start: [f64; 3],
    /// Body radius, metres.
    pub radius: f64,
    /// Tool width, metres.
    pub tool_width: f64,
    /// Top speed, m/s (default: the API's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_max: Option<f64>,
    /// Acceleration limit, m/s² (default: the API's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a_max: Option<f64>,
    /// Yaw-rate limit, rad/s (default 1.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub w_max: Option<f64>,
    /// The polygon its plan covers with `--plan-per-robot` (default: the whole site).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<Vec<[f64; 2]>>,
}

/// The world file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldFile {
    /// map_server YAML, relative to the world file.
    pub map: String,
    /// Hidden static obstacles.
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Moving obstacles.
    #[serde(default)]
    pub movers: Vec<MoverSpec>,
    /// Robots.
    #[serde(default)]
    pub robots: Vec<RobotSpecFile>,
}

fn finite(field: &str, values: &[f64]) -> Result<(), SimError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(bad(field, "must be finite numbers"))
    }
}

fn positive(field: &str, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(bad(field, format!("must be a positive number, got {v}")))
    }
}

impl WorldFile {
    /// Parses and checks a world file's text.
    pub fn parse(text: &str) -> Result<Self, SimError> {
        let world: Self = serde_json::from_str(text).map_err(|e| bad("world", e.to_string()))?;
        world.validate()?;
        Ok(world)
    }

    /// Every number finite, sizes positive, ids valid and distinct.
    pub fn validate(&self) -> Result<(), SimError> {
        if self.map.trim().is_empty() {
            return Err(bad("map", "is empty"));
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            match o {
                ObstacleSpec::Box(b) => {
                    finite(&format!("obstacles[{i}].box"), b)?;
                    if b[2] <= b[0] || b[3] <= b[1] {
                        return Err(bad(&format!("obstacles[{i}].box"), "needs x0 < x1 and y0 < y1"));
                    }
                }
                ObstacleSpec::Disc(d) => {
                    finite(&format!("obstacles[{i}].disc"), d)?;
                    positive(&format!("obstacles[{i}].disc r"), d[2])?;
                }
            }
        }
        for (i, m) in self.movers.iter().enumerate() {
            finite(&format!("movers[{i}]"), &[m.from[0], m.from[1], m.to[0], m.to[1]])?;
            positive(&format!("movers[{i}].r"), m.r)?;
            positive(&format!("movers[{i}].speed"), m.speed)?;
        }
        for (i, r) in self.robots.iter().enumerate() {
            shift_proto::keys::validate_name("robots[].id", &r.id)
                .map_err(|e| bad(&format!("robots[{i}].id"), e.to_string()))?;
            if self.robots[..i].iter().any(|o| o.id == r.id) {
                return Err(bad(&format!("robots[{i}].id"), format!("{:?} appears twice", r.id)));
            }
            finite(&format!("robots[{i}].start"), &r.start)?;
            positive(&format!("robots[{i}].radius"), r.radius)?;
            positive(&format!("robots[{i}].tool_width"), r.tool_width)?;
            for (name, v) in [("v_max", r.v_max), ("a_max", r.a_max), ("w_max", r.w_max)] {
                if let Some(v) = v {
                    positive(&format!("robots[{i}].{name}"), v)?;
                }
            }
            if let Some(region) = &r.region {
                if region.len() < 3 {
                    return Err(bad(&format!("robots[{i}].region"), "needs at least 3 points"));
                }
                finite(&format!("robots[{i}].region"), &region.concat())?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_issue_example_parses() {
        let w = WorldFile::parse(
            r#"{"map": "map.yaml", "obstacles": [{"box": [1, 2, 3, 4]}, {"disc": [5, 6, 0.5]}],
                "movers": [{"r": 0.3, "from": [0, 0], "to": [4, 0], "speed": 0.5}],
                "robots": [{"id": "r1", "start": [1, 1, 0], "radius": 0.25, "tool_width": 0.5}]}"#,
        )
        .expect("parses");
        assert_eq!(w.obstacles[0], ObstacleSpec::Box([1.0, 2.0, 3.0, 4.0]));
        assert_eq!(w.obstacles[1], ObstacleSpec::Disc([5.0, 6.0, 0.5]));
        assert_eq!(w.movers[0].speed, 0.5);
        assert_eq!(w.robots[0].id, "r1");
        assert_eq!(w.robots[0].region, None);
    }

    #[test]
    fn bad_fields_are_named() {
        let cases = [
            (
                r#"{"map": "m.yaml", "obstacles": [{"box": [3, 0, 1, 1]}]}"#,
                "obstacles[0].box",
            ),
            (
                r#"{"map": "m.yaml", "obstacles": [{"disc": [0, 0, -1]}]}"#,
                "obstacles[0].disc r",
            ),
            (
                r#"{"map": "m.yaml", "movers": [{"r": 0.3, "from": [0, 0], "to": [1, 0], "speed": 0}]}"#,
                "movers[0].speed",
            ),
            (
                r#"{"map": "m.yaml", "robots": [{"id": "a b", "start": [0, 0, 0], "radius": 0.2, "tool_width": 0.4}]}"#,
                "robots[0].id",
            ),
            (
                r#"{"map": "m.yaml", "robots": [{"id": "a", "start": [0, 0, 0], "radius": 0.2, "tool_width": 0.4},
                {"id": "a", "start": [1, 0, 0], "radius": 0.2, "tool_width": 0.4}]}"#,
                "robots[1].id",
            ),
            (
                r#"{"map": "m.yaml", "robots": [{"id": "a", "start": [0, 0, 0], "radius": 0.2, "tool_width": 0}]}"#,
                "robots[0].tool_width",
            ),
            (r#"{"map": "", "robots": []}"#, "map"),
            (r#"{"map": "m.yaml", "extra": 1}"#, "world"),
        ];
        for (text, field) in cases {
            let e = WorldFile::parse(text).expect_err(text);
            assert!(e.to_string().starts_with(field), "{text}: {e}");
        }
    }
}
