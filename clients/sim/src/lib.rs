//! shift-sim: a simulated fleet for SHIFT. Differential-drive robots, each its own Zenoh participant, drive
//! the plans the daemon assigns them in a hidden world (the site's map plus obstacles the daemon does not
//! know, plus movers), publish odometry and laser scans ray-cast against that world, follow corrections by
//! version, stop for what their own laser sees in their way, and measure what they really covered.
//!
//! Sans-IO core: [`world`], [`drive`], [`pursuit`], [`lidar`], [`robot`], [`sim`], [`measure`], [`sight`]; I/O shell:
//! [`net`] (Zenoh), [`plans`] (HTTP), [`clock`], [`report`], [`run`].

pub mod clock;
pub mod drive;
pub mod error;
pub mod lidar;
pub mod measure;
pub mod net;
pub mod plans;
pub mod pursuit;
pub mod report;
pub mod robot;
pub mod run;
pub mod sight;
pub mod sim;
pub mod spread;
pub mod world;

pub use error::SimError;
pub use report::Report;
pub use run::{RunOptions, run};
