//! What the engine loop does when the store cannot write (disk full, read-only data dir, an I/O error).
//!
//! - A client's request ([`shift_engine::Event::is_request`]) is handled on a snapshot of the engine; if its
//!   writes do not commit, the snapshot is put back and the request is refused (507 when full, 503 when
//!   read-only): nothing of it is stored, served or published. While the store is failing, requests are
//!   refused before the engine sees them.
//! - Facts the fleet lived through (a job finished, a robot drove, a check found an obstacle) stand in the
//!   engine. Their durable part — the writes and whatever announces them: the views of stored records,
//!   published corrections and plans, status events — waits here, in order, and is carried out when the store
//!   writes again. Nothing is served or published before it is stored, so a correction a robot got always
//!   exists in the store, and nothing half-written is served after the space comes back.
//! - At most once a second, the next event first probes the store ([`Store::recover`]: reopen, a small write)
//!   and, when that works, commits what waits.

use std::collections::VecDeque;

use shift_engine::Command;
use shift_proto::PlanEvent;

use crate::store::fault::{FaultKind, StoreError};
use crate::store::{Store, Write};

/// How long after a failed probe the next one may run, milliseconds.
pub const PROBE_EVERY_MS: u64 = 1_000;

/// Facts' durable commands kept while the store fails, in events; later facts' durable parts are dropped (and
/// counted) beyond it.
pub const MAX_DEFERRED: usize = 10_000;

/// The store's health as the loop sees it, and the facts waiting for it.
#[derive(Debug, Default)]
pub struct Durability {
    fault: Option<StoreError>,
    last_probe_ms: u64,
    deferred: VecDeque<Vec<Command>>,
}

impl Durability {
    /// Why the store does not write now, if it does not.
    pub fn fault(&self) -> Option<&StoreError> {
        self.fault.as_ref()
    }

    /// Facts' events waiting for the store.
    pub fn deferred(&self) -> usize {
        self.deferred.len()
    }

    /// A write failed.
    pub fn failed(&mut self, e: &StoreError, now_ms: u64) {
        metrics::counter!("shift_store_failures_total", "kind" => e.kind.as_str()).increment(1);
        if self.fault.is_none() {
            tracing::error!(
                kind = e.kind.as_str(),
                "store write failed, writes are refused until it recovers: {e}"
            );
        }
        self.fault = Some(e.clone());
        self.last_probe_ms = now_ms;
    }

    /// Whether a fact's commands must wait: the store failed, or earlier facts wait (order is kept).
    pub fn must_wait(&self) -> bool {
        self.fault.is_some() || !self.deferred.is_empty()
    }

    /// Keeps a fact's durable commands for later. A fault of the data itself (not of the disk) will not go
    /// away by waiting: such a batch is dropped with an error in the log.
    pub fn defer(&mut self, later: Vec<Command>) {
        if later.is_empty() {
            return;
        }
        if self.fault.as_ref().is_some_and(|f| f.kind == FaultKind::Data) && self.deferred.is_empty() {
            tracing::error!("a fact's writes were dropped: the store cannot hold their data");
            metrics::counter!("shift_store_deferred_dropped_total").increment(1);
            return;
        }
        if self.deferred.len() >= MAX_DEFERRED {
            metrics::counter!("shift_store_deferred_dropped_total").increment(1);
            tracing::warn!(
                waiting = self.deferred.len(),
                "store still failing: a fact's writes were dropped"
            );
            return;
        }
        self.deferred.push_back(later);
    }

    /// When the store failed and the last probe is a second old: probes it and commits what waits, in order,
    /// handing each committed batch to `execute`. Returns true when the store writes again and nothing waits.
    pub fn retry(&mut self, store: &Store, now_ms: u64, mut execute: impl FnMut(Vec<Command>)) -> bool {
        if self.fault.is_none() {
            return self.deferred.is_empty();
        }
        if now_ms.saturating_sub(self.last_probe_ms) < PROBE_EVERY_MS {
            return false;
        }
        self.last_probe_ms = now_ms;
        if let Err(e) = store.recover(now_ms) {
            tracing::debug!("store probe failed: {e}");
            self.fault = Some(e);
            return false;
        }
        while let Some(batch) = self.deferred.front() {
            let writes: Vec<Write<'_>> = batch.iter().filter_map(Write::of).collect();
            if !writes.is_empty()
                && let Err(e) = store.commit(&writes)
            {
                self.failed(&e, now_ms);
                return false;
            }
            if let Some(batch) = self.deferred.pop_front() {
                execute(batch);
            }
        }
        tracing::info!("store writes again; everything that waited is committed");
        self.fault = None;
        true
    }
}

/// Splits a fact's commands into what runs now and what must wait for the store: writes, and what announces
/// stored state (the views of stored records, published corrections and plans, status and correction events).
pub fn split_durable(cmds: Vec<Command>) -> (Vec<Command>, Vec<Command>) {
    cmds.into_iter().partition(|c| !is_durable(c))
}

fn is_durable(cmd: &Command) -> bool {
    match cmd {
        Command::StoreSite(_)
        | Command::StorePlan(_)
        | Command::StoreResult { .. }
        | Command::StoreCorrection { .. }
        | Command::ForgetPlan { .. }
        | Command::PublishCorrection(_)
        | Command::PublishPlan { .. } => true,
        Command::Publish(event) => matches!(event, PlanEvent::Status(_) | PlanEvent::Correction(_)),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_what_announces_them_wait_the_rest_runs_now() {
        let cmds = vec![
            Command::CancelJob { plan_id: "p-1".into() },
            Command::ForgetPlan { plan_id: "p-0".into() },
            Command::Publish(PlanEvent::Progress {
                plan_id: "p-1".into(),
                progress: 0.5,
            }),
            Command::FeedSite {
                robot: "r1".into(),
                site: None,
            },
        ];
        let (now, later) = split_durable(cmds);
        assert_eq!(now.len(), 3);
        assert!(matches!(later.as_slice(), [Command::ForgetPlan { .. }]));
    }

    #[test]
    fn a_failure_waits_a_second_before_the_next_probe() {
        let dir = tempfile::tempdir().expect("tempdir");
        let store = Store::open(dir.path()).expect("open");
        let mut d = Durability::default();
        d.failed(&StoreError::new(FaultKind::Full, "full"), 10_000);
        d.defer(vec![Command::CancelJob { plan_id: "p".into() }]);
        assert!(d.must_wait());
        let mut ran = 0;
        assert!(!d.retry(&store, 10_500, |_| ran += 1), "too soon to probe");
        assert_eq!(ran, 0);
        assert!(d.retry(&store, 11_000, |_| ran += 1), "the store writes again");
        assert_eq!((ran, d.deferred(), d.fault().is_none()), (1, 0, true));
    }
}
