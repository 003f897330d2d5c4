//! Listings: `GET /v1/sites`, `GET /v1/plans?site=&status=&robot=&limit=&after=` (newest first, cursor
//! pagination), and the map read-back `GET /v1/sites/{site}/map`. All answer from the read model.

use axum::extract::{Path, RawQuery, State};
use shift_planner::map::CellState;
use shift_proto::{
    ErrorBody, OccupancyGridDoc, PLAN_PAGE_DEFAULT, PLAN_PAGE_MAX, PlanList, PlanListQuery, PlanStatus, SiteList,
};

use super::AppState;
use super::error::{ApiError, ApiJson};

/// Every site with its summary, in name order.
#[utoipa::path(get, path = "/v1/sites", tag = "sites", responses((status = 200, body = SiteList)))]
pub async fn list_sites(State(state): State<AppState>) -> ApiJson<SiteList> {
    let now = state.clock.now_ms();
    let items = state
        .views
        .sites()
        .into_iter()
        .map(|mut s| {
            state.live.annotate(&mut s, now);
            s
        })
        .collect();
    ApiJson(SiteList { items })
}

/// Plans, newest first, a page at a time: pass a page's `next` as `after` for the following page. Filters
/// combine (site and status and robot). A bad parameter answers 400 naming it.
#[utoipa::path(get, path = "/v1/plans", tag = "plans", params(PlanListQuery),
    responses((status = 200, body = PlanList), (status = 400, body = ErrorBody)))]
pub async fn list_plans(State(state): State<AppState>, RawQuery(raw): RawQuery) -> Result<ApiJson<PlanList>, ApiError> {
    let query = parse_query(raw.as_deref().unwrap_or(""))?;
    let limit = query.limit.unwrap_or(PLAN_PAGE_DEFAULT) as usize;
    let before = match &query.after {
        None => None,
        Some(id) => Some(
            state
                .views
                .plan_seq(id)
                .ok_or_else(|| ApiError::bad_request(format!("after: no plan {id:?} to continue after")))?,
        ),
    };
    let (items, more) = state.views.plans_page(before, limit, |r| {
        query.site.as_ref().is_none_or(|s| &r.request.site == s)
            && query.status.is_none_or(|s| r.status == s)
            && query.robot.as_ref().is_none_or(|robot| r.robot.as_ref() == Some(robot))
    });
    let next = if more {
        items.last().map(|p| p.plan_id.clone())
    } else {
        None
    };
    Ok(ApiJson(PlanList { items, next }))
}

/// Reads the query string field by field, so an error names the field.
fn parse_query(raw: &str) -> Result<PlanListQuery, ApiError> {
    let pairs: Vec<(String, String)> = query_pairs(raw)?;
    let mut q = PlanListQuery::default();
    for (key, value) in pairs {
        let text = || Some(value.clone());
        match key.as_str() {
            "site" => q.site = text(),
            "robot" => q.robot = text(),
            "after" => q.after = text(),
            "status" => {
                let status = PlanStatus::ALL
                    .into_iter()
                    .find(|s| s.as_str() == value)
                    .ok_or_else(|| {
                        let names: Vec<&str> = PlanStatus::ALL.iter().map(|s| s.as_str()).collect();
                        ApiError::bad_request(format!("status: {value:?} is not one of {}", names.join(", ")))
                    })?;
                q.status = Some(status);
            }
            "limit" => {
                let n: u32 = value
                    .parse()
                    .map_err(|_| ApiError::bad_request(format!("limit: {value:?} is not a whole number")))?;
                if !(1..=PLAN_PAGE_MAX).contains(&n) {
                    return Err(ApiError::bad_request(format!(
                        "limit: {n} is outside 1..={PLAN_PAGE_MAX}"
                    )));
                }
                q.limit = Some(n);
            }
            other => {
                return Err(ApiError::bad_request(format!(
                    "{other}: unknown parameter (site, status, robot, limit, after)"
                )));
            }
        }
    }
    Ok(q)
}

/// `a=1&b=x%20y` → pairs, percent- and plus-decoded.
pub(super) fn query_pairs(raw: &str) -> Result<Vec<(String, String)>, ApiError> {
    let mut out = Vec::new();
    for part in raw.split('&').filter(|p| !p.is_empty()) {
        let (k, v) = part.split_once('=').unwrap_or((part, ""));
        let k =
            decode(k).ok_or_else(|| ApiError::bad_request(format!("query: {k:?} is not valid percent-encoding")))?;
        let v = decode(v).ok_or_else(|| ApiError::bad_request(format!("{k}: value is not valid percent-encoding")))?;
        out.push((k, v));
    }
    Ok(out)
}

fn decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'+' => out.push(b' '),
            b'%' => {
                let hex = s.get(i + 1..i + 3)?;
                out.push(u8::from_str_radix(hex, 16).ok()?);
                i += 2;
            }
            b => out.push(b),
        }
        i += 1;
    }
    String::from_utf8(out).ok()
}

/// The site's map as the planner sees it (thresholded: 0 free, 100 occupied, −1 unknown), in the shape of the
/// JSON upload, so it can be uploaded again unchanged.
#[utoipa::path(get, path = "/v1/sites/{site}/map", tag = "sites",
    params(("site" = String, Path, description = "site name")),
    responses((status = 200, body = OccupancyGridDoc), (status = 404, body = ErrorBody)))]
pub async fn get_site_map(
    State(state): State<AppState>,
    Path(site): Path<String>,
) -> Result<ApiJson<OccupancyGridDoc>, ApiError> {
    let grid = state
        .views
        .site_map(&site)
        .ok_or_else(|| ApiError::not_found(format!("unknown site {site:?}")))?;
    let g = grid.geometry;
    let cells = grid
        .cells
        .iter()
        .map(|c| match c {
            CellState::Free => 0,
            CellState::Occupied => 100,
            CellState::Unknown => -1,
        })
        .collect();
    Ok(ApiJson(OccupancyGridDoc {
        resolution: g.resolution,
        origin: [g.origin.x, g.origin.y],
        width: g.width as u64,
        height: g.height as u64,
        cells,
        free_thresh: None,
        occupied_thresh: None,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_parse_field_by_field() {
        let q = parse_query("site=my%20site&status=ready&limit=3&after=p-9&robot=r+1").expect("parses");
        assert_eq!(q.site.as_deref(), Some("my site"));
        assert_eq!(q.status, Some(PlanStatus::Ready));
        assert_eq!(q.limit, Some(3));
        assert_eq!(q.after.as_deref(), Some("p-9"));
        assert_eq!(q.robot.as_deref(), Some("r 1"));
        for (bad, field) in [
            ("limit=0", "limit"),
            ("limit=501", "limit"),
            ("limit=-1", "limit"),
            ("status=busy", "status"),
            ("sort=asc", "sort"),
            ("site=%zz", "site"),
        ] {
            let e = parse_query(bad).expect_err(bad);
            assert_eq!(e.status, axum::http::StatusCode::BAD_REQUEST);
            assert!(e.message.starts_with(field), "{bad}: {}", e.message);
        }
    }
}
