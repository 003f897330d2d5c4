//! One simulated robot, sans-IO: its body, the plan it follows (by version), the safety stop on its own scan,
//! and what it measures (driven length, stops, collisions, the swept tool area).

use shift_client::robot::{Applied, FollowedPlan, RobotMessage};
use shift_planner::geom::Point2;
use shift_planner::map::GridGeometry;
use shift_planner::metrics::coverage::CoverageRaster;

use crate::drive::{DiffDrive, Limits};
use crate::pursuit::Follower;
use crate::world::World;
use crate::world::file::RobotSpecFile;

/// The API's defaults for limits a world file leaves out.
const DEFAULT_V_MAX: f64 = 1.0;
const DEFAULT_A_MAX: f64 = 0.5;
const DEFAULT_W_MAX: f64 = 1.5;
const ALPHA_MAX: f64 = 3.0;
/// Tolerance of the safety field beyond half a map cell, metres (see [`SimRobot::path_blocked`]).
const GRAZE_M: f64 = 0.01;
/// Extra room kept ahead beyond the braking distance, metres.
const STOP_MARGIN_M: f64 = 0.05;
/// How far the body may reach into the world before it counts as a collision, metres: plans pass walls at
/// exactly the radius from non-free cell centres (DESIGN §6), and the simulated controller tracks its path to
/// within a centimetre or two, so touching at that depth is a graze (counted apart), not a collision.
pub const TRACKING_TOLERANCE_M: f64 = 0.02;
/// Spacing of the samples along the arc the safety check sweeps, metres.
const ARC_STEP_M: f64 = 0.05;

/// The point `s` metres along the arc of curvature `kappa` from `body`'s pose.
fn arc_point(body: &DiffDrive, kappa: f64, s: f64) -> (f64, f64) {
    let (c, sn) = (body.yaw.cos(), body.yaw.sin());
    if kappa.abs() < 1e-9 {
        return (body.x + s * c, body.y + s * sn);
    }
    let (dx, dy) = ((kappa * s).sin() / kappa, (1.0 - (kappa * s).cos()) / kappa);
    (body.x + c * dx - sn * dy, body.y + sn * dx + c * dy)
}

/// What a robot counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RobotStats {
    /// Distance driven, metres.
    pub driven_m: f64,
    /// Times it stopped for something its scan saw in its way.
    pub stops: u64,
    /// Times it ran into the static world (map cells or hidden obstacles) deeper than
    /// [`TRACKING_TOLERANCE_M`], counted on contact.
    pub collisions: u64,
    /// Times it touched the static world no deeper than [`TRACKING_TOLERANCE_M`].
    pub grazes: u64,
    /// Times it touched a mover.
    pub mover_contacts: u64,
    /// Corrections applied (versions advanced by corrections).
    pub corrections_applied: u64,
    /// Corrections it could not use (another plan's, a bad range).
    pub corrections_rejected: u64,
    /// Plan fetches asked for because a correction showed a version gap.
    pub gaps: u64,
    /// Simulated time at which it reached the end of its plan.
    pub finished_at_s: Option<f64>,
}

/// One robot.
#[derive(Debug, Clone)]
pub struct SimRobot {
    /// Its spec from the world file.
    pub spec: RobotSpecFile,
    /// Its body.
    pub body: DiffDrive,
    /// Its limits.
    pub limits: Limits,
    /// The plan it follows.
    pub followed: FollowedPlan,
    follower: Follower,
    /// What it counted.
    pub stats: RobotStats,
    /// The cells its tool swept.
    pub swept: CoverageRaster,
    /// Its last scan's returns in the map frame.
    seen: Vec<Point2>,
    blocked: bool,
    touching: bool,
    hitting: bool,
    touching_mover: bool,
}

impl SimRobot {
    /// A robot at its start, following nothing yet, with dynamic-tracking threshold `mu`.
    pub fn new(spec: RobotSpecFile, geometry: GridGeometry, mu: f64) -> Self {
        let [x, y, yaw] = spec.start;
        let limits = Limits {
            v_max: spec.v_max.unwrap_or(DEFAULT_V_MAX),
            a_max: spec.a_max.unwrap_or(DEFAULT_A_MAX),
            w_max: spec.w_max.unwrap_or(DEFAULT_W_MAX),
            alpha_max: ALPHA_MAX,
        };
        Self {
            swept: CoverageRaster::new(geometry, spec.tool_width / 2.0),
            spec,
            body: DiffDrive::at(x, y, yaw),
            limits,
            followed: FollowedPlan::default(),
            follower: Follower::new(mu),
            stats: RobotStats::default(),
            seen: Vec::new(),
            blocked: false,
            touching: false,
            hitting: false,
            touching_mover: false,
        }
    }

    /// Its position.
    pub fn position(&self) -> Point2 {
        Point2::new(self.body.x, self.body.y)
    }

    /// True when it has a plan and has reached its end.
    pub fn finished(&self) -> bool {
        self.followed.doc().is_some() && self.follower.is_finished()
    }

