//! The process allocator seen from inside (issue 22): jemalloc's purging thread and its figures as a gauge.
//! The binary installs jemalloc as its global allocator (`main.rs`); these calls are made by `shiftd serve`.

/// Turns on jemalloc's background purging thread. Without it, pages freed in an arena go back to the system only
/// when that arena is next used after their decay time, so a daemon that went quiet after a burst (a replayed
/// log, a map upload) may keep them for as long as it stays quiet. 4 050 real laser scans replayed, then 20 s
/// idle (README, "Memory on a real laser log"): jemalloc resident 36.1 and 48.4 MiB in two runs without the
/// thread, 34.6 and 33.2 MiB with it, for 27.4 MiB allocated each time.
pub fn purge_idle_arenas() {
    if let Err(e) = tikv_jemalloc_ctl::background_thread::write(true) {
        tracing::warn!("jemalloc's background thread is off ({e}): freed pages wait for their arena's next use");
    }
}

/// How often `shift_allocator_bytes` is refreshed.
const ALLOCATOR_STATS_EVERY: std::time::Duration = std::time::Duration::from_secs(2);

/// Sets `shift_allocator_bytes{stat}` from jemalloc's statistics every [`ALLOCATOR_STATS_EVERY`], on a named
/// thread (issue 22): `allocated` is what the program holds, `active` the pages those allocations occupy,
/// `resident` what jemalloc keeps in RAM (active, metadata, and freed pages not yet handed back after the decay
/// time), `mapped` and `retained` address space. RSS above `resident` is code, stacks and other allocators.
pub fn spawn_allocator_stats() {
    use tikv_jemalloc_ctl::{epoch, stats};
    let spawned = std::thread::Builder::new().name("alloc-stats".into()).spawn(|| {
        loop {
            if epoch::advance().is_ok() {
                let figures = [
                    ("allocated", stats::allocated::read()),
                    ("active", stats::active::read()),
                    ("metadata", stats::metadata::read()),
                    ("resident", stats::resident::read()),
                    ("mapped", stats::mapped::read()),
                    ("retained", stats::retained::read()),
                ];
                for (stat, value) in figures {
                    if let Ok(bytes) = value {
                        metrics::gauge!("shift_allocator_bytes", "stat" => stat).set(bytes as f64);
                    }
                }
            }
            std::thread::sleep(ALLOCATOR_STATS_EVERY);
        }
    });
    if let Err(e) = spawned {
        tracing::warn!("no allocator statistics ({e})");
    }
}
