//! How adapters talk to the engine loop: its message type and a cloneable handle. A leaf: HTTP handlers, the
//! Zenoh fleet, plan jobs, path checks and the ingest import this module and nothing else of the loop.

use std::time::Instant;

use shift_engine::{EngineError, Event, PlanRecord};
use shift_proto::{MissionView, SiteSummary};
use tokio::sync::{mpsc, oneshot, watch};

/// Capacity of the engine's inbox; handlers wait for room (back-pressure), progress reports are dropped.
pub const INBOX: usize = 1024;

/// What the engine loop answers a caller.
#[derive(Debug, Default)]
pub struct Reply {
    /// Plan records changed by the event (the accepted plan first).
    pub plans: Vec<PlanRecord>,
    /// Site summaries changed by the event.
    pub sites: Vec<SiteSummary>,
    /// Mission views changed by the event (the accepted mission first).
    pub missions: Vec<MissionView>,
}

/// Why an event was not carried out.
#[derive(Debug, thiserror::Error)]
pub enum LoopError {
    /// The engine refused it.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// The store could not commit it (or is failing): nothing of it is stored, served or published.
    #[error("store: {0}")]
    Store(crate::store::fault::StoreError),
    /// The engine loop has stopped.
    #[error("the engine has stopped")]
    Stopped,
}

/// A message to the engine loop.
#[derive(Debug)]
pub enum Msg {
    /// Handle an event; answer on `reply` when given.
    Event {
        /// The event (boxed: messages stay small in the channel).
        event: Box<Event>,
        /// Where to answer.
        reply: Option<oneshot::Sender<Result<Reply, LoopError>>>,
        /// When it was sent (the loop measures how long events wait in the inbox).
        sent: Instant,
    },
    /// Stop every running job (shutdown after the grace period); they go back to the queue.
    InterruptJobs,
    /// Leave the loop.
    Stop,
}

impl Msg {
    /// An event nobody waits for.
    pub fn event(event: Event) -> Self {
        Self::Event {
            event: Box::new(event),
            reply: None,
            sent: Instant::now(),
        }
    }
}

/// A cheap, cloneable handle to the engine loop.
#[derive(Debug, Clone)]
pub struct EngineHandle {
    tx: mpsc::Sender<Msg>,
    running: watch::Receiver<usize>,
}

impl EngineHandle {
    /// A handle over the loop's inbox and its running-jobs gauge.
    pub fn new(tx: mpsc::Sender<Msg>, running: watch::Receiver<usize>) -> Self {
        Self { tx, running }
    }

    /// Sends an event and waits for the engine's answer (after the store committed).
    pub async fn call(&self, event: Event) -> Result<Reply, LoopError> {
        let (reply, rx) = oneshot::channel();
        self.tx
            .send(Msg::Event {
                event: Box::new(event),
                reply: Some(reply),
                sent: Instant::now(),
            })
            .await
            .map_err(|_| LoopError::Stopped)?;
        rx.await.map_err(|_| LoopError::Stopped)?
    }

    /// Sends an event without waiting.
    pub async fn tell(&self, msg: Msg) -> Result<(), LoopError> {
        self.tx.send(msg).await.map_err(|_| LoopError::Stopped)
    }

    /// Sends from a thread outside the async runtime (the blocking pool, the ingest thread), waiting for room.
    pub fn blocking_tell(&self, msg: Msg) -> Result<(), LoopError> {
        self.tx.blocking_send(msg).map_err(|_| LoopError::Stopped)
    }

    /// Sends without waiting for room; fails when the inbox is full (callers drop lossy data then).
    pub fn try_tell(&self, msg: Msg) -> Result<(), LoopError> {
        self.tx.try_send(msg).map_err(|_| LoopError::Stopped)
    }

    /// Watches the number of running jobs.
    pub fn running(&self) -> watch::Receiver<usize> {
        self.running.clone()
    }

    /// True while the engine loop takes events.
    pub fn is_alive(&self) -> bool {
        !self.tx.is_closed()
    }
}
