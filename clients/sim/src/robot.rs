//! One simulated robot, sans-IO: its body, the plan it follows (by version), the safety stop on its own scan,
//! and what it measures (driven length, stops, collisions, the swept tool area).

use shift_client::robot::{Applied, FollowedPlan, RobotMessage};
use shift_planner::geom::Point2;
use shift_planner::map::{GridGeometry, OccupancyGrid};
use shift_planner::metrics::coverage::CoverageRaster;

use crate::drive::{DiffDrive, Limits};
use crate::pursuit::{Command, Follower};
use crate::world::World;
use crate::world::file::RobotSpecFile;

/// The API's defaults for limits a world file leaves out.
const DEFAULT_V_MAX: f64 = 1.0;
const DEFAULT_A_MAX: f64 = 0.5;
const DEFAULT_W_MAX: f64 = 1.5;
const ALPHA_MAX: f64 = 3.0;
/// Tolerance of the safety field beyond half a map cell, metres, round what it sees that its map does not
/// hold (see [`SimRobot::path_blocked`]).
const GRAZE_M: f64 = 0.01;
/// The same round returns on walls its map holds: the depth a touch may have and still count as a graze
/// ([`TRACKING_TOLERANCE_M`]) less [`GRAZE_KEEP_M`], so a robot tracking a wall-hugging lane a centimetre or so
/// off is not stopped by the wall its plan passes at its radius, and still stops short of a collision.
const GRAZE_KNOWN_M: f64 = TRACKING_TOLERANCE_M - GRAZE_KEEP_M;
/// What the safety field keeps between itself and a collision with a known wall, metres: the scan's angular
/// sampling and the braking path's steps let a body end a few millimetres past where its field was checked.
const GRAZE_KEEP_M: f64 = 0.005;
/// How much closer to what it saw than it already is a body inside its safety field may come on a step,
/// metres: rounding, far below the scan's point spacing (see [`SimRobot::path_blocked`]).
const SLIDE_SLACK_M: f64 = 1e-4;
/// A stopped robot this close to a field's edge (or inside it) turns to slide along it ([`SimRobot::slide_turn`]),
/// metres.
const SLIDE_NEAR_M: f64 = 0.01;
/// How much a slide heading tips away from the field, as a share of the unit direction along it.
const SLIDE_TIP: f64 = 0.2;
/// Yaw-rate gain of a slide turn, 1/s.
const SLIDE_TURN_GAIN: f64 = 2.0;
/// Extra room kept ahead beyond where the body would come to rest at full speed, metres; it shrinks with the
/// speed (slack for what the braking model leaves out grows with it), so a robot creeping onto a lane end that
/// the plan puts at its radius from a wall's cells reaches it instead of standing short.
const STOP_MARGIN_M: f64 = 0.05;
/// How far the body may reach into the world before it counts as a collision, metres: plans pass walls at
/// exactly the radius from non-free cell centres (DESIGN §6), and the simulated controller tracks its path to
/// within a centimetre or two, so touching at that depth is a graze (counted apart), not a collision.
pub const TRACKING_TOLERANCE_M: f64 = 0.02;
/// How far ahead a detour's headway toward the target is judged, seconds.
const DETOUR_LOOKAHEAD_S: f64 = 1.0;
/// The slowest detour speed, m/s.
const DETOUR_CRAWL_MPS: f64 = 0.1;
/// Yaw rates tried either side of straight on by a detour (the range split in this many steps each way).
const DETOUR_RATES: u32 = 7;
/// The headway a detour must make over its roll-out, metres.
const DETOUR_HEADWAY_M: f64 = 0.02;
/// How long a robot stopped by its safety check waits before it gives up its target, simulated seconds (a
/// waypoint follower that does not stop on a failed goal, as Nav2's with `stop_on_failure: false`).
pub const GIVE_UP_S: f64 = 10.0;
/// How long a robot stopped by its safety check waits before it retraces its path goal by goal
/// ([`crate::pursuit::Follower::retrace`]), simulated seconds: long enough for a mover to walk by.
pub const RETRACE_S: f64 = 2.0;
/// A robot held by its safety stop that has not got this far from where it was first held is still held, metres.
const STUCK_MOVE_M: f64 = 0.05;
/// How far back along its path from the target a retracing robot looks for its nearest waypoint, metres.
const RETRACE_BACK_M: f64 = 1.0;
/// A target given up takes the waypoints this close to it along, metres.
const GIVE_UP_CLEAR_M: f64 = 1.0;
/// Bound on the steps of a predicted stop (a body at 10 m/s braking at 0.5 m/s² in 0.05 s steps needs 400).
const MAX_BRAKING_STEPS: usize = 2000;

