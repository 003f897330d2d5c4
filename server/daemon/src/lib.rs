//! shiftd: the SHIFT daemon and its command-line front end.
//!
//! `shiftd serve` (the HTTP API over the engine, the store and the plan job pool: [`run`]), `shiftd plan` (one
//! plan from a scene or a map) and `shiftd eval` (every strategy and baseline on a folder of scenes). The file I/O, the wire conversion and the rendering live here; the algorithms are in
//! `shift-planner`.

pub mod brain;
pub mod config;
pub mod eval;
pub mod fleet;
pub mod http;
pub mod jobs;
pub mod plan_doc;
pub mod record;
pub mod render;
pub mod replay;
pub mod scene_io;
pub mod server;
pub mod store;
pub mod views;
pub mod watch;

pub use config::Config;
pub use server::run;
