//! Why a correction could not be computed. Small, `Copy`-free but cheap to clone, next to the algorithm.

use thiserror::Error;

/// Everything [`super::repair`], [`super::judge`]'s parameters and [`super::retime`] can reject.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CorrectError {
    /// A parameter of [`super::CorrectParams`] (or of a retime call) is out of range.
    #[error("invalid correction parameter {name}: {reason}")]
    InvalidParam {
        /// Field name as spelled in the params struct.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The path has fewer than two waypoints or a waypoint that is not finite.
    #[error("path is unusable for a correction: {0}")]
    BadPath(String),
    /// The breach does not lie on the path (segment index out of range, t outside [0, 1], end before start).
    #[error("breach does not lie on the path: {0}")]
    BadBreach(String),
    /// The start anchor (where the patch must begin, at or ahead of the robot) is itself closer than the robot
    /// radius to an obstacle, or off the map: no collision-free patch can start there.
    #[error("start anchor ({x:.3}, {y:.3}) m is in collision (clearance {clearance_m:.3} m)")]
    AnchorInCollision {
        /// Anchor x, map frame, metres.
        x: f64,
        /// Anchor y, map frame, metres.
        y: f64,
        /// Its clearance, metres.
        clearance_m: f64,
    },
    /// The world's grid and distance field do not describe the same raster.
    #[error("world is inconsistent: {0}")]
    BadWorld(String),
}
