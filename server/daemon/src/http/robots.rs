//! Robots: the registry (liveliness, last pose, progress) and plan assignment.

use axum::extract::{Path, State};
use axum::http::StatusCode;
use shift_engine::Event;
use shift_proto::{AssignRequest, ErrorBody, PlanStatusResponse, RobotView};

use super::AppState;
use super::error::{ApiError, ApiJson};

/// Assign a ready plan to a robot: it is published on the robot's plan key (JSON) and plan_path key
/// (nav_msgs/Path CDR), served by the plan queryable, and its progress is tracked from odometry.
#[utoipa::path(post, path = "/v1/plans/{id}/assign", tag = "robots", params(("id" = String, Path)),
    request_body = AssignRequest,
    responses((status = 200, body = PlanStatusResponse), (status = 400, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, description = "plan not ready", body = ErrorBody)))]
pub async fn assign_plan(
    State(state): State<AppState>,
    Path(id): Path<String>,
    ApiJson(req): ApiJson<AssignRequest>,
) -> Result<ApiJson<PlanStatusResponse>, ApiError> {
    let view = state
        .views
        .plan(&id)
        .ok_or_else(|| ApiError::not_found(format!("unknown plan {id:?}")))?;
    let doc = view.doc.ok_or_else(|| {
        ApiError::new(
            StatusCode::CONFLICT,
            "invalid_state",
            format!(
                "plan {id} is {}; only a computed plan can be assigned",
                view.record.status.as_str()
            ),
        )
    })?;
    let reply = state
        .brain
        .call(Event::AssignPlan {
            plan_id: id,
            robot: req.robot,
            doc,
        })
        .await?;
    let rec = reply
        .plans
        .into_iter()
        .next()
        .ok_or_else(|| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", "no plan record"))?;
    Ok(ApiJson(rec.to_response()))
}

/// Every robot seen: alive or lost, last pose, plan and progress.
#[utoipa::path(get, path = "/v1/robots", tag = "robots", responses((status = 200, body = [RobotView])))]
pub async fn list_robots(State(state): State<AppState>) -> ApiJson<Vec<RobotView>> {
    ApiJson(state.views.robots())
}

/// One robot.
#[utoipa::path(get, path = "/v1/robots/{id}", tag = "robots", params(("id" = String, Path)),
    responses((status = 200, body = RobotView), (status = 404, body = ErrorBody)))]
pub async fn get_robot(State(state): State<AppState>, Path(id): Path<String>) -> Result<ApiJson<RobotView>, ApiError> {
    state
        .views
        .robot(&id)
        .map(ApiJson)
        .ok_or_else(|| ApiError::not_found(format!("unknown robot {id:?}")))
}
