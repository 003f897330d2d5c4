//! The planner's error type: every way a map, a scene or a request can be rejected.

use thiserror::Error;

/// Everything the planner can reject. Messages say what is wrong and where, so the CLI can print one
/// line and the API can return it as a 400 body.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PlannerError {
    /// The map_server YAML could not be parsed.
    #[error("map yaml: {0}")]
    MapYaml(String),
    /// The image the YAML names could not be read.
    #[error("map image {path:?} is missing or unreadable: {reason}")]
    MissingImage {
        /// The image path as written in (or resolved from) the YAML.
        path: String,
        /// Why reading failed.
        reason: String,
    },
    /// The image bytes are not a decodable PGM or PNG.
    #[error("map image could not be decoded: {0}")]
    ImageDecode(String),
    /// The number of cells does not match width × height.
    #[error("map size mismatch: width {width} × height {height} needs {expected} cells, got {got}")]
    SizeMismatch {
        /// Declared width in cells.
        width: usize,
        /// Declared height in cells.
        height: usize,
        /// width × height.
        expected: usize,
        /// Cells actually given.
        got: usize,
    },
    /// A grid with no cells.
    #[error("map is empty (width {width}, height {height})")]
    EmptyMap {
        /// Width in cells.
        width: usize,
        /// Height in cells.
        height: usize,
    },
    /// More cells than [`crate::map::GridGeometry::MAX_CELLS`] (or a width × height that overflows).
    #[error("map too large: width {width} × height {height} cells is over the limit of {max_cells} cells")]
    MapTooLarge {
        /// Width in cells.
        width: usize,
        /// Height in cells.
        height: usize,
        /// The limit.
        max_cells: usize,
    },
    /// The resolution is zero, negative or not finite.
    #[error("map resolution must be a positive finite number of metres per cell, got {0}")]
    InvalidResolution(f64),
    /// A number that must be finite is NaN or infinite.
    #[error("{field} must be finite, got {value}")]
    NonFinite {
        /// Which field.
        field: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A parameter outside its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParam {
        /// Parameter name as the user spells it.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The start lies outside the map.
    #[error("start ({x:.3}, {y:.3}) m lies outside the map")]
    StartOutsideMap {
        /// Start x in the map frame, metres.
        x: f64,
        /// Start y in the map frame, metres.
        y: f64,
    },
    /// No cell of the map is far enough from obstacles for the robot.
    #[error("no traversable cell: the robot (radius {radius_m} m) fits nowhere on this map")]
    NoTraversableSpace {
        /// Robot radius in metres.
        radius_m: f64,
    },
    /// A terrain point cloud with no finite point left to grid.
    #[error("terrain cloud has no finite point: {skipped} of {total} points were NaN or infinite")]
    EmptyCloud {
        /// Points given.
        total: usize,
        /// Points skipped for a NaN or infinite coordinate.
        skipped: usize,
    },
    /// A terrain height field too small for the curvature and slope stencils (3 × 3 cells).
    #[error("terrain {field} of {width} × {height} cells is too small: at least {min} × {min} cells are needed")]
    TerrainTooSmall {
        /// Which input (e.g. `"elevation grid"`).
        field: &'static str,
        /// Width in cells.
        width: usize,
        /// Height in cells.
        height: usize,
        /// The smallest side accepted, cells.
        min: usize,
    },
    /// A terrain input that would need more of something than the planner allows.
    #[error("terrain {field}: {needed} is over the limit of {limit}")]
    TerrainTooLarge {
        /// Which quantity (e.g. `"waypoints"`).
        field: &'static str,
        /// How many the input needs.
        needed: usize,
        /// The limit.
        limit: usize,
    },
    /// The caller asked the planner to stop.
    #[error("planning was cancelled")]
    Cancelled,
    /// A plan correction (judge / repair / retime) was rejected.
    #[error("correction: {0}")]
    Correct(#[from] crate::correct::CorrectError),
}

/// Shorthand for planner results.
pub type Result<T, E = PlannerError> = std::result::Result<T, E>;

/// Checks that `value` is finite, naming the field otherwise.
pub fn finite(field: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(PlannerError::NonFinite { field, value })
    }
}
