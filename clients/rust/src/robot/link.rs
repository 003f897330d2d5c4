//! A robot's Zenoh side: its plan and corrections subscriptions, and the plan query that closes a version gap.

use std::time::Duration;

use shift_proto::keys::KeySpace;
use shift_proto::{CorrectionDoc, PlanDocument, PlanStatusResponse};
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::Subscriber;
use zenoh::sample::Sample;

use super::{Applied, FollowedPlan};
use crate::error::{ClientError, Result};

fn zerr(e: impl std::fmt::Display) -> ClientError {
    ClientError::Zenoh(e.to_string())
}

/// A Zenoh config for a loopback-style peer: peer mode, connected to `endpoint` only (e.g.
/// `tcp/127.0.0.1:7447`), listening nowhere, no multicast or gossip scouting.
///
/// ```
/// let config = shift_client::robot::peer_config("tcp/127.0.0.1:7447")?;
/// # Ok::<(), shift_client::ClientError>(())
/// ```
pub fn peer_config(endpoint: &str) -> Result<zenoh::Config> {
    if endpoint.is_empty() || endpoint.contains(['"', '\\']) {
        return Err(ClientError::InvalidInput(format!("zenoh endpoint {endpoint:?}")));
    }
    let mut c = zenoh::Config::default();
    for (key, value) in [
        ("mode", "\"peer\"".to_owned()),
        ("listen/endpoints", "[]".to_owned()),
        ("connect/endpoints", format!("[\"{endpoint}\"]")),
        ("scouting/multicast/enabled", "false".to_owned()),
        ("scouting/gossip/enabled", "false".to_owned()),
    ] {
        c.insert_json5(key, &value)
            .map_err(|e| ClientError::InvalidInput(format!("zenoh config {key}: {e}")))?;
    }
    Ok(c)
}

/// A message the server sent to a robot.
#[derive(Debug, Clone, PartialEq)]
pub enum RobotMessage {
    /// A whole plan (on assignment, or a fetched one).
    Plan(PlanDocument),
    /// A correction of the plan.
    Correction(CorrectionDoc),
    /// The status of a plan assigned to this robot (its watch health says e.g. `blocked`).
    Status(Box<PlanStatusResponse>),
}

/// One robot's link to the fleet: subscribed to `{prefix}/{fleet}/robots/{robot}/plan` and `…/corrections`,
/// and to `{prefix}/{fleet}/plans/*/status` for the statuses of plans assigned to it (the server publishes
/// statuses per plan; those of other robots' plans are dropped here).
///
/// ```no_run
/// # async fn run() -> shift_client::Result<()> {
/// use shift_client::proto::keys::KeySpace;
/// use shift_client::robot::{FollowedPlan, RobotLink};
/// let link = RobotLink::connect("tcp/127.0.0.1:7447", KeySpace::default(), "r1").await?;
/// let mut followed = FollowedPlan::default();
/// // A robot that (re)starts asks for its current plan first.
/// if let Some(doc) = link.fetch_plan(std::time::Duration::from_secs(2)).await? {
///     followed.on_plan(doc);
/// }
/// loop {
///     let message = link.recv().await?;
///     let applied = link.follow(&mut followed, message).await?;
///     println!("{applied:?}: now at version {:?}", followed.version());
/// }
/// # }
/// ```
pub struct RobotLink {
    session: zenoh::Session,
    keys: KeySpace,
    robot: String,
    plans: Subscriber<FifoChannelHandler<Sample>>,
    corrections: Subscriber<FifoChannelHandler<Sample>>,
    statuses: Subscriber<FifoChannelHandler<Sample>>,
    /// How long a gap's plan query waits for the answer.
    pub fetch_timeout: Duration,
}

impl std::fmt::Debug for RobotLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotLink")
            .field("keys", &self.keys)
            .field("robot", &self.robot)
            .finish_non_exhaustive()
    }
}

