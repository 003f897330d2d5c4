//! shiftd: the SHIFT daemon and its command-line front end.
//!
//! `shiftd serve` (the HTTP API over the engine, the store and the plan job pool: [`run`]), `shiftd plan` (one
//! plan from a scene or a map) and `shiftd eval` (every strategy and baseline on a folder of scenes). Adapters
//! only: HTTP, Zenoh, the store, the job and check pools, the recorder, file I/O and rendering, each talking to
//! the engine loop through its handle (`engine_loop::handle`). The fleet's decisions are in `shift-engine`, the
//! algorithms in `shift-planner`.

pub mod allocator;
pub mod clock;
pub mod cloud;
pub mod config;
pub mod demo;
pub mod engine_loop;
pub mod error;
pub mod eval;
pub mod eval_fleet;
pub mod fleet;
pub mod http;
pub mod jobs;
pub mod pools;
pub mod record;
pub mod render;
pub mod render_fleet;
pub mod render_terrain;
pub mod replay;
pub mod scene_io;
pub mod server;
pub mod store;
pub mod terrain_cli;
pub mod views;
pub mod watch;

pub use config::Config;
pub use server::{run, run_with_clock};
