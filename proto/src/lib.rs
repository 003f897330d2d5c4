//! # shift-proto
//!
//! SHIFT's wire types: the plan JSON of DESIGN §5.1, the scene file of §5.2, and (as later issues land) the
//! HTTP bodies, Zenoh key builders and ROS 2 codecs. Everything here is plain serde data; no algorithm.

pub mod api;
pub mod plan;
pub mod scene;

pub use api::{
    AssignRequest, AttributeBlob, AttributeSpec, ErrorBody, ErrorDetail, PlanAccepted, PlanEvent, PlanOptions, PlanRequest,
    PlanStatus, PlanStatusResponse, RegionReady, RobotSpec, RobotView, PoseView, SiteSummary, SpeedProfileResponse, SpeedSample,
};
pub use plan::{PlanDocument, PlanMetricsDoc, RegionDoc, WaypointDoc, WaypointKindDoc};
pub use scene::SceneFile;
