//! Plans: create, status, listing, path, speed profile, cancel, and waiting for a result.

use std::time::Duration;

use reqwest::Method;
use shift_proto::{
    PlanAccepted, PlanDocument, PlanList, PlanListQuery, PlanMetricsDoc, PlanRequest, PlanStatusResponse,
    SpeedProfileResponse,
};

use crate::client::{Client, segment};
use crate::error::{ClientError, Result};

impl Client {
    /// `POST /v1/plans`: asks for a plan; answers at once (202) with its id, status `queued`.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::{PlanRequest, RobotSpec};
    /// let request = PlanRequest {
    ///     site: "demo".into(),
    ///     start: [0.5, 0.5],
    ///     robot: RobotSpec::new(0.15, 0.3),
    ///     attribute: None,
    ///     region: None,
    ///     options: None,
    ///     objective: None,
    ///     snap_start_m: None,
    /// };
    /// let accepted = client.create_plan(&request).await?;
    /// println!("plan {}", accepted.plan_id);
    /// # Ok(()) }
    /// ```
    pub async fn create_plan(&self, request: &PlanRequest) -> Result<PlanAccepted> {
        self.json(
            self.request(Method::POST, "/v1/plans").json(request),
            "the accepted plan",
        )
        .await
    }

    /// [`Client::create_plan`], sent again while the plan queue is full (429) after the wait the daemon asks for
    /// (`Retry-After`; 1 s when it gives none), for at most `max_wait` in all. The last 429 is returned when the
    /// time is up; any other error at once.
    pub async fn create_plan_waiting(
        &self,
        request: &PlanRequest,
        max_wait: std::time::Duration,
    ) -> Result<PlanAccepted> {
        let deadline = tokio::time::Instant::now() + max_wait;
        loop {
            match self.create_plan(request).await {
                Err(e) if e.status() == Some(reqwest::StatusCode::TOO_MANY_REQUESTS) => {
                    let wait = e.retry_after().unwrap_or(std::time::Duration::from_secs(1));
                    if tokio::time::Instant::now() + wait > deadline {
                        return Err(e);
                    }
                    tokio::time::sleep(wait).await;
                }
                other => return other,
            }
        }
    }

    /// `GET /v1/plans/{id}`: status, progress, metrics once ready, error once failed.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let status = client.plan("p-1").await?;
    /// println!("{} at {:.0} %", status.status.as_str(), status.progress * 100.0);
    /// # Ok(()) }
    /// ```
    pub async fn plan(&self, plan_id: &str) -> Result<PlanStatusResponse> {
        let path = format!("/v1/plans/{}", segment(plan_id));
        self.json(self.request(Method::GET, &path), "the plan status").await
    }

    /// The figures of merit of a plan (DESIGN §6), `None` until it is computed.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// if let Some(m) = client.metrics("p-1").await? {
    ///     println!("{:.1} % covered in {:.0} s", m.coverage_pct, m.duration_s);
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn metrics(&self, plan_id: &str) -> Result<Option<PlanMetricsDoc>> {
        Ok(self.plan(plan_id).await?.metrics)
    }

    /// `GET /v1/plans?…`: one page of plans, newest first; pass the page's `next` as `after` for the next.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::{PlanListQuery, PlanStatus};
    /// let mut query = PlanListQuery { site: Some("demo".into()), status: Some(PlanStatus::Ready),
    ///     limit: Some(100), ..PlanListQuery::default() };
    /// loop {
    ///     let page = client.plans(&query).await?;
    ///     for p in &page.items {
    ///         println!("{} {}", p.plan_id, p.status.as_str());
    ///     }
    ///     match page.next {
    ///         Some(next) => query.after = Some(next),
    ///         None => break,
    ///     }
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn plans(&self, query: &PlanListQuery) -> Result<PlanList> {
        self.json(self.request(Method::GET, "/v1/plans").query(query), "the plan list")
            .await
    }

    /// Every plan the query selects, following the pages (`query.after` is where to start; `query.limit` is
    /// the page size).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use shift_client::proto::PlanListQuery;
    /// let on_r1 = client
    ///     .all_plans(PlanListQuery { robot: Some("r1".into()), ..PlanListQuery::default() })
    ///     .await?;
    /// println!("r1 was given {} plans", on_r1.len());
    /// # Ok(()) }
    /// ```
    pub async fn all_plans(&self, mut query: PlanListQuery) -> Result<Vec<PlanStatusResponse>> {
        let mut all = Vec::new();
        loop {
            let page = self.plans(&query).await?;
            all.extend(page.items);
            match page.next {
                Some(next) if query.after.as_ref() != Some(&next) => query.after = Some(next),
                _ => return Ok(all),
            }
        }
    }

    /// `GET /v1/plans/{id}/path`: the plan document (DESIGN §5.1), current version (409 until computed).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let doc = client.path("p-1").await?;
    /// println!("version {}: {} waypoints", doc.version, doc.waypoints.len());
    /// # Ok(()) }
    /// ```
    pub async fn path(&self, plan_id: &str) -> Result<PlanDocument> {
        let path = format!("/v1/plans/{}/path", segment(plan_id));
        self.json(self.request(Method::GET, &path), "the plan document").await
    }

    /// `GET /v1/plans/{id}/speed-profile`: per waypoint, arc length s (m), speed v (m/s), time t (s).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let profile = client.speed_profile("p-1").await?;
    /// let last = profile.samples.last().map_or(0.0, |s| s.t);
    /// println!("{last:.0} s to drive");
    /// # Ok(()) }
    /// ```
    pub async fn speed_profile(&self, plan_id: &str) -> Result<SpeedProfileResponse> {
        let path = format!("/v1/plans/{}/speed-profile", segment(plan_id));
        self.json(self.request(Method::GET, &path), "the speed profile").await
    }

    /// `DELETE /v1/plans/{id}`: cancels a queued or planning plan (409 once it finished).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let status = client.cancel_plan("p-1").await?;
    /// assert_eq!(status.status, shift_client::proto::PlanStatus::Cancelled);
    /// # Ok(()) }
    /// ```
    pub async fn cancel_plan(&self, plan_id: &str) -> Result<PlanStatusResponse> {
        let path = format!("/v1/plans/{}", segment(plan_id));
        self.json(self.request(Method::DELETE, &path), "the plan status").await
    }

    /// Polls `GET /v1/plans/{id}` every `every` until the computation ended (ready, active, done, failed or
    /// cancelled) and answers that status; [`ClientError::Timeout`] when `timeout` passes first. For live
    /// progress, follow [`Client::events`] instead.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use std::time::Duration;
    /// let done = client.wait_plan("p-1", Duration::from_millis(200), Duration::from_secs(60)).await?;
    /// println!("{}", done.status.as_str());
    /// # Ok(()) }
    /// ```
    pub async fn wait_plan(&self, plan_id: &str, every: Duration, timeout: Duration) -> Result<PlanStatusResponse> {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            let status = self.plan(plan_id).await?;
            if status.status.is_final() {
                return Ok(status);
            }
            if tokio::time::Instant::now() + every > deadline {
                return Err(ClientError::Timeout(format!(
                    "plan {plan_id} still {} after {timeout:?}",
                    status.status.as_str()
                )));
            }
            tokio::time::sleep(every).await;
        }
    }
}
