//! Missions (one request for a fleet on one site: the site divided among the robots, each part an ordinary
//! plan): create, status, assign every part, replan the remainder, cancel, follow as events; and a site's
//! measured coverage raster.

use reqwest::Method;
use shift_proto::{MissionAccepted, MissionRequest, MissionRobot, MissionView, OccupancyGridDoc};

use crate::client::{Client, segment};
use crate::error::Result;
use crate::sse::MissionEvents;

impl Client {
    /// `POST /v1/missions`: asks for a mission; answers at once (202) with its id, status `queued`. The whole
    /// request is checked first: a 400 names the field (`robots[1].id …`), and nothing is stored.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::{MissionRequest, MissionRobot};
    /// let request = MissionRequest {
    ///     site: "warehouse".into(),
    ///     robots: vec![
    ///         MissionRobot::new("r1", [1.0, 1.0], 0.3, 0.6),
    ///         MissionRobot::new("r2", [38.0, 23.0], 0.3, 0.6),
    ///     ],
    ///     attribute: None,
    ///     options: None,
    ///     objective: None,
    /// };
    /// let accepted = client.create_mission(&request).await?;
    /// println!("mission {}", accepted.mission_id);
    /// # Ok(()) }
    /// ```
    pub async fn create_mission(&self, request: &MissionRequest) -> Result<MissionAccepted> {
        self.json(
            self.request(Method::POST, "/v1/missions").json(request),
            "the accepted mission",
        )
        .await
    }

    /// `GET /v1/missions/{id}`: status, one plan per robot (in the request's order), planned and measured
    /// coverage, progress and ETA.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let m = client.mission("m-1").await?;
    /// println!("{} at {:.0} %", m.status.as_str(), m.progress * 100.0);
    /// for p in &m.plans {
    ///     println!("{}: plan {} {}", p.robot, p.plan_id, p.status.as_str());
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn mission(&self, mission_id: &str) -> Result<MissionView> {
        let path = format!("/v1/missions/{}", segment(mission_id));
        self.json(self.request(Method::GET, &path), "the mission").await
    }

    /// `POST /v1/missions/{id}/assign`: publishes every part's plan to its robot, all or none (409 while a plan
    /// is not computed); answers the mission, now `active`.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::MissionStatus;
    /// let m = client.assign_mission("m-1").await?;
    /// assert_eq!(m.status, MissionStatus::Active);
    /// # Ok(()) }
    /// ```
    pub async fn assign_mission(&self, mission_id: &str) -> Result<MissionView> {
        let path = format!("/v1/missions/{}/assign", segment(mission_id));
        self.json(
            self.request(Method::POST, &path).json(&serde_json::json!({})),
            "the mission",
        )
        .await
    }

    /// `POST /v1/missions/{id}/replan`: asks for what the mission has left to be divided again among its robots
    /// that are not lost, each from where it is (what their tools swept is left out); each plan then gets its
    /// next version. Answers at once (202) with the mission's view; the new versions show once the job ends.
    /// 409 before the mission is planned and once it is done or cancelled. (The daemon also replans by itself
    /// when a robot is lost or comes back.)
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let before = client.mission("m-1").await?;
    /// client.replan_mission("m-1").await?;
    /// let versions: Vec<u64> = before.plans.iter().map(|p| p.version).collect();
    /// println!("replanning from versions {versions:?}");
    /// # Ok(()) }
    /// ```
    pub async fn replan_mission(&self, mission_id: &str) -> Result<MissionView> {
        let path = format!("/v1/missions/{}/replan", segment(mission_id));
        self.json(
            self.request(Method::POST, &path).json(&serde_json::json!({})),
            "the mission",
        )
        .await
    }

    /// `POST /v1/missions/{id}/robots`: `robot` joins the mission and takes a balanced share of what is left
    /// (a replan of the whole fleet, each robot from where it is). A bad robot answers 400 naming
    /// `robots[n]` (n its place after the mission's robots); 409 while the mission is being planned or once it
    /// ended.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let robot = shift_client::proto::MissionRobot::new("r4", [2.0, 3.0], 0.25, 0.5);
    /// let view = client.join_mission("m-1", &robot).await?;
    /// println!("{} robots now", view.plans.len());
    /// # Ok(()) }
    /// ```
    pub async fn join_mission(&self, mission_id: &str, robot: &MissionRobot) -> Result<MissionView> {
        let path = format!("/v1/missions/{}/robots", segment(mission_id));
        self.json(self.request(Method::POST, &path).json(robot), "the mission")
            .await
    }

    /// `DELETE /v1/missions/{id}`: cancels the mission and its plans not yet driven (a robot already driving
    /// its part finishes it); 409 once it is done, failed or cancelled.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::MissionStatus;
    /// let m = client.cancel_mission("m-1").await?;
    /// assert_eq!(m.status, MissionStatus::Cancelled);
    /// # Ok(()) }
    /// ```
    pub async fn cancel_mission(&self, mission_id: &str) -> Result<MissionView> {
        let path = format!("/v1/missions/{}", segment(mission_id));
        self.json(self.request(Method::DELETE, &path), "the mission").await
    }

    /// `GET /v1/missions/{id}/events`: the mission's views as they change, typed ([`MissionEvents`]): first
    /// the current one; the stream ends after `done`, `failed` or `cancelled`. Errors of the request itself
    /// (404 for an unknown mission) come here; a broken stream later comes as an `Err` item.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use futures_util::StreamExt;
    /// use shift_client::proto::MissionStatus;
    /// let mut views = client.mission_events("m-1").await?;
    /// while let Some(view) = views.next().await {
    ///     let view = view?;
    ///     println!("{} {:.0} %", view.status.as_str(), view.progress * 100.0);
    ///     if view.status == MissionStatus::Ready {
    ///         client.assign_mission(&view.mission_id).await?;
    ///     }
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn mission_events(&self, mission_id: &str) -> Result<MissionEvents> {
        let path = format!("/v1/missions/{}/events", segment(mission_id));
        Ok(MissionEvents::new(self.open_stream(&path).await?))
    }

    /// `GET /v1/sites/{site}/coverage`: what robots' tools swept on the site while driving plans, over its map:
    /// `100` swept, `0` free and not swept, `-1` not free.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let grid = client.site_coverage("warehouse").await?;
    /// let swept = grid.cells.iter().filter(|&&c| c == 100).count();
    /// let free = grid.cells.iter().filter(|&&c| c == 0).count();
    /// println!("{swept} of {} cells swept", swept + free);
    /// # Ok(()) }
    /// ```
    pub async fn site_coverage(&self, site: &str) -> Result<OccupancyGridDoc> {
        let path = format!("/v1/sites/{}/coverage", segment(site));
        self.json(self.request(Method::GET, &path), "the coverage grid").await
    }

    /// `GET /v1/sites/{site}/coverage?format=png`: the same raster as a PNG (the map in greys, swept cells
    /// green, one pixel per cell, the map's top row first).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let png = client.site_coverage_png("warehouse").await?;
    /// std::fs::write("coverage.png", &png).expect("written");
    /// # Ok(()) }
    /// ```
    pub async fn site_coverage_png(&self, site: &str) -> Result<Vec<u8>> {
        let path = format!("/v1/sites/{}/coverage", segment(site));
        let rb = self
            .request(Method::GET, &path)
            .query(&[("format", "png")])
            .header(reqwest::header::ACCEPT, "image/png");
        Ok(self.send(rb).await?.bytes().await?.to_vec())
    }
}
