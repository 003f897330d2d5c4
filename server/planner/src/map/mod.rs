//! Maps: occupancy grids, their loaders, distance fields, and the live ikd-tree.

pub mod distance;
pub mod field;
pub mod grid;
pub mod ikd_tree;
pub mod json_grid;
pub mod live_points;
pub mod obstacle;
pub mod ros;

pub use distance::DistanceField;
pub use field::{FieldRings, Ring};
pub use grid::{Cell, CellState, GridGeometry, OccupancyGrid, Thresholds};
pub use ikd_tree::{IkdParams, IkdTree};
pub use json_grid::JsonGrid;
pub use live_points::LivePoints;
pub use obstacle::ObstacleDistance;
pub use ros::{LoadedMap, MapMode, MapYaml, load_ros_map};