impl RobotLink {
    /// Opens a peer session to `endpoint` ([`peer_config`]) and subscribes as `robot`.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// use shift_client::proto::keys::KeySpace;
    /// let link = shift_client::robot::RobotLink::connect("tcp/127.0.0.1:7447", KeySpace::default(), "r1").await?;
    /// # Ok(()) }
    /// ```
    pub async fn connect(endpoint: &str, keys: KeySpace, robot: &str) -> Result<Self> {
        let session = zenoh::open(peer_config(endpoint)?).await.map_err(zerr)?;
        Self::on_session(session, keys, robot).await
    }

    /// Subscribes as `robot` on a session the caller opened (and may use for odometry and clouds too).
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// use shift_client::proto::keys::KeySpace;
    /// let session = zenoh::open(shift_client::robot::peer_config("tcp/127.0.0.1:7447")?)
    ///     .await
    ///     .map_err(|e| shift_client::ClientError::Zenoh(e.to_string()))?;
    /// let link = shift_client::robot::RobotLink::on_session(session, KeySpace::default(), "r1").await?;
    /// # Ok(()) }
    /// ```
    pub async fn on_session(session: zenoh::Session, keys: KeySpace, robot: &str) -> Result<Self> {
        keys.validate().map_err(|e| ClientError::InvalidInput(e.to_string()))?;
        let plan_key = keys.plan(robot).map_err(|e| ClientError::InvalidInput(e.to_string()))?;
        let corr_key = keys
            .corrections(robot)
            .map_err(|e| ClientError::InvalidInput(e.to_string()))?;
        let plans = session.declare_subscriber(plan_key).await.map_err(zerr)?;
        let corrections = session.declare_subscriber(corr_key).await.map_err(zerr)?;
        let statuses = session.declare_subscriber(keys.all_plan_status()).await.map_err(zerr)?;
        Ok(Self {
            session,
            keys,
            robot: robot.to_owned(),
            plans,
            corrections,
            statuses,
            fetch_timeout: Duration::from_secs(5),
        })
    }

    /// The session (to publish odometry, clouds, a liveliness token on it).
    pub fn session(&self) -> &zenoh::Session {
        &self.session
    }

    /// The robot's name.
    pub fn robot(&self) -> &str {
        &self.robot
    }

    /// The next plan or correction sent to this robot. A payload that is not the JSON it should be is an
    /// error ([`ClientError::Decode`]); the link stays usable.
    ///
    /// ```no_run
    /// # async fn run(link: shift_client::robot::RobotLink) -> shift_client::Result<()> {
    /// use shift_client::robot::RobotMessage;
    /// match link.recv().await? {
    ///     RobotMessage::Plan(doc) => println!("plan {} v{}", doc.plan_id, doc.version),
    ///     RobotMessage::Correction(c) => println!("correction to v{}", c.version),
    ///     RobotMessage::Status(s) => println!("plan {} is {:?}", s.plan_id, s.watch),
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn recv(&self) -> Result<RobotMessage> {
        loop {
            tokio::select! {
                s = self.plans.recv_async() => {
                    let sample = s.map_err(zerr)?;
                    return decode(&sample, "a plan document").map(RobotMessage::Plan);
                }
                s = self.corrections.recv_async() => {
                    let sample = s.map_err(zerr)?;
                    return decode(&sample, "a correction").map(RobotMessage::Correction);
                }
                s = self.statuses.recv_async() => {
                    let sample = s.map_err(zerr)?;
                    let status: PlanStatusResponse = decode(&sample, "a plan status")?;
                    if status.robot.as_deref() == Some(self.robot.as_str()) {
                        return Ok(RobotMessage::Status(Box::new(status)));
                    }
                }
            }
        }
    }

