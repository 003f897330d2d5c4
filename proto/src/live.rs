//! What a site looks like right now, for operators (issue 21): `GET /v1/sites/{site}/live` (the live obstacle
//! points) and the payloads of the site's event stream `GET /v1/sites/{site}/events`, whose other events are
//! [`crate::PlanEvent`]s and [`crate::MissionView`]s of the site.

use serde::{Deserialize, Serialize};

use crate::api::RobotView;

/// Points served by `GET /v1/sites/{site}/live` when `max_points` is not given.
pub const LIVE_POINTS_DEFAULT: usize = 20_000;

/// Largest accepted `max_points`.
pub const LIVE_POINTS_MAX: usize = 200_000;

/// Query of `GET /v1/sites/{site}/live`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::IntoParams))]
#[cfg_attr(feature = "openapi", into_params(parameter_in = Query))]
#[serde(deny_unknown_fields)]
pub struct LivePointsQuery {
    /// At most this many points (default 20 000, at most 200 000); a larger map is thinned evenly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_points: Option<usize>,
}

/// The obstacle points the fleet's sensors put in a site's live map (its ikd-tree), map frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct LivePoints {
    /// Site.
    pub site: String,
    /// Points in the live map (all of them, also when fewer are sent).
    pub count: usize,
    /// Fewer points are sent than the map holds (`max_points`).
    pub truncated: bool,
    /// `[x, y]`, metres.
    pub points: Vec<[f64; 2]>,
}

/// Site event `robots`: the robots of the site whose view changed since the last such event (all of them in the
/// first one after connecting).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct RobotsUpdate {
    /// Their views, by robot id.
    pub robots: Vec<RobotView>,
}

/// Site events `coverage` and `live`: something the page fetches again changed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SiteChanged {
    /// Site.
    pub site: String,
    /// For `coverage`: the raster's last stamp, milliseconds since the Unix epoch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub updated_ms: Option<u64>,
    /// For `live`: points in the live map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<usize>,
}
