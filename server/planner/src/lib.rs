//! # shift-planner
//!
//! The coverage-planning algorithms of SHIFT: pure, synchronous and deterministic (every random choice comes
//! from a seed passed in), with no I/O, no clock and no wire types. Units are metres, seconds and radians in
//! the map frame unless a name says otherwise.
//!
//! Pipeline: [`map`] (grids, distance fields) → [`space`] (footprint, reach, coverable set) →
//! `decompose` (regions) → `pattern` (lanes, spiral, boundary passes) → `order` (visiting order) →
//! `link` (transits) → `metrics` (DESIGN §6); then `smooth` (B-spline corners) and `speed` (RFICP speed
//! profile and times) post-process the finished path. While a robot drives, `correct` judges the plan ahead
//! of it against the live map and repairs the stretches that lost clearance (IKD-SWOpt). [`terrain`] turns
//! point clouds into smoothed surfaces (seed 000 §IV.A–B): occupancy for ground robots, 3-D lanes for drones.

pub mod baseline;
pub mod correct;
pub mod decompose;
pub mod divide;
pub mod error;
pub mod footprint;
pub mod geom;
pub mod link;
pub mod map;
pub mod metrics;
pub mod order;
mod parallel;
pub mod pattern;
pub mod pipeline;
pub mod remainder;
pub mod smooth;
pub mod space;
pub mod speed;
pub mod terrain;
pub mod testing;

pub use error::{PlannerError, Result};
