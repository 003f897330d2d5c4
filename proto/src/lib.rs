//! # shift-proto
//!
//! SHIFT's wire types: the plan JSON of DESIGN §5.1, the scene file of §5.2, and (as later issues land) the
//! HTTP bodies, Zenoh key builders and ROS 2 codecs. Everything here is plain serde data; no algorithm.

pub mod attribute;
pub mod plan;
pub mod scene;

pub use attribute::{AttributeBlobDoc, AttributeDoc};
pub use plan::{PlanDocument, PlanMetricsDoc, RegionDoc, WaypointDoc, WaypointKindDoc};
pub use scene::SceneFile;
