//! `GET /v1/sites/{site}/live`: the obstacle points the fleet's sensors put in a site's live map, for the
//! operator's page and for anyone who wants to see what the watch sees.

use axum::extract::{Path, RawQuery, State};
use shift_proto::{ErrorBody, LIVE_POINTS_DEFAULT, LIVE_POINTS_MAX, LivePoints, LivePointsQuery};

use super::AppState;
use super::error::{ApiError, ApiJson};
use super::listings::query_pairs;

fn parse_query(raw: &str) -> Result<LivePointsQuery, ApiError> {
    let mut q = LivePointsQuery::default();
    for (key, value) in query_pairs(raw)? {
        match key.as_str() {
            "max_points" => {
                let n: usize = value
                    .parse()
                    .map_err(|_| ApiError::bad_request(format!("max_points: {value:?} is not a whole number")))?;
                if !(1..=LIVE_POINTS_MAX).contains(&n) {
                    return Err(ApiError::bad_request(format!(
                        "max_points: {n} is outside 1..={LIVE_POINTS_MAX}"
                    )));
                }
                q.max_points = Some(n);
            }
            other => {
                return Err(ApiError::bad_request(format!(
                    "{other}: unknown parameter (max_points)"
                )));
            }
        }
    }
    Ok(q)
}

/// Every `stride`-th of `points` so that at most `max` are kept, evenly over the map's order.
fn thin<T: Copy>(points: &[T], max: usize) -> Vec<T> {
    let stride = points.len().div_ceil(max.max(1)).max(1);
    points.iter().step_by(stride).copied().collect()
}

/// The live obstacle points of a site (map frame, metres): what robots' clouds and scans added that the static
/// map does not hold, minus what expired or was seen through. An empty list for a site no robot has fed yet.
#[utoipa::path(get, path = "/v1/sites/{site}/live", tag = "sites",
    params(("site" = String, Path, description = "site name"), LivePointsQuery),
    responses((status = 200, body = LivePoints), (status = 400, body = ErrorBody), (status = 404, body = ErrorBody)))]
pub async fn get_live(
    State(state): State<AppState>,
    Path(site): Path<String>,
    RawQuery(raw): RawQuery,
) -> Result<ApiJson<LivePoints>, ApiError> {
    let query = parse_query(raw.as_deref().unwrap_or(""))?;
    if state.views.site(&site).is_none() {
        return Err(ApiError::not_found(format!("unknown site {site:?}")));
    }
    let max = query.max_points.unwrap_or(LIVE_POINTS_DEFAULT);
    let all = state
        .live
        .get(&site)
        .and_then(|live| Some(live.map.read().ok()?.points().all()))
        .unwrap_or_default();
    let points: Vec<[f64; 2]> = thin(&all, max).iter().map(|p| [p.x, p.y]).collect();
    Ok(ApiJson(LivePoints {
        site,
        count: all.len(),
        truncated: points.len() < all.len(),
        points,
    }))
}

/// Points in a site's live map (0 when none yet).
pub fn live_count(state: &AppState, site: &str) -> usize {
    state
        .live
        .get(site)
        .and_then(|live| live.map.read().ok().map(|m| m.len()))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_at_most_max_spread_over_the_map() {
        let pts: Vec<u32> = (0..1000).collect();
        let kept = thin(&pts, 300);
        assert!(kept.len() <= 300 && kept.len() >= 250, "{}", kept.len());
        assert_eq!(kept[0], 0);
        assert!(*kept.last().unwrap_or(&0) >= 990);
        assert_eq!(thin(&pts, 5000).len(), 1000);
        assert!(thin::<u32>(&[], 10).is_empty());
    }

    #[test]
    fn the_query_names_a_bad_field() {
        assert_eq!(parse_query("max_points=10").map(|q| q.max_points).ok(), Some(Some(10)));
        for bad in ["max_points=0", "max_points=x", "max_points=999999999", "size=3"] {
            let msg = parse_query(bad).err().map(|e| e.message).unwrap_or_default();
            let field = bad.split('=').next().unwrap_or_default();
            assert!(msg.contains(field), "{bad}: {msg}");
        }
    }
}
