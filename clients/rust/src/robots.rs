//! Robots over HTTP: the registry and plan assignment. (Robots themselves talk Zenoh: [`crate::robot`].)

use reqwest::Method;
use shift_proto::{AssignRequest, PlanStatusResponse, RobotView};

use crate::client::{Client, segment};
use crate::error::Result;

impl Client {
    /// `POST /v1/plans/{id}/assign`: publishes a computed plan to `robot` over Zenoh and starts watching its
    /// path; answers the plan's status (now `active`, with the robot).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let status = client.assign("p-1", "r1").await?;
    /// assert_eq!(status.robot.as_deref(), Some("r1"));
    /// # Ok(()) }
    /// ```
    pub async fn assign(&self, plan_id: &str, robot: &str) -> Result<PlanStatusResponse> {
        let path = format!("/v1/plans/{}/assign", segment(plan_id));
        let body = AssignRequest {
            robot: robot.to_owned(),
        };
        self.json(self.request(Method::POST, &path).json(&body), "the plan status")
            .await
    }

    /// `GET /v1/robots`: every robot seen, in name order.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// for r in client.robots().await? {
    ///     println!("{} {}", r.robot, if r.alive { "alive" } else { "lost" });
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn robots(&self) -> Result<Vec<RobotView>> {
        self.json(self.request(Method::GET, "/v1/robots"), "the robot list")
            .await
    }

    /// `GET /v1/robots/{id}`: last pose, plan and progress, the site its data feeds, last correction.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let r = client.robot("r1").await?;
    /// if let Some(pose) = r.pose {
    ///     println!("r1 at ({:.2}, {:.2})", pose.x, pose.y);
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn robot(&self, robot: &str) -> Result<RobotView> {
        let path = format!("/v1/robots/{}", segment(robot));
        self.json(self.request(Method::GET, &path), "the robot").await
    }
}
