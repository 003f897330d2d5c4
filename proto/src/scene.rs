//! Scene files (DESIGN §5.2): `scene.json` beside a map_server map.

use serde::{Deserialize, Serialize};

/// `{"map": "map.yaml", "start": [x, y], "robot_radius": r, "tool_width": w, "attribute": "attribute.pgm"?}`.
/// Paths are relative to the scene's directory; lengths in metres, map frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneFile {
    /// map_server YAML file name.
    pub map: String,
    /// Start (dock) position, metres.
    pub start: [f64; 2],
    /// Robot radius, metres.
    pub robot_radius: f64,
    /// Tool width, metres.
    pub tool_width: f64,
    /// Attribute image (A = value / 255), same size as the map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attribute: Option<String>,
    /// Free-text provenance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_scene() {
        let s: SceneFile =
            serde_json::from_str(r#"{"map":"map.yaml","start":[1.0,2.0],"robot_radius":0.2,"tool_width":0.4}"#)
                .expect("parses");
        assert_eq!(s.start, [1.0, 2.0]);
        assert!(s.attribute.is_none());
        assert!(serde_json::from_str::<SceneFile>(r#"{"map":"m.yaml"}"#).is_err());
    }
}
