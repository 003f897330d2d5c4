//! Path checks on the check pool ([`crate::pools`]): the engine asks for a check of one robot's path
//! ([`shift_engine::CheckJob`]); this runs the engine's pure check function with the site's live obstacle
//! tree under its read lock (the ingest thread, the only writer, waits at most one check), times it, and
//! reports back. The engine keeps at most one check per robot in flight, so this never queues work itself.

use std::panic::AssertUnwindSafe;
use std::sync::Arc;
use std::time::Instant;

use shift_engine::{CheckJob, CheckOutcome, Event, LiveMaps, run_check};

use crate::engine_loop::handle::{EngineHandle, Msg};

/// Spawns checks.
#[derive(Debug)]
pub struct CheckRunner {
    pool: Arc<rayon::ThreadPool>,
    to_engine: EngineHandle,
    live: Arc<LiveMaps>,
}

impl CheckRunner {
    /// A runner on `pool` reading `live` and reporting to the engine thread.
    pub fn new(pool: Arc<rayon::ThreadPool>, to_engine: EngineHandle, live: Arc<LiveMaps>) -> Self {
        Self { pool, to_engine, live }
    }

    /// Starts a check.
    pub fn start(&self, job: CheckJob) {
        let to_engine = self.to_engine.clone();
        let live = self.live.clone();
        self.pool.spawn(move || {
            let t = Instant::now();
            let site = live.get(&job.site);
            let result = std::panic::catch_unwind(AssertUnwindSafe(|| match &site {
                Some(s) => match s.map.read() {
                    Ok(map) => run_check(&job, Some(map.points())),
                    Err(_) => CheckOutcome::Failed("live map lock poisoned".into()),
                },
                None => run_check(&job, None),
            }));
            let compute_us = t.elapsed().as_micros() as u64;
            metrics::histogram!("shift_check_seconds").record(compute_us as f64 / 1e6);
            let outcome = result.unwrap_or_else(|_| {
                tracing::error!(robot = job.robot, plan_id = job.plan_id, "path check panicked");
                CheckOutcome::Failed("internal check error (logged)".into())
            });
            match &outcome {
                CheckOutcome::Correct(p) => {
                    // A proposal: the engine decides whether it becomes a version (`shift_corrections_total`);
                    // one held at a blockage is proposed again at every check.
                    metrics::counter!("shift_check_proposals_total", "reason" => p.reason.as_str()).increment(1);
                    tracing::debug!(
                        robot = job.robot,
                        plan_id = job.plan_id,
                        reason = p.reason.as_str(),
                        from = p.from,
                        to = p.to,
                        iterations = p.iterations,
                        trigger = ?job.trigger,
                        ahead_from = job.ahead_from,
                        version = job.doc.version,
                        compute_us,
                        "path check proposes a correction"
                    );
                }
                CheckOutcome::Failed(why) => {
                    // Persistent (e.g. a robot standing inside an obstacle): counted, logged at debug level
                    // so a check every few hundred milliseconds does not flood the log.
                    metrics::counter!("shift_check_failed_total").increment(1);
                    tracing::debug!(robot = job.robot, "path check failed: {why}");
                }
                CheckOutcome::Clear => tracing::debug!(
                    robot = job.robot,
                    trigger = ?job.trigger,
                    ahead_from = job.ahead_from,
                    x = job.pose.x,
                    y = job.pose.y,
                    compute_us,
                    "path check: clear"
                ),
            }
            // The engine must learn of every end (it keeps one check per robot in flight).
            let _ = to_engine.blocking_tell(Msg::event(Event::CheckFinished {
                robot: job.robot,
                plan_id: job.plan_id,
                base_version: job.doc.version,
                outcome,
                compute_us,
            }));
        });
    }
}
