//! The daemon's compute threads: a fixed pool for plan jobs and one for path checks, both off the async
//! runtime.
//!
//! Fixed, long-lived threads rather than tokio's blocking pool: that pool starts a thread whenever all of its
//! threads are busy and lets it idle for ten seconds before it ends, so a daemon that plans every few seconds
//! keeps cycling threads, and with glibc each new thread may be handed a fresh malloc arena whose freed
//! planner buffers are never returned. The soak (issue 22) showed RSS stepping up with such bursts. Here the
//! plan pool has exactly `[jobs] workers` threads (the engine never runs more jobs at once) and the check pool
//! one per core (the engine keeps at most one check per robot in flight; checks take milliseconds, and never
//! queue behind a plan that takes seconds).
//!
use std::sync::Arc;

/// The plan and check pools.
#[derive(Debug, Clone)]
pub struct Pools {
    /// Plan jobs (`shift-plan-N` threads).
    pub plans: Arc<rayon::ThreadPool>,
    /// Path checks (`shift-check-N` threads).
    pub checks: Arc<rayon::ThreadPool>,
}

impl Pools {
    /// `plan_threads` plan workers (at least one) and one check worker per core.
    pub fn new(plan_threads: usize) -> std::io::Result<Self> {
        let cores = std::thread::available_parallelism().map_or(2, usize::from);
        Ok(Self {
            plans: Arc::new(pool("shift-plan", plan_threads.max(1))?),
            checks: Arc::new(pool("shift-check", cores)?),
        })
    }
}

fn pool(name: &'static str, threads: usize) -> std::io::Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(move |i| format!("{name}-{i}"))
        .build()
        .map_err(std::io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pools_run_work_on_named_threads() {
        let pools = Pools::new(2).expect("pools");
        assert_eq!(pools.plans.current_num_threads(), 2);
        let (tx, rx) = std::sync::mpsc::channel();
        pools.plans.spawn(move || {
            let name = std::thread::current().name().map(str::to_owned);
            tx.send(name).expect("send");
        });
        let name = rx.recv().expect("ran").expect("named");
        assert!(name.starts_with("shift-plan-"), "{name}");
    }
}
