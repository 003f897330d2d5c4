//! `--plan-per-robot`: one plan per robot from its start pose (within its region when it has one), asked of the
//! daemon over HTTP, waited for, and assigned to the robot.

use std::time::Duration;

use shift_client::Client;
use shift_client::proto::{PlanRequest, PlanStatus, RobotSpec};

use crate::error::SimError;
use crate::robot::SimRobot;

fn ferr(e: impl std::fmt::Display) -> SimError {
    SimError::Fleet(e.to_string())
}

/// The plan request for `robot` on `site`.
pub fn request_for(site: &str, robot: &SimRobot) -> PlanRequest {
    let spec = &robot.spec;
    let mut request = PlanRequest::new(
        site,
        [spec.start[0], spec.start[1]],
        RobotSpec {
            v_max: robot.limits.v_max,
            a_max: robot.limits.a_max,
            ..RobotSpec::new(spec.radius, spec.tool_width)
        },
    );
    request.region = spec.region.clone();
    // A start a few centimetres off its piece of free space is moved onto it, as a robot's dock often is.
    request.snap_start_m = Some(2.0 * spec.radius);
    request
}

/// Asks for every robot's plan, waits until each is ready (or failed), and assigns it; returns the plan ids.
pub async fn plan_and_assign(
    client: &Client,
    site: &str,
    robots: &[SimRobot],
    timeout: Duration,
) -> Result<Vec<String>, SimError> {
    let mut ids = Vec::with_capacity(robots.len());
    for robot in robots {
        let accepted = client.create_plan(&request_for(site, robot)).await.map_err(ferr)?;
        tracing::info!(robot = %robot.spec.id, plan = %accepted.plan_id, "plan requested");
        ids.push(accepted.plan_id);
    }
    for (robot, id) in robots.iter().zip(&ids) {
        let status = client
            .wait_plan(id, Duration::from_millis(200), timeout)
            .await
            .map_err(ferr)?;
        if status.status != PlanStatus::Ready {
            return Err(SimError::Fleet(format!(
                "plan {id} for {} ended {}: {}",
                robot.spec.id,
                status.status.as_str(),
                status.error.unwrap_or_default()
            )));
        }
        client.assign(id, &robot.spec.id).await.map_err(ferr)?;
        tracing::info!(robot = %robot.spec.id, plan = %id, "plan assigned");
    }
    Ok(ids)
}
