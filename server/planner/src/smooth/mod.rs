//! Path smoothing (seed 000 §IV.E): B-spline curves through the corners of a finished path where they keep
//! clearance and coverage, with the curvature that bounds the speed there.

pub mod bspline;
pub mod corners;

pub use bspline::BSpline;
pub use corners::{SmoothedPath, round_corners, round_corners_where};

/// Smoothing knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothParams {
    /// Longest leg (distance from a corner to where its curve starts), metres.
    pub max_leg_m: f64,
    /// Heading changes below this are left alone (radians).
    pub min_turn_rad: f64,
    /// Heading changes above this (reversals) stay sharp: the robot turns on the spot (radians).
    pub max_turn_rad: f64,
    /// Curve samples per radian of heading change (at least 4 per corner).
    pub samples_per_rad: f64,
}

impl SmoothParams {
    /// Defaults for a tool of width `tool_width_m` (metres): legs up to one tool width.
    pub fn for_tool(tool_width_m: f64) -> Self {
        Self {
            max_leg_m: tool_width_m,
            min_turn_rad: 1f64.to_radians(),
            max_turn_rad: 170f64.to_radians(),
            samples_per_rad: 8.0,
        }
    }
}
