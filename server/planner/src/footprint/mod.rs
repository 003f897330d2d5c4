//! Robots that are not discs (issue 23): a convex footprint polygon in the robot frame (Nav2's `footprint`
//! convention), checked against the occupancy grid pose by pose.
//!
//! - [`shape`]: the polygon, validated, its inscribed and circumscribed radii and the planning radius of the
//!   coverage space built for it;
//! - [`check`]: is a pose clear — the distance field for the easy cases, parry2d for the band between the
//!   two radii — and DESIGN §6 `collisions` in footprint form;
//! - [`poses`]: the poses a robot takes driving a polyline forward and turning in place at its vertices;
//! - [`lattice`]: a heading lattice search for transits the footprint decides (a doorway passed lengthwise),
//!   guided by [`guide`].
//!
//! Coverage with a footprint is `crate::pipeline::footprinted`.

pub mod check;
pub mod guide;
pub mod lattice;
pub mod poses;
pub mod shape;

#[cfg(test)]
mod tests;

pub use check::FootprintCheck;
pub use lattice::{LatticeParams, connect};
pub use shape::{FOOTPRINT_FIELD, Footprint};
