//! What the daemon puts on Zenoh: plans (JSON on the plan key, nav_msgs/Path CDR on the plan_path key),
//! corrections (JSON on the corrections key) and plan status (JSON on `…/plans/{plan}/status`, DESIGN §5.4).
//!
//! One task puts them in the order the engine decided them (queued → planning → ready → active reaches a
//! subscriber in that order; a correction never overtakes its plan). The engine loop hands messages over with
//! `try_send`, never blocking; a full queue drops the message and counts it (`shift_publish_dropped_total`): a
//! robot that missed a plan or correction fetches the current plan from the queryable, a status reader gets
//! the current status from the status queryable.

use std::sync::Arc;

use shift_proto::keys::KeySpace;
use shift_proto::ros::path::encode_plan_path;
use shift_proto::ros::{Header, Time};
use shift_proto::{CorrectionDoc, PlanDocument, PlanStatusResponse};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use zenoh::bytes::Encoding;
use zenoh::qos::CongestionControl;

/// Messages waiting to be put.
const QUEUE: usize = 4096;

/// One message out.
#[derive(Debug)]
enum Outgoing {
    Plan { robot: String, doc: Arc<PlanDocument> },
    Correction(Arc<CorrectionDoc>),
    Status(Box<PlanStatusResponse>),
}

impl Outgoing {
    fn label(&self) -> &'static str {
        match self {
            Self::Plan { .. } => "plan",
            Self::Correction(_) => "correction",
            Self::Status(_) => "status",
        }
    }
}

/// Hands messages to the publishing task; cheap to clone, usable from any thread.
#[derive(Debug, Clone)]
pub struct Publisher {
    tx: mpsc::Sender<Outgoing>,
}

impl Publisher {
    /// Starts the publishing task on the current runtime.
    pub fn start(session: zenoh::Session, keys: Arc<KeySpace>) -> (Self, JoinHandle<()>) {
        let (tx, mut rx) = mpsc::channel::<Outgoing>(QUEUE);
        let task = tokio::spawn(async move {
            while let Some(msg) = rx.recv().await {
                put(&session, &keys, msg).await;
            }
        });
        (Self { tx }, task)
    }

    fn send(&self, msg: Outgoing) {
        let label = msg.label();
        if self.tx.try_send(msg).is_err() {
            metrics::counter!("shift_publish_dropped_total", "kind" => label).increment(1);
            tracing::warn!(kind = label, "zenoh publishing cannot keep up: message dropped");
        }
    }

    /// Sends `doc` to `robot` (a robot that misses it fetches it from the plan queryable).
    pub fn plan(&self, robot: &str, doc: Arc<PlanDocument>) {
        self.send(Outgoing::Plan {
            robot: robot.to_owned(),
            doc,
        });
    }

    /// Sends a correction to its robot. A robot that misses it sees a version gap at the next one and fetches
    /// the current plan from the queryable.
    pub fn correction(&self, correction: Arc<CorrectionDoc>) {
        self.send(Outgoing::Correction(correction));
    }

    /// Publishes a plan's status.
    pub fn status(&self, status: PlanStatusResponse) {
        self.send(Outgoing::Status(Box::new(status)));
    }
}

async fn put(session: &zenoh::Session, keys: &KeySpace, msg: Outgoing) {
    match msg {
        Outgoing::Plan { robot, doc } => {
            let (Ok(plan_key), Ok(path_key)) = (keys.plan(&robot), keys.plan_path(&robot)) else {
                tracing::warn!(robot, "no valid plan key for this robot name");
                return;
            };
            let json = match serde_json::to_vec(&*doc) {
                Ok(j) => j,
                Err(e) => return tracing::error!("plan JSON: {e}"),
            };
            // Block, not drop, when the link is congested: a plan is worth the wait (this task waits, never the
            // engine).
            let put = session.put(&plan_key, json).encoding(Encoding::APPLICATION_JSON);
            if let Err(e) = put.congestion_control(CongestionControl::Block).await {
                tracing::warn!(robot, "publishing the plan: {e}");
            }
            let header = Header {
                stamp: Time { sec: 0, nanosec: 0 },
                frame_id: doc.frame.clone(),
            };
            let cdr = encode_plan_path(&header, &doc);
            let put = session.put(&path_key, cdr).encoding(Encoding::APPLICATION_CDR);
            if let Err(e) = put.congestion_control(CongestionControl::Block).await {
                tracing::warn!(robot, "publishing the ROS path: {e}");
            }
        }
        Outgoing::Correction(c) => {
            let Ok(key) = keys.corrections(&c.robot) else {
                return tracing::warn!(robot = c.robot, "no valid corrections key for this robot name");
            };
            match serde_json::to_vec(&*c) {
                Ok(json) => {
                    if let Err(e) = session.put(&key, json).encoding(Encoding::APPLICATION_JSON).await {
                        tracing::warn!(robot = c.robot, "publishing a correction: {e}");
                    }
                }
                Err(e) => tracing::error!("correction JSON: {e}"),
            }
        }
        Outgoing::Status(status) => {
            let Ok(key) = keys.plan_status(&status.plan_id) else {
                return tracing::warn!(plan_id = status.plan_id, "no valid status key for this plan id");
            };
            match serde_json::to_vec(&*status) {
                Ok(json) => {
                    if let Err(e) = session.put(&key, json).encoding(Encoding::APPLICATION_JSON).await {
                        tracing::warn!(plan_id = status.plan_id, "publishing the plan status: {e}");
                    }
                }
                Err(e) => tracing::error!("status JSON: {e}"),
            }
        }
    }
}
