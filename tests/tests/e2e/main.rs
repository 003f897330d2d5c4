//! The end-to-end suite: one test binary (one link of shiftd and Zenoh instead of one per file), a module per
//! area. Each starts shiftd in-process on 127.0.0.1 with Zenoh in peer mode on loopback only.

mod architecture;
mod corrections;
mod dashboard_api;
mod door;
mod fields;
mod fleet_engine;
mod fleet_ros2;
mod fleet_zenoh;
mod fuzz_feed;
mod fuzz_regressions;
mod http_api;
mod listings;
mod missions;
mod record_replay;
mod terrain;
