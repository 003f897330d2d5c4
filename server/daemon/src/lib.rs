//! shiftd: the SHIFT daemon and its command-line front end.
//!
//! Today: `shiftd plan` (one plan from a scene or a map) and `shiftd eval` (every strategy and baseline on a
//! folder of scenes). The file I/O, the wire conversion and the rendering live here; the algorithms are in
//! `shift-planner`.

pub mod eval;
pub mod plan_doc;
pub mod render;
pub mod scene_io;