    /// The robot's current plan from the daemon's plan queryable (`None` when no plan is assigned to it or
    /// nobody answered within `timeout`).
    ///
    /// ```no_run
    /// # async fn run(link: shift_client::robot::RobotLink) -> shift_client::Result<()> {
    /// if let Some(doc) = link.fetch_plan(std::time::Duration::from_secs(2)).await? {
    ///     println!("plan {} at version {}", doc.plan_id, doc.version);
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn fetch_plan(&self, timeout: Duration) -> Result<Option<PlanDocument>> {
        let key = self
            .keys
            .plan(&self.robot)
            .map_err(|e| ClientError::InvalidInput(e.to_string()))?;
        let replies = self.session.get(key).timeout(timeout).await.map_err(zerr)?;
        let mut newest: Option<PlanDocument> = None;
        while let Ok(reply) = replies.recv_async().await {
            let Ok(sample) = reply.result() else { continue };
            let doc: PlanDocument = decode(sample, "a plan document")?;
            if newest.as_ref().is_none_or(|n| doc.version > n.version) {
                newest = Some(doc);
            }
        }
        Ok(newest)
    }

    /// A plan's current status from the daemon's status queryable (`None` when nobody answered within
    /// `timeout`). Statuses are published when they change; a robot that joins (or rejoins) asks, so it learns
    /// a watch health such as `blocked` that changed before it was listening.
    ///
    /// ```no_run
    /// # async fn run(link: shift_client::robot::RobotLink) -> shift_client::Result<()> {
    /// if let Some(status) = link.fetch_status("p-1", std::time::Duration::from_secs(2)).await? {
    ///     println!("{} is {:?}, watch {:?}", status.plan_id, status.status, status.watch);
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn fetch_status(&self, plan_id: &str, timeout: Duration) -> Result<Option<PlanStatusResponse>> {
        let key = self
            .keys
            .plan_status(plan_id)
            .map_err(|e| ClientError::InvalidInput(e.to_string()))?;
        let replies = self.session.get(key).timeout(timeout).await.map_err(zerr)?;
        let mut newest: Option<PlanStatusResponse> = None;
        while let Ok(reply) = replies.recv_async().await {
            let Ok(sample) = reply.result() else { continue };
            let status: PlanStatusResponse = decode(sample, "a plan status")?;
            if newest.as_ref().is_none_or(|n| status.version >= n.version) {
                newest = Some(status);
            }
        }
        Ok(newest)
    }

    /// Feeds `message` to `followed`; on a version gap fetches the plan ([`RobotLink::fetch_plan`] with
    /// [`RobotLink::fetch_timeout`]) and feeds that too. Answers what finally happened (still a gap when
    /// the fetch found nothing newer).
    ///
    /// ```no_run
    /// # async fn run(link: shift_client::robot::RobotLink) -> shift_client::Result<()> {
    /// let mut followed = shift_client::robot::FollowedPlan::default();
    /// let applied = link.follow(&mut followed, link.recv().await?).await?;
    /// # Ok(()) }
    /// ```
    pub async fn follow(&self, followed: &mut FollowedPlan, message: RobotMessage) -> Result<Applied> {
        let applied = match message {
            RobotMessage::Plan(doc) => followed.on_plan(doc),
            RobotMessage::Correction(c) => match followed.on_correction(c) {
                Ok(a) => a,
                // A correction that does not fit its own base: the plan is the truth.
                Err(_) => Applied::Gap {
                    plan_id: followed.doc().map(|d| d.plan_id.clone()).unwrap_or_default(),
                    base: followed.version().unwrap_or(0),
                    have: followed.version(),
                },
            },
            RobotMessage::Status(status) => followed.on_status(&status),
        };
        if !matches!(applied, Applied::Gap { .. }) {
            return Ok(applied);
        }
        match self.fetch_plan(self.fetch_timeout).await? {
            Some(doc) => match followed.on_plan(doc) {
                Applied::Stale => Ok(applied),
                fetched => Ok(fetched),
            },
            None => Ok(applied),
        }
    }
}

fn decode<T: serde::de::DeserializeOwned>(sample: &Sample, what: &str) -> Result<T> {
    serde_json::from_slice(&sample.payload().to_bytes()).map_err(|source| ClientError::Decode {
        what: what.to_owned(),
        source,
    })
}