/// Where the body's centre would pass if it took `cmd` for one step of `dt` and then braked to rest holding the
/// same yaw-rate command, with the body's own acceleration limits (its yaw rate lags the command, so the arc it
/// really drives is not the commanded one); then [`STOP_MARGIN_M`], scaled by the speed of that step over
/// `v_max`, on along its final heading.
fn braking_path(body: &DiffDrive, cmd: Command, limits: &Limits, dt: f64) -> Vec<Point2> {
    let mut b = *body;
    let mut path = Vec::new();
    b.step(cmd.v, cmd.w, limits, dt);
    path.push(Point2::new(b.x, b.y));
    let margin = if limits.v_max > 0.0 {
        STOP_MARGIN_M * (b.v.abs() / limits.v_max).min(1.0)
    } else {
        STOP_MARGIN_M
    };
    let mut n = 0;
    while b.v > 0.0 && n < MAX_BRAKING_STEPS {
        b.step(0.0, cmd.w, limits, dt);
        path.push(Point2::new(b.x, b.y));
        n += 1;
    }
    let (c, s) = (b.yaw.cos(), b.yaw.sin());
    for k in 1..=2 {
        let d = margin * f64::from(k) / 2.0;
        path.push(Point2::new(b.x + d * c, b.y + d * s));
    }
    path
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
    /// Waypoints given up after waiting [`GIVE_UP_S`] for a way to them.
    pub skipped_waypoints: u64,
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
    /// The radius of the safety field round each of `seen` (see [`Self::fields`]).
    fields: Vec<f64>,
    blocked: bool,
    /// The yaw-rate command its last clear check assumed while braking.
    brake_w: f64,
    /// Since when, and where, its safety stop has held it without letting it get anywhere (see
    /// [`STUCK_MOVE_M`]), simulated seconds.
    waiting_since: Option<(f64, Point2)>,
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
            fields: Vec::new(),
            blocked: false,
            brake_w: 0.0,
            waiting_since: None,
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
        // The patch of a correction, to move the target with it when it alone is applied.
        let mut patch = None;
        let applied = match message {
            RobotMessage::Plan(doc) => self.followed.on_plan(doc),
            RobotMessage::Correction(c) => {
                patch = Some((c.version, c.from, c.to, c.waypoints.len()));
                match self.followed.on_correction(c) {
                    Ok(a) => a,
                    Err(e) => {
                        tracing::warn!(robot = %self.spec.id, "correction not applied: {e}");
                        self.stats.corrections_rejected += 1;
                        return Applied::Stale;
                    }
                }
            }
            RobotMessage::Status(status) => return self.followed.on_status(&status),
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
                match patch {
                    Some((v, from, to, inserted)) if v == *version && v == old_version + 1 => {
                        self.follower.corrected(from, to, inserted, &doc.waypoints, &self.body);
                    }
                    // Held corrections applied with it: their patches are not all known here.
                    _ => self.follower.reacquire(old_len, &doc.waypoints, &self.body),
                }
                if let Some(w) = doc.waypoints.get(self.follower.target()) {
                    tracing::info!(robot = %self.spec.id, version, x = self.body.x, y = self.body.y, target_x = w.x, target_y = w.y, "correction applied");
                }
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

    /// Its last scan's returns in the map frame.
    pub fn seen(&self) -> &[Point2] {
        &self.seen
    }

    /// Index of the waypoint it is heading for.
    pub fn target_index(&self) -> usize {
        self.follower.target()
    }

    /// The waypoints it has still to reach, from its current target on while they stay within `within_m` of
    /// it (map frame).
    pub fn path_ahead(&self, within_m: f64) -> Vec<Point2> {
        let here = self.position();
        self.followed.doc().map_or_else(Vec::new, |d| {
            d.waypoints
                .iter()
                .skip(self.follower.target())
                .map(|w| Point2::new(w.x, w.y))
                .take_while(|p| (*p - here).norm() <= within_m)
                .collect()
        })
    }

    /// Keeps a scan's returns (robot-frame points) in the map frame for the safety stop, each with its field
    /// on the robot's `map` (see [`Self::fields`]).
    pub fn observe(&mut self, points: &[(f64, f64)], map: &OccupancyGrid) {
        let (c, s) = (self.body.yaw.cos(), self.body.yaw.sin());
        self.seen = points
            .iter()
            .map(|&(x, y)| Point2::new(self.body.x + c * x - s * y, self.body.y + s * x + c * y))
            .collect();
        self.fields = self.fields(map);
    }

    /// True when something seen lies where the body would pass along `path` (see [`braking_path`]). Each return
    /// has a field round it ([`Self::fields`]): the body's radius less half a map cell (plans keep the radius from
    /// non-free cell *centres*, DESIGN §6, so a robot on its plan sees a wall's face up to half a cell closer than
    /// that, and must not stop for it), less a tracking tolerance. A body already inside a field (a centimetre
    /// off a path that hugs a wall) may move as long as it gets no deeper into any field than it is now (less
    /// [`SLIDE_SLACK_M`]): it can slide along a wall or back away from it, but not close in.
    fn path_blocked(&self, path: &[Point2]) -> bool {
        let here = self.position();
        let mut reach = 0.0;
        let mut last = here;
        for p in path {
            reach += (*p - last).norm();
            last = *p;
        }
        let near: Vec<(Point2, f64)> = self
            .seen
            .iter()
            .zip(&self.fields)
            .map(|(p, r)| (*p, *r))
            .filter(|(p, r)| (*p - here).norm() < reach + r)
            .collect();
        // How far outside its field the body is now, at the worst (negative: that deep inside one).
        let now = near
            .iter()
            .map(|(p, r)| (*p - here).norm() - r)
            .fold(f64::INFINITY, f64::min);
        let floor = if now >= 0.0 { 0.0 } else { now - SLIDE_SLACK_M };
        near.iter()
            .any(|(p, r)| path.iter().any(|q| (*p - *q).norm() - r < floor))
    }

    /// The radius of the safety field round each return of the last scan: [`GRAZE_M`] or, on a wall its map
    /// holds (the return's cell or one next to it not free), [`GRAZE_KNOWN_M`], beyond half a cell.
    fn fields(&self, map: &OccupancyGrid) -> Vec<f64> {
        let g = map.geometry;
        let base = self.spec.radius - g.resolution / 2.0;
        self.seen
            .iter()
            .map(|p| {
                base - if crate::sight::near_known(map, *p) {
                    GRAZE_KNOWN_M
                } else {
                    GRAZE_M
                }
            })
            .collect()
    }

    /// The safety stop with a local detour, as a robot's own local planner does it. `cmd` goes as it is when the
    /// path the body would really drive (see [`braking_path`]) is clear of what it saw. Otherwise the clear arc
    /// that brings it closest to `target` (see [`SimRobot::detour`]) goes instead; failing that it stops: it
    /// brakes on exactly the path last found clear (the yaw-rate command that path was checked with) and, at
    /// rest, turns on the spot at `turn` (always safe for a disc) to face its target while it waits. Every
    /// command it lets through was checked from the body's state at that step, so the body never enters the
    /// field round what it saw.
    fn guard(&mut self, cmd: Command, target: Option<Point2>, turn: f64, dt: f64) -> Command {
        let clear = |c: Command| !self.path_blocked(&braking_path(&self.body, c, &self.limits, dt));
        let chosen = if self.body.v <= 0.0 && cmd.v <= 0.0 || clear(cmd) {
            Some(cmd)
        } else {
            target.and_then(|t| self.detour(cmd, t, dt))
        };
        if let Some(c) = chosen {
            self.brake_w = c.w;
            self.blocked = false;
            return c;
        }
        if !self.blocked {
            self.stats.stops += 1;
        }
        self.blocked = true;
        Command {
            v: 0.0,
            w: if self.body.v > 0.0 {
                self.brake_w
            } else {
                target.and_then(|t| self.slide_turn(t)).unwrap_or(turn)
            },
            tool_on: cmd.tool_on,
        }
    }

    /// Standing at the edge of a field with its target beyond it (the way to the target closes in on what it
    /// saw, as round the end of a wall it cut too close), the yaw rate that turns it to slide along the field
    /// instead: toward the target's direction less its part toward the return deepest in (or nearest) its
    /// field, tipped a little away. `None` when no return is within a centimetre of its field or the target
    /// lies away from it (turning toward the target is then the way on).
    fn slide_turn(&self, target: Point2) -> Option<f64> {
        let here = self.position();
        let (p, depth) = self
            .seen
            .iter()
            .zip(&self.fields)
            .map(|(p, r)| (*p, (*p - here).norm() - r))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let away = here - p;
        let to = target - here;
        if depth > SLIDE_NEAR_M || away.norm() < 1e-9 || to.norm() < 1e-9 {
            return None;
        }
        let (n, t) = (away.normalize(), to.normalize());
        let into = t.dot(&n);
        if into >= 0.0 {
            return None;
        }
        let slide = t - n * into + n * SLIDE_TIP;
        let err = crate::drive::wrap(slide.y.atan2(slide.x) - self.body.yaw);
        Some((SLIDE_TURN_GAIN * err).clamp(-self.limits.w_max, self.limits.w_max))
    }

    /// Among arcs at the commanded speed, half of it and a crawl, and yaw rates across the body's range, the
    /// clear one whose [`DETOUR_LOOKAHEAD_S`] roll-out ends closest to `target`, if that is closer than the body
    /// is now (a detour must make headway, or the robot waits).
    fn detour(&self, cmd: Command, target: Point2, dt: f64) -> Option<Command> {
        let v_nominal = cmd.v.max(self.body.v).clamp(DETOUR_CRAWL_MPS, self.limits.v_max);
        let now = (target - self.position()).norm();
        let mut best: Option<(f64, Command)> = None;
        for v in [v_nominal, v_nominal / 2.0, DETOUR_CRAWL_MPS] {
            for k in 0..=2 * DETOUR_RATES {
                let w = self.limits.w_max * (f64::from(k) / f64::from(DETOUR_RATES) - 1.0);
                let c = Command { v, w, ..cmd };
                let mut b = self.body;
                for _ in 0..(DETOUR_LOOKAHEAD_S / dt).ceil() as usize {
                    b.step(c.v, c.w, &self.limits, dt);
                }
                let end = (target - Point2::new(b.x, b.y)).norm();
                if end < now - DETOUR_HEADWAY_M
                    && best.is_none_or(|(e, _)| end < e)
                    && !self.path_blocked(&braking_path(&self.body, c, &self.limits, dt))
                {
                    best = Some((end, c));
                }
            }
        }
        best.map(|(_, c)| c)
    }

    /// Advances `dt` seconds at simulated time `t` (the end of the step).
    pub fn step(&mut self, world: &World, t: f64, dt: f64) {
        let Some(doc) = self.followed.doc() else {
            self.body.step(0.0, 0.0, &self.limits, dt);
            return;
        };
        let cmd = self.follower.command(&doc.waypoints, &self.body, &self.limits);
        if self.follower.is_finished() && self.stats.finished_at_s.is_none() {
            self.stats.finished_at_s = Some(t);
        }
        let turn = self.follower.turn_rate(&doc.waypoints, &self.body, &self.limits);
        let target = doc.waypoints.get(self.follower.target()).map(|w| Point2::new(w.x, w.y));
        let cmd = self.guard(cmd, target, turn, dt);
        // Held means blocked now, or blocked before and not yet STUCK_MOVE_M from where it was first held: a
        // robot whose guard lets a creep through between stops (at the edge of its safety field) is as stuck
        // as one standing still.
        let here = self.position();
        self.waiting_since = match self.waiting_since {
            Some((since, at)) if (here - at).norm() < STUCK_MOVE_M => Some((since, at)),
            _ if self.blocked => Some((t, here)),
            _ => None,
        };
        if let Some(doc) = self.followed.doc()
            && self.waiting_since.is_some_and(|(since, _)| t - since >= RETRACE_S)
            && self.follower.retrace(&doc.waypoints, &self.body, RETRACE_BACK_M)
        {
            // A fresh wait: giving up counts from here.
            self.waiting_since = Some((t, here));
            tracing::debug!(robot = %self.spec.id, target = self.follower.target(), x = self.body.x, y = self.body.y, "blocked: retracing the path goal by goal");
        }
        if let Some(doc) = self.followed.doc()
            && self.waiting_since.is_some_and(|(since, _)| t - since >= GIVE_UP_S)
        {
            let skipped = self.follower.skip(&doc.waypoints, GIVE_UP_CLEAR_M);
            self.stats.skipped_waypoints += skipped as u64;
            self.waiting_since = None;
            tracing::info!(robot = %self.spec.id, skipped, x = self.body.x, y = self.body.y, "blocked too long: waypoints given up");
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive;
    use proptest::prelude::*;

    fn robot(x: f64, y: f64, yaw: f64) -> SimRobot {
        let spec = RobotSpecFile {
            id: "r".into(),
            start: [x, y, yaw],
            radius: 0.3,
            tool_width: 0.5,
            v_max: None,
            a_max: None,
            w_max: None,
            region: None,
        };
        let geometry = GridGeometry::new(100, 100, 0.1, Point2::new(-5.0, -5.0)).expect("geometry");
        SimRobot::new(spec, geometry, 0.2)
    }

    /// Field radius for a 0.3 m body on a 0.1 m grid.
    const FIELD: f64 = 0.3 - 0.05 - GRAZE_M;

    proptest! {
        /// Whatever it is commanded, a body never drives into the field round anything it has seen (the oracle:
        /// the distance from its centre to every seen point, after every step), even when its yaw rate lags a
        /// command that swings it toward a wall at the side.
        #[test]
        fn the_safety_stop_keeps_the_body_out_of_what_it_saw(
            yaw in -3.2f64..3.2,
            points in proptest::collection::vec((-2.0f64..2.0, -2.0f64..2.0), 1..40),
            commands in proptest::collection::vec((0.0f64..1.2, -2.0f64..2.0, 1usize..30), 1..12),
            tx in -3.0f64..3.0,
            ty in -3.0f64..3.0,
        ) {
            let mut r = robot(0.0, 0.0, yaw);
            r.seen = points.iter().map(|&(x, y)| Point2::new(x, y)).filter(|p| p.coords.norm() >= FIELD).collect();
            r.fields = vec![FIELD; r.seen.len()];
            let turn = 0.7;
            let target = Some(Point2::new(tx, ty));
            for (v, w, n) in commands {
                for _ in 0..n {
                    let cmd = r.guard(Command { v, w, tool_on: false }, target, turn, 0.05);
                    r.body.step(cmd.v, cmd.w, &r.limits, 0.05);
                    for p in &r.seen {
                        let d = (*p - r.position()).norm();
                        prop_assert!(d >= FIELD - 2e-3, "{d} from {p:?} at {:?}", r.body);
                    }
                }
            }
        }
    }

    #[test]
    fn a_lagging_turn_toward_a_wall_is_stopped_before_it() {
        // Spinning left at full rate from rest, then commanded straight on: the body swings left while its yaw
        // rate winds down. A wall 0.28 m to the left ahead clears the commanded straight line, not the swing.
        let mut r = robot(0.0, 0.0, 0.0);
        r.body.w = 1.5;
        r.seen = (0..40)
            .map(|i| Point2::new(f64::from(i) * 0.01, FIELD + 0.03))
            .collect();
        r.fields = vec![FIELD; r.seen.len()];
        let mut closest = f64::INFINITY;
        for _ in 0..40 {
            let cmd = r.guard(
                Command {
                    v: 0.5,
                    w: 0.0,
                    tool_on: false,
                },
                None,
                0.0,
                0.05,
            );
            r.body.step(cmd.v, cmd.w, &r.limits, 0.05);
            for p in &r.seen {
                closest = closest.min((*p - r.position()).norm());
            }
        }
        assert!(closest >= FIELD - 1e-3, "{closest}");
        assert!(r.stats.stops >= 1);
    }

    #[test]
    fn a_robot_squeezed_against_a_wall_detours_along_it_instead_of_waiting() {
        // A wall along y = 0; the robot 0.27 m from it; its target lies along the wall 0.25 m off it. Its
        // controller pulls toward the wall (as pure pursuit does cutting an inside corner), into the field.
        let mut r = robot(0.0, 0.27, 0.0);
        r.seen = (-100..400).map(|i| Point2::new(f64::from(i) * 0.01, 0.0)).collect();
        r.fields = vec![FIELD; r.seen.len()];
        let target = Point2::new(3.0, 0.25);
        let mut reached = false;
        for _ in 0..400 {
            let to = target - r.position();
            if to.norm() < 0.2 {
                reached = true;
                break;
            }
            let err = drive::wrap(to.y.atan2(to.x) - r.body.yaw);
            let nominal = Command {
                v: 0.5,
                w: (3.0 * err - 0.4).clamp(-1.5, 1.5),
                tool_on: true,
            };
            let cmd = r.guard(nominal, Some(target), (3.0 * err).clamp(-1.5, 1.5), 0.05);
            r.body.step(cmd.v, cmd.w, &r.limits, 0.05);
            assert!(r.body.y >= FIELD - 2e-3, "{:?}", r.body);
        }
        assert!(reached, "stuck at {:?}", r.body);
    }

    /// A wall along y = 0 on a 0.1 m map (cells y < 0 occupied), as its returns.
    fn wall_map() -> (OccupancyGrid, Vec<Point2>) {
        let g = GridGeometry::new(100, 100, 0.1, Point2::new(-5.0, -5.0)).expect("geometry");
        let mut map = OccupancyGrid::filled(g, shift_planner::map::CellState::Free);
        map.fill_rect(-5.0, -5.0, 5.0, 0.0, shift_planner::map::CellState::Occupied);
        (
            map,
            (-100..400).map(|i| Point2::new(f64::from(i) * 0.01, 0.0)).collect(),
        )
    }

    #[test]
    fn a_robot_a_centimetre_deep_in_a_known_walls_field_slides_along_it_but_not_into_a_new_obstacle() {
        // The plan runs at the radius from the wall's cell centres (0.3 m from y = -0.05, 0.25 m from the face);
        // the robot tracks it 2.5 cm toward the wall: half a centimetre inside even the known wall's field, so
        // only sliding (no deeper than now) lets it on.
        let (map, wall) = wall_map();
        let mut r = robot(0.0, 0.3 - 0.05 - 0.025, 0.0);
        r.seen = wall.clone();
        r.fields = r.fields(&map);
        assert!(
            r.fields
                .iter()
                .all(|f| (f - (0.3 - 0.05 - GRAZE_KNOWN_M)).abs() < 1e-12)
        );
        let ahead = Command {
            v: 0.3,
            w: 0.0,
            tool_on: true,
        };
        for _ in 0..40 {
            let cmd = r.guard(ahead, Some(Point2::new(3.0, 0.225)), 0.0, 0.05);
            r.body.step(cmd.v, cmd.w, &r.limits, 0.05);
        }
        assert!(r.body.x > 0.4 && !r.blocked, "held at {:?}", r.body);
        // The same returns with no wall on the map (an obstacle the map does not have) keep the strict field,
        // and the body may not close in on it.
        let free = OccupancyGrid::filled(map.geometry, shift_planner::map::CellState::Free);
        let mut r = robot(0.0, 0.3 - 0.05 - 0.025, 0.0);
        r.seen = wall;
        r.fields = r.fields(&free);
        assert!(r.fields.iter().all(|f| (f - FIELD).abs() < 1e-12));
        for _ in 0..40 {
            let toward = Command {
                v: 0.3,
                w: -0.3,
                tool_on: true,
            };
            let cmd = r.guard(toward, None, 0.0, 0.05);
            r.body.step(cmd.v, cmd.w, &r.limits, 0.05);
            assert!(r.body.y >= 0.3 - 0.05 - 0.025 - 1e-3, "closed in: {:?}", r.body);
        }
    }

    #[test]
    fn a_robot_stopped_short_of_a_walls_end_turns_to_slide_past_it_and_gets_there() {
        // A wall's end at the origin (returns along x = 0 for y ≥ 0); the robot stands just inside its field
        // below and left of it, facing its target beyond the end, so straight on closes in on the corner.
        let corner: Vec<Point2> = (0..200).map(|i| Point2::new(0.0, f64::from(i) * 0.005)).collect();
        let y0 = -((FIELD - 0.001).powi(2) - 0.05f64.powi(2)).sqrt();
        let mut r = robot(-0.05, y0, 0.0);
        r.seen = corner;
        r.fields = vec![FIELD; r.seen.len()];
        let target = Point2::new(0.4, y0 - 0.02);
        let toward = |r: &SimRobot| {
            let to = target - r.position();
            let err = drive::wrap(to.y.atan2(to.x) - r.body.yaw);
            Command {
                v: if err.abs() < 0.8 { 0.2 } else { 0.0 },
                w: (2.0 * err).clamp(-1.5, 1.5),
                tool_on: true,
            }
        };
        assert!(
            r.path_blocked(&braking_path(&r.body, toward(&r), &r.limits, 0.05)),
            "straight on is blocked"
        );
        let turn = r.slide_turn(target).expect("a slide");
        assert!(turn < 0.0, "turns away from the corner: {turn}");
        let mut reached = false;
        for _ in 0..600 {
            let to = target - r.position();
            if to.norm() < 0.05 {
                reached = true;
                break;
            }
            let nominal = toward(&r);
            let cmd = r.guard(nominal, Some(target), nominal.w, 0.05);
            r.body.step(cmd.v, cmd.w, &r.limits, 0.05);
            let nearest = r
                .seen
                .iter()
                .map(|p| (*p - r.position()).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(
                nearest >= FIELD - 0.001 - 1e-3,
                "closed in to {nearest} at {:?}",
                r.body
            );
        }
        assert!(reached, "stuck at {:?}", r.body);
    }
}
