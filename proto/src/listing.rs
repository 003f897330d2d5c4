//! Listings and the map read-back of the HTTP API (DESIGN §5.3): `GET /v1/sites`, `GET /v1/plans?…` and
//! `GET /v1/sites/{site}/map`.
//!
//! Plans are listed newest first (by acceptance order) a page at a time: a page's `next` is the cursor to pass
//! as `after` for the following page; pages never repeat or skip a plan, even while new plans arrive (they
//! are newer than every cursor, so they only show on a fresh first page).

use serde::{Deserialize, Serialize};

use crate::api::{PlanStatus, PlanStatusResponse, SiteSummary};

/// Plans per page when `limit` is not given.
pub const PLAN_PAGE_DEFAULT: u32 = 50;

/// Largest accepted `limit`.
pub const PLAN_PAGE_MAX: u32 = 500;

/// `GET /v1/sites`: every site, in name order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SiteList {
    /// Each site's summary (as `GET /v1/sites/{site}` answers it).
    pub items: Vec<SiteSummary>,
}

/// Query of `GET /v1/plans`; every field optional. Unknown parameters are refused (400 naming them).
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::IntoParams))]
#[cfg_attr(feature = "openapi", into_params(parameter_in = Query))]
#[serde(deny_unknown_fields)]
pub struct PlanListQuery {
    /// Only plans on this site.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub site: Option<String>,
    /// Only plans in this lifecycle state (`queued`, `planning`, `ready`, `active`, `done`, `failed`,
    /// `cancelled`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub status: Option<PlanStatus>,
    /// Only plans assigned to this robot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<String>,
    /// Plans per page, 1–500 (default 50).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit: Option<u32>,
    /// Cursor: the `next` of the previous page (a plan id); the page holds the plans older than it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub after: Option<String>,
}

/// `GET /v1/plans`: one page of plans, newest first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct PlanList {
    /// The plans of this page, newest first (each as `GET /v1/plans/{id}` answers it).
    pub items: Vec<PlanStatusResponse>,
    /// Cursor of the next page (pass it as `after`); absent on the last page.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub next: Option<String>,
}

/// An occupancy grid shaped like nav_msgs/OccupancyGrid: the JSON body of `POST /v1/sites/{site}/map` and
/// the answer of `GET /v1/sites/{site}/map` (the site's map as the planner sees it, thresholded, so it can be
/// uploaded again unchanged).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct OccupancyGridDoc {
    /// Metres per cell edge.
    pub resolution: f64,
    /// Map-frame position of cell (0, 0)'s outer corner, metres.
    pub origin: [f64; 2],
    /// Columns.
    pub width: u64,
    /// Rows.
    pub height: u64,
    /// Row-major occupancy, row 0 at the origin: 0 free … 100 occupied, −1 unknown (the read-back holds only
    /// 0, 100 and −1).
    pub cells: Vec<i16>,
    /// Upload only: free below this probability (default 0.196).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free_thresh: Option<f64>,
    /// Upload only: occupied above this probability (default 0.65).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub occupied_thresh: Option<f64>,
}

impl OccupancyGridDoc {
    /// The value of cell (column, row), or `None` outside the grid.
    pub fn cell(&self, column: u64, row: u64) -> Option<i16> {
        if column >= self.width || row >= self.height {
            return None;
        }
        let i = usize::try_from(row * self.width + column).ok()?;
        self.cells.get(i).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn query_round_trips_and_refuses_unknown_fields() {
        let q = PlanListQuery {
            status: Some(PlanStatus::Ready),
            limit: Some(2),
            ..PlanListQuery::default()
        };
        let v = serde_json::to_value(&q).expect("ser");
        assert_eq!(v, serde_json::json!({"status": "ready", "limit": 2}));
        assert!(serde_json::from_str::<PlanListQuery>(r#"{"sort": "x"}"#).is_err());
    }

    #[test]
    fn grid_cells_by_column_and_row() {
        let g = OccupancyGridDoc {
            resolution: 0.5,
            origin: [0.0, 0.0],
            width: 2,
            height: 2,
            cells: vec![0, 0, 100, -1],
            free_thresh: None,
            occupied_thresh: None,
        };
        assert_eq!(g.cell(0, 1), Some(100));
        assert_eq!(g.cell(1, 1), Some(-1));
        assert_eq!(g.cell(2, 0), None);
        let text = serde_json::to_string(&g).expect("ser");
        assert!(!text.contains("thresh"));
    }
}
