//! Robots: the registry (liveliness, last pose, progress) and plan assignment.

use axum::extract::{Path, State};
use axum::http::StatusCode;
use shift_engine::Event;
use shift_proto::{AssignRequest, ErrorBody, PlanStatusResponse, RobotSensorsView, RobotView};

use super::AppState;
use super::error::{ApiError, ApiJson};

/// Assign a ready plan to a robot: it is published on the robot's plan key (JSON) and plan_path key
/// (nav_msgs/Path CDR), served by the plan queryable, and its progress is tracked from odometry.
#[utoipa::path(post, path = "/v1/plans/{id}/assign", tag = "robots", params(("id" = String, Path)),
    request_body = AssignRequest,
    responses((status = 200, body = PlanStatusResponse),
        (status = 400, description = "invalid field (named in the message)", body = ErrorBody),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, description = "plan not ready", body = ErrorBody),
        (status = 413, description = "body over [http] max_request_bytes", body = ErrorBody)))]
pub async fn assign_plan(
    State(state): State<AppState>,
    Path(id): Path<String>,
    ApiJson(req): ApiJson<AssignRequest>,
) -> Result<ApiJson<PlanStatusResponse>, ApiError> {
    shift_engine::site::validate_name("robot", &req.robot)?;
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
        .engine
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

/// The view with what the ingest saw of the robot's sensor data.
fn with_sensors(state: &AppState, mut view: RobotView) -> RobotView {
    let counts = state.sensors.lock().ok().and_then(|h| h.counts(&view.robot));
    view.sensors = counts.map(|c| RobotSensorsView {
        placed: c.placed,
        points: c.points,
        waiting: c.waiting,
        dropped: c.dropped,
        last_drop: c.last_drop,
    });
    view
}

/// Every robot seen: alive or lost, last pose, plan and progress, the site its data feeds and what became of
/// its sensor data.
#[utoipa::path(get, path = "/v1/robots", tag = "robots", responses((status = 200, body = [RobotView])))]
pub async fn list_robots(State(state): State<AppState>) -> ApiJson<Vec<RobotView>> {
    let mut views = state.views.robots();
    // Robots only heard on sensor topics (no odometry, no token) are robots too.
    let hub_robots = state.sensors.lock().map(|h| h.robots()).unwrap_or_default();
    for robot in hub_robots {
        if !views.iter().any(|v| v.robot == robot) {
            views.push(unseen(&state, robot));
        }
    }
    views.sort_by(|a, b| a.robot.cmp(&b.robot));
    ApiJson(views.into_iter().map(|v| with_sensors(&state, v)).collect())
}

/// A robot the engine has not heard of, only the ingest.
fn unseen(state: &AppState, robot: String) -> RobotView {
    let site = state
        .sensors
        .lock()
        .ok()
        .and_then(|h| h.site_of(&robot).map(str::to_owned));
    RobotView {
        robot,
        alive: false,
        last_seen_ms: 0,
        pose: None,
        plan_id: None,
        driven_fraction: None,
        driven_m: None,
        last_correction: None,
        site,
        sensors: None,
    }
}

/// One robot.
#[utoipa::path(get, path = "/v1/robots/{id}", tag = "robots", params(("id" = String, Path)),
    responses((status = 200, body = RobotView), (status = 404, body = ErrorBody)))]
pub async fn get_robot(State(state): State<AppState>, Path(id): Path<String>) -> Result<ApiJson<RobotView>, ApiError> {
    let known = state.sensors.lock().map(|h| h.counts(&id).is_some()).unwrap_or(false);
    let view = match state.views.robot(&id) {
        Some(v) => v,
        None if known => unseen(&state, id),
        None => return Err(ApiError::not_found(format!("unknown robot {id:?}"))),
    };
    Ok(ApiJson(with_sensors(&state, view)))
}
