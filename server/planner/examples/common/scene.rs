//! A shared scene folder (`scene.json` beside a ROS map_server map) as a coverage space, for the examples and
//! the scene tests.

use std::path::Path;

use shift_planner::geom::Point2;
use shift_planner::map::load_ros_map;
use shift_planner::space::{CoverageSpace, RobotShape};

#[derive(serde::Deserialize)]
struct Scene {
    map: String,
    start: [f64; 2],
    robot_radius: f64,
    tool_width: f64,
}

/// The space of the scene in `dir`: its map, its robot, its start.
pub fn scene(dir: &Path) -> Result<CoverageSpace, String> {
    let text = std::fs::read_to_string(dir.join("scene.json")).map_err(|e| e.to_string())?;
    let scene: Scene = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let yaml = std::fs::read_to_string(dir.join(&scene.map)).map_err(|e| e.to_string())?;
    let map = load_ros_map(&yaml, |img| std::fs::read(dir.join(img)).map_err(|e| e.to_string()))
        .map_err(|e| e.to_string())?;
    let robot = RobotShape {
        radius_m: scene.robot_radius,
        tool_width_m: scene.tool_width,
    };
    CoverageSpace::new(map.grid, robot, Point2::new(scene.start[0], scene.start[1])).map_err(|e| e.to_string())
}
