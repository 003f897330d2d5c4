//! # shift-client
//!
//! An async client of SHIFT's HTTP API (DESIGN §5.3) and helpers for robots on its Zenoh fabric (§5.4). Wire
//! types are `shift-proto`'s, re-exported as [`proto`]; nothing is redeclared here.
//!
//! - [`Client`]: sites and maps, plans (create, status, listing, path, speed profile, cancel, wait), typed
//!   server-sent events ([`Client::events`]), robots and assignment, missions for a fleet (create, status,
//!   assign, replan, cancel, their events as [`MissionEvents`]) and a site's measured coverage. Every call
//!   returns [`Result`]`<_, `[`ClientError`]`>`; an error answer carries the API's `{"error": {code,
//!   message}}` and the HTTP status.
//! - [`robot`]: [`robot::FollowedPlan`] keeps a plan current under versioned corrections; with the `robot`
//!   feature (default) [`robot::RobotLink`] receives plans and corrections over Zenoh and fetches the plan
//!   when a version gap shows.
//! - The `shiftctl` binary (feature `cli`, default) is an operator's command line over the same calls.
//!
//! ```no_run
//! # async fn run() -> shift_client::Result<()> {
//! use shift_client::proto::{PlanRequest, RobotSpec};
//! let client = shift_client::Client::new("http://127.0.0.1:7878")?;
//! let accepted = client
//!     .create_plan(&PlanRequest {
//!         site: "demo".into(),
//!         start: [0.5, 0.5],
//!         robot: RobotSpec::new(0.15, 0.3),
//!         attribute: None,
//!         region: None,
//!         options: None,
//!         objective: None,
//!         snap_start_m: None,
//!     })
//!     .await?;
//! let mut events = client.events(&accepted.plan_id).await?;
//! while let Some(event) = events.next_event().await? {
//!     println!("{}", event.name());
//!     if matches!(&event, shift_client::proto::PlanEvent::Status(s) if s.status.is_final()) {
//!         break;
//!     }
//! }
//! let doc = client.path(&accepted.plan_id).await?;
//! println!("{} waypoints, {:.0} s", doc.waypoints.len(), doc.metrics.duration_s);
//! # Ok(()) }
//! ```

mod client;
mod error;
mod fields;
mod missions;
mod plans;
pub mod robot;
mod robots;
mod sites;
pub mod sse;

pub use client::{Client, DEFAULT_BASE_URL};
pub use error::{ClientError, Result};
pub use shift_proto as proto;
pub use sse::{MissionEvents, PlanEvents};