    /// Takes a plan or correction from the fleet.
    pub fn on_message(&mut self, message: RobotMessage) -> Applied {
        let before = self
            .followed
            .doc()
            .map(|d| (d.plan_id.clone(), d.version, d.waypoints.len()));
        let applied = match message {
            RobotMessage::Plan(doc) => self.followed.on_plan(doc),
            RobotMessage::Correction(c) => match self.followed.on_correction(c) {
                Ok(a) => a,
                Err(e) => {
                    tracing::warn!(robot = %self.spec.id, "correction not applied: {e}");
                    self.stats.corrections_rejected += 1;
                    return Applied::Stale;
                }
            },
        };
        let Some(doc) = self.followed.doc() else {
            return applied;
        };
        match (&applied, before) {
            (Applied::Plan { plan_id, .. }, Some((old_id, _, old_len))) if *plan_id == old_id => {
                self.follower.reacquire(old_len, &doc.waypoints, &self.body);
            }
            (Applied::Plan { .. }, _) => {
                self.follower.restart();
                self.stats.finished_at_s = None;
            }
            (Applied::Correction { version }, Some((_, old_version, old_len))) => {
                self.stats.corrections_applied += version.saturating_sub(old_version);
                if let Some(w) = doc.waypoints.get(self.follower.target()) {
                    tracing::info!(robot = %self.spec.id, version, x = self.body.x, y = self.body.y, target_x = w.x, target_y = w.y, "correction applied");
                }
                self.follower.reacquire(old_len, &doc.waypoints, &self.body);
            }
            (Applied::Gap { .. }, _) => self.stats.gaps += 1,
            _ => {}
        }
        if matches!(applied, Applied::Plan { .. } | Applied::Correction { .. }) {
            // A plan reached anew may have been finished before this change.
            if self.stats.finished_at_s.is_some() && !self.follower.is_finished() {
                self.stats.finished_at_s = None;
            }
        }
        applied
    }

    /// Keeps a scan's returns (robot-frame points) in the map frame for the safety stop.
    pub fn observe(&mut self, points: &[(f64, f64)]) {
        let (c, s) = (self.body.yaw.cos(), self.body.yaw.sin());
        self.seen = points
            .iter()
            .map(|&(x, y)| Point2::new(self.body.x + c * x - s * y, self.body.y + s * x + c * y))
            .collect();
    }

    /// True when something seen lies in the stretch the body would sweep before it could stop from `v` on the
    /// arc of curvature `kappa` it is commanded along (plus a margin). The swept radius is the body's less half
    /// a map cell: plans keep the radius from non-free cell *centres* (DESIGN §6), so a robot on its plan sees
    /// a wall's face up to half a cell closer than that, and must not stop for it.
    fn path_blocked(&self, v: f64, kappa: f64, resolution: f64) -> bool {
        let r = self.spec.radius - resolution / 2.0 - GRAZE_M;
        let reach = v * v / (2.0 * self.limits.a_max) + STOP_MARGIN_M;
        let samples = (reach / ARC_STEP_M).ceil().max(1.0) as usize;
        // A point already inside the field blocks only motion that brings the body closer to it.
        self.seen.iter().any(|p| {
            let d0 = (p.x - self.body.x).hypot(p.y - self.body.y);
            d0 < reach + r
                && (1..=samples).any(|k| {
                    let (x, y) = arc_point(&self.body, kappa, reach * k as f64 / samples as f64);
                    let d = (p.x - x).hypot(p.y - y);
                    d < r && d < d0
                })
        })
    }

    /// Advances `dt` seconds at simulated time `t` (the end of the step).
    pub fn step(&mut self, world: &World, t: f64, dt: f64) {
        let Some(doc) = self.followed.doc() else {
            self.body.step(0.0, 0.0, &self.limits, dt);
            return;
        };
        let mut cmd = self.follower.command(&doc.waypoints, &self.body, &self.limits);
        if self.follower.is_finished() && self.stats.finished_at_s.is_none() {
            self.stats.finished_at_s = Some(t);
        }
        // The speed it would have after this step, and the arc it is steered along.
        let v_next = cmd.v.min(self.body.v + self.limits.a_max * dt).max(self.body.v);
        let kappa = if cmd.v > 1e-9 { cmd.w / cmd.v } else { 0.0 };
        let blocked = v_next > 0.0 && self.path_blocked(v_next, kappa, world.grid.geometry.resolution);
        if blocked {
            // Turning on the spot is always safe for a disc: face the target while waiting.
            cmd.w = self.follower.turn_rate(&doc.waypoints, &self.body, &self.limits);
            cmd.v = 0.0;
            if !self.blocked {
                self.stats.stops += 1;
            }
        }
        self.blocked = blocked;
        let from = self.position();
        self.stats.driven_m += self.body.step(cmd.v, cmd.w, &self.limits, dt);
        let to = self.position();
        if cmd.tool_on {
            self.swept.stamp_segment(from, to);
        }
        let touching = world.collides(to, self.spec.radius);
        let hitting = touching && world.collides(to, self.spec.radius - TRACKING_TOLERANCE_M);
        if hitting && !self.hitting {
            self.stats.collisions += 1;
            tracing::warn!(robot = %self.spec.id, x = to.x, y = to.y, "collision with the world");
        } else if touching && !self.touching {
            self.stats.grazes += 1;
        }
        self.touching = touching;
        self.hitting = hitting;
        let touching_mover = world.touches_mover(to, self.spec.radius);
        if touching_mover && !self.touching_mover {
            self.stats.mover_contacts += 1;
        }
        self.touching_mover = touching_mover;
    }
}
