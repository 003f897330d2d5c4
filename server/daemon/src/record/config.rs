//! `[record]`: MCAP recording of everything the daemon ingests and decides (`shiftd serve --record DIR`).

use std::path::PathBuf;

use serde::Deserialize;

/// `[record]` of the config file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecordConfig {
    /// Folder the MCAP files go to; empty = no recording. `--record DIR` sets it.
    pub dir: PathBuf,
    /// A file is finished and the next one started once it reaches this many bytes (on disk, plus what the
    /// open chunk holds uncompressed).
    pub max_file_bytes: u64,
    /// … or once it has been open this many seconds.
    pub max_file_s: u64,
    /// Seconds between occupancy grids (`foxglove.Grid`) of each site; 0 = none.
    pub grid_interval_s: u64,
    /// Messages waiting for the writer thread; when full, new ones are dropped and counted.
    pub queue_messages: usize,
    /// Bytes of ingested payloads (clouds, odometry) waiting for the writer; above it they are dropped and
    /// counted (engine events and decisions are only bounded by `queue_messages`).
    pub queue_bytes: usize,
    /// Uncompressed bytes per zstd chunk.
    pub chunk_bytes: u64,
}

impl Default for RecordConfig {
    fn default() -> Self {
        Self {
            dir: PathBuf::new(),
            max_file_bytes: 512 << 20,
            max_file_s: 3600,
            grid_interval_s: 10,
            queue_messages: 8192,
            queue_bytes: 64 << 20,
            chunk_bytes: 1 << 20,
        }
    }
}

impl RecordConfig {
    /// True when a folder is set.
    pub fn enabled(&self) -> bool {
        !self.dir.as_os_str().is_empty()
    }
}
