//! # shift-proto
//!
//! SHIFT's wire types: the plan JSON of DESIGN §5.1, the scene file of §5.2, the HTTP bodies of §5.3, the Zenoh
//! key expressions of §5.4 ([`keys`]) and the ROS 2 CDR codecs ([`ros`]). Plain data and codecs; no algorithm,
//! no I/O.

pub mod api;
pub mod attribute;
pub mod correction;
pub mod error;
pub mod field;
pub mod keys;
pub mod listing;
pub mod live;
pub mod mission;
pub mod plan;
pub mod ros;
pub mod scene;
pub mod terrain;

pub use api::{
    AssignRequest, ErrorBody, ErrorDetail, LastCorrection, PlanAccepted, PlanEvent, PlanObjective, PlanOptions,
    PlanRequest, PlanStatus, PlanStatusResponse, PoseView, ProgressJump, RegionReady, RobotSensorsView, RobotSpec,
    RobotView, SiteSummary, SpeedProfileResponse, SpeedSample, WatchHealth,
};
pub use attribute::{AttributeBlobDoc, AttributeDoc};
pub use correction::{CorrectionDoc, CorrectionError, CorrectionReason};
pub use error::CodecError;
pub use field::{FieldRequest, GeoReference};
pub use listing::{OccupancyGridDoc, PLAN_PAGE_DEFAULT, PLAN_PAGE_MAX, PlanList, PlanListQuery, SiteList};
pub use live::{LIVE_POINTS_DEFAULT, LIVE_POINTS_MAX, LivePoints, LivePointsQuery, RobotsUpdate, SiteChanged};
pub use mission::{
    MissionAccepted, MissionCoverage, MissionPlanView, MissionRequest, MissionRobot, MissionStatus, MissionView,
};
pub use plan::{PlanDocument, PlanMetricsDoc, RegionDoc, WaypointDoc, WaypointKindDoc};
pub use scene::SceneFile;
pub use terrain::{
    CloudSourceDoc, DroneMetricsDoc, GroundDoc, QuantilesDoc, RobotKindDoc, SurfaceDoc, TerrainDoc,
    TerrainPlanDocument, TerrainUploadQuery,
};
