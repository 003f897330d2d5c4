//! Following a plan's waypoints: pure pursuit toward the current target at the plan's speed, with seed 003's
//! dynamic tracking (§ "dynamic tracking", Alg. 2). The following threshold `mu` is a distance in metres: once
//! the robot is closer than `mu` to its target it takes the next one without stopping; `mu = 0` is classic
//! goal-by-goal navigation that brakes to a stop on every target and turns on the spot toward the next.

use shift_proto::{WaypointDoc, WaypointKindDoc};

use crate::drive::{DiffDrive, Limits, wrap};

/// Within this distance of a target the robot has reached it when it stops there (mu = 0), metres.
const ARRIVE_M: f64 = 0.03;
/// Below this speed the robot counts as stopped, m/s.
const STOPPED_MPS: f64 = 0.01;
/// A target further off the heading than this is turned to on the spot first, radians.
const TURN_ON_SPOT_RAD: f64 = std::f64::consts::FRAC_PI_4;
/// Goal by goal (mu = 0), the robot turns on the spot until its target is within this of its heading before
/// it drives off (it stands still anyway: aligning first keeps it on the straight line to the target), radians.
const ALIGN_RAD: f64 = 0.05;
/// Yaw-rate gain of the on-spot turn, 1/s.
const TURN_GAIN: f64 = 2.0;
/// How far beyond its projection on the segment into its target the robot steers, at the least, metres (see
/// [`Follower::carrot`]). Shorter look-aheads swing about the line: the body's yaw rate lags its command
/// (`alpha_max`), and at 0.15 m the unit test's robot weaves ±8 cm for metres on end.
const LOOKAHEAD_M: f64 = 0.3;
/// The look-ahead grows with the speed: this many seconds of travel, when longer than [`LOOKAHEAD_M`].
const LOOKAHEAD_S: f64 = 0.5;
/// Waypoints searched either side of the old target when the path changes under the robot.
const REACQUIRE_WINDOW: usize = 400;

/// What the follower asks of the body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Forward speed, m/s.
    pub v: f64,
    /// Yaw rate, rad/s.
    pub w: f64,
    /// The tool works (the stretch being driven is a `cover` one).
    pub tool_on: bool,
}

impl Command {
    const STOP: Self = Self {
        v: 0.0,
        w: 0.0,
        tool_on: false,
    };
}

/// Where the robot is along its plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Follower {
    mu: f64,
    target: usize,
    finished: bool,
    /// After [`Self::retrace`]: goal by goal (mu = 0) until this waypoint is reached.
    precise_until: Option<usize>,
}

impl Follower {
    /// A follower with threshold `mu` (metres, ≥ 0), heading for the first waypoint.
    pub fn new(mu: f64) -> Self {
        Self {
            mu: mu.max(0.0),
            target: 0,
            finished: false,
            precise_until: None,
        }
    }

    /// The threshold in force: 0 while retracing (see [`Self::retrace`]).
    fn mu(&self) -> f64 {
        if self.precise_until.is_some() { 0.0 } else { self.mu }
    }

    /// True while it retraces its path goal by goal (see [`Self::retrace`]).
    pub fn is_retracing(&self) -> bool {
        self.precise_until.is_some()
    }

    /// A robot stuck short of its target (its safety stop holds it: cutting a corner at `mu` brought it too
    /// near a wall's end, and the way to the target lies round it) goes back to its path: it heads for the
    /// waypoint nearest it among those up to `back_m` of path before the target, and follows goal by goal
    /// (stop, turn on the spot, straight on: the path's own polyline, which keeps its clearance) until it has
    /// reached the target it was stuck on, then takes up `mu` again. Returns false (and changes nothing) when
    /// already retracing or there is no path.
    pub fn retrace(&mut self, wps: &[WaypointDoc], body: &DiffDrive, back_m: f64) -> bool {
        if self.precise_until.is_some() || self.finished || self.target >= wps.len() {
            return false;
        }
        let d2 = |i: usize| (wps[i].x - body.x).powi(2) + (wps[i].y - body.y).powi(2);
        let (mut first, mut run) = (self.target, 0.0);
        while first > 0 && run < back_m {
            run += (wps[first].x - wps[first - 1].x).hypot(wps[first].y - wps[first - 1].y);
            first -= 1;
        }
        let nearest = (first..=self.target)
            .min_by(|&a, &b| d2(a).total_cmp(&d2(b)))
            .unwrap_or(self.target);
        self.precise_until = Some(self.target);
        self.target = nearest;
        true
    }

    /// The waypoint it heads for.
    pub fn target(&self) -> usize {
        self.target
    }

    /// True once the last waypoint is reached.
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    fn reached(&self, d: f64, body: &DiffDrive, last: bool) -> bool {
        let mu = self.mu();
        if mu == 0.0 || last {
            d < ARRIVE_M.max(if last { mu.min(0.1) } else { 0.0 }) && (body.v < STOPPED_MPS || mu > 0.0)
        } else {
            d < mu
        }
    }

    /// The command for this instant.
    pub fn command(&mut self, wps: &[WaypointDoc], body: &DiffDrive, lim: &Limits) -> Command {
        if self.finished || wps.is_empty() {
            return Command::STOP;
        }
        let dist = |i: usize| ((wps[i].x - body.x).powi(2) + (wps[i].y - body.y).powi(2)).sqrt();
        loop {
            let last = self.target + 1 >= wps.len();
            if !self.reached(dist(self.target), body, last) {
                break;
            }
            if last {
                self.finished = true;
                self.precise_until = None;
                return Command::STOP;
            }
            if self.precise_until.is_some_and(|k| self.target >= k) {
                self.precise_until = None;
            }
            self.target += 1;
        }
        let wp = &wps[self.target];
        let tool_on = wp.kind == WaypointKindDoc::Cover && self.target > 0;
        let l = (wp.x - body.x).hypot(wp.y - body.y);
        let (ax, ay) = self.carrot(wps, body);
        let (dx, dy) = (ax - body.x, ay - body.y);
        let la = (dx * dx + dy * dy).sqrt();
        let (c, s) = (body.yaw.cos(), body.yaw.sin());
        let (lx, ly) = (c * dx + s * dy, -s * dx + c * dy);
        let alpha = wrap(ly.atan2(lx));
        let standing = body.v < STOPPED_MPS && self.mu() == 0.0 && l > ARRIVE_M;
        if alpha.abs() > TURN_ON_SPOT_RAD || (standing && alpha.abs() > ALIGN_RAD) {
            return Command {
                v: 0.0,
                w: (TURN_GAIN * alpha).clamp(-lim.w_max, lim.w_max),
                tool_on,
            };
        }
        // Pure pursuit: the arc through the carrot tangent to the heading.
        let kappa = if la > 1e-9 { 2.0 * ly / (la * la) } else { 0.0 };
        let mut v = wp.v.clamp(0.05, lim.v_max);
        if self.mu() == 0.0 || self.target + 1 == wps.len() {
            // Brake to stand on the target.
            v = v.min((2.0 * lim.a_max * l).sqrt());
        }
        if kappa.abs() > 1e-9 {
            v = v.min(lim.w_max / kappa.abs());
        }
        v *= alpha.cos();
        Command {
            v,
            w: v * kappa,
            tool_on,
        }
    }

    /// The point it steers for: on the segment from the previous waypoint into the target, [`LOOKAHEAD_M`]
    /// beyond the body's projection on it (the target itself when nearer), so a stretch between targets far
    /// apart is driven along its straight line rather than on an arc that leaves it.
    fn carrot(&self, wps: &[WaypointDoc], body: &DiffDrive) -> (f64, f64) {
        let wp = &wps[self.target];
        let Some(p) = self.target.checked_sub(1).and_then(|i| wps.get(i)) else {
            return (wp.x, wp.y);
        };
        let (sx, sy) = (wp.x - p.x, wp.y - p.y);
        let len = sx.hypot(sy);
        let ahead = LOOKAHEAD_M.max(body.v.abs() * LOOKAHEAD_S);
        if len <= ahead {
            return (wp.x, wp.y);
        }
        let along = (((body.x - p.x) * sx + (body.y - p.y) * sy) / len).clamp(0.0, len);
        let at = (along + ahead).min(len) / len;
        (p.x + sx * at, p.y + sy * at)
    }

    /// The on-the-spot yaw rate that turns the body toward its target.
    pub fn turn_rate(&self, wps: &[WaypointDoc], body: &DiffDrive, lim: &Limits) -> f64 {
        let Some(wp) = wps.get(self.target) else { return 0.0 };
        let alpha = wrap((wp.y - body.y).atan2(wp.x - body.x) - body.yaw);
        (TURN_GAIN * alpha).clamp(-lim.w_max, lim.w_max)
    }

    /// The path changed under the robot (a correction, or the plan fetched after a gap): heads for the
    /// waypoint of the new path nearest the robot within a window round the old target (shifted by the change
    /// in length), the later one on a tie.
    pub fn reacquire(&mut self, old_len: usize, wps: &[WaypointDoc], body: &DiffDrive) {
        if wps.is_empty() {
            self.target = 0;
            return;
        }
        let grown = wps.len() as i64 - old_len as i64;
        let lo = self.target.saturating_sub(REACQUIRE_WINDOW);
        let hi = ((self.target as i64 + REACQUIRE_WINDOW as i64 + grown.max(0)).max(0) as usize).min(wps.len() - 1);
        let lo = lo.min(hi);
        let d2 = |i: usize| (wps[i].x - body.x).powi(2) + (wps[i].y - body.y).powi(2);
        let mut best = lo;
        for i in lo..=hi {
            if d2(i) <= d2(best) {
                best = i;
            }
        }
        self.target = best;
        self.finished = false;
        self.precise_until = None;
    }

    /// One correction replaced waypoints `[from, to)` of the path by `inserted` waypoints (`wps` is the new
    /// path): the target moves with the waypoint it named, as the daemon moves the robot's progress. A target
    /// inside the replaced stretch becomes the patch's waypoint nearest the robot (the later on a tie), so the
    /// robot neither turns back for the patch's start nor cuts into it. Unlike [`Self::reacquire`] this never
    /// jumps to another pass of the path that happens to run by.
    pub fn corrected(&mut self, from: usize, to: usize, inserted: usize, wps: &[WaypointDoc], body: &DiffDrive) {
        if wps.is_empty() {
            self.target = 0;
            return;
        }
        let last = wps.len() - 1;
        let t = self.target;
        self.target = if t >= to {
            t + inserted - (to - from).min(t)
        } else if t >= from {
            let d2 = |i: usize| (wps[i].x - body.x).powi(2) + (wps[i].y - body.y).powi(2);
            let hi = (from + inserted).min(last);
            // The nearest, the later on a tie.
            (from.min(hi)..=hi)
                .rev()
                .min_by(|&a, &b| d2(a).total_cmp(&d2(b)))
                .unwrap_or(hi)
        } else {
            t
        }
        .min(last);
        self.finished = false;
        self.precise_until = None;
    }

    /// Gives up the target (a robot blocked too long, as a waypoint follower that does not stop on a failed
    /// goal): heads for the first later waypoint more than `clear_m` from it, or finishes when none is; returns
    /// the waypoints given up.
    pub fn skip(&mut self, wps: &[WaypointDoc], clear_m: f64) -> usize {
        let Some(at) = wps.get(self.target) else {
            self.finished = true;
            return 0;
        };
        let from = self.target;
        self.precise_until = None;
        let far = |w: &WaypointDoc| (w.x - at.x).hypot(w.y - at.y) > clear_m;
        match wps.iter().enumerate().skip(from + 1).find(|(_, w)| far(w)) {
            Some((i, _)) => self.target = i,
            None => {
                self.target = wps.len() - 1;
                self.finished = true;
            }
        }
        self.target - from
    }

    /// A new plan: start again from its first waypoint.
    pub fn restart(&mut self) {
        self.target = 0;
        self.finished = false;
        self.precise_until = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIM: Limits = Limits {
        v_max: 1.0,
        a_max: 0.5,
        w_max: 1.5,
        alpha_max: 3.0,
    };

    fn wp(x: f64, y: f64) -> WaypointDoc {
        WaypointDoc {
            x,
            y,
            z: 0.0,
            v: 0.8,
            t: 0.0,
            kind: WaypointKindDoc::Cover,
            region: Some(0),
        }
    }

    /// An L: 4 m along x, then 3 m up, waypoints every 0.25 m.
    fn ell() -> Vec<WaypointDoc> {
        let mut w: Vec<_> = (0..=16).map(|i| wp(f64::from(i) * 0.25, 0.0)).collect();
        w.extend((1..=12).map(|i| wp(4.0, f64::from(i) * 0.25)));
        w
    }

    /// Drives until finished; returns (time, largest distance from the path's polyline, stops on the way).
    fn drive(mu: f64) -> (f64, f64, usize) {
        let wps = ell();
        let mut f = Follower::new(mu);
        let mut body = DiffDrive::at(0.0, 0.0, 0.0);
        let (mut t, mut worst, mut stops, mut moving) = (0.0, 0.0f64, 0, false);
        while !f.is_finished() && t < 200.0 {
            let c = f.command(&wps, &body, &LIM);
            body.step(c.v, c.w, &LIM, 0.05);
            t += 0.05;
            let off = if body.x <= 4.0 {
                body.y.abs().min((body.x - 4.0).abs())
            } else {
                body.x - 4.0
            };
            worst = worst.max(off);
            if moving && body.v < STOPPED_MPS {
                stops += 1;
                moving = false;
            }
            moving |= body.v > 0.05;
        }
        assert!(f.is_finished(), "mu {mu}: not finished after {t} s");
        (t, worst, stops)
    }

    #[test]
    fn dynamic_tracking_removes_stop_and_go() {
        let (t0, off0, stops0) = drive(0.0);
        let (t2, off2, stops2) = drive(0.2);
        // Goal by goal stops at each of the 28 targets; mu = 0.2 m drives through.
        assert!(stops0 >= 25, "{stops0}");
        assert!(stops2 <= 2, "{stops2}");
        assert!(t2 < t0 / 2.0, "{t2} vs {t0}");
        // Goal by goal stays on the path; mu cuts the L's sharp corner by about its look-ahead.
        assert!(off0 < 0.07 && off2 < 0.35, "{off0} {off2}");
    }

    #[test]
    fn giving_up_a_target_heads_for_the_first_waypoint_clear_of_it() {
        let wps = ell();
        let mut f = Follower::new(0.2);
        f.target = 14; // (3.5, 0)
        // (3.75, 0), (4, 0) and (4, 0.25) lie within 0.6 m of it.
        assert_eq!(f.skip(&wps, 0.6), 4);
        assert_eq!((wps[f.target()].x, wps[f.target()].y), (4.0, 0.5));
        f.target = wps.len() - 2;
        f.skip(&wps, 0.6);
        assert!(f.is_finished());
    }

    #[test]
    fn a_correction_is_picked_up_where_the_robot_is() {
        let wps = ell();
        let mut f = Follower::new(0.2);
        let mut body = DiffDrive::at(0.0, 0.0, 0.0);
        while body.x < 1.0 {
            let c = f.command(&wps, &body, &LIM);
            body.step(c.v, c.w, &LIM, 0.05);
        }
        let before = f.target();
        // Ten detour waypoints inserted from index 8 (x = 2.0): the target stays ahead of the robot.
        let mut patched = wps[..8].to_vec();
        patched.extend((0..10).map(|i| wp(2.0 + f64::from(i) * 0.1, 0.5)));
        patched.extend_from_slice(&wps[8..]);
        f.reacquire(wps.len(), &patched, &body);
        assert!(
            f.target() <= before + 1 && f.target() + 1 >= before,
            "{} vs {before}",
            f.target()
        );
        let p = &patched[f.target()];
        assert!(p.x >= body.x - 0.3, "{} behind {}", p.x, body.x);
    }

    #[test]
    fn a_correction_moves_the_target_with_its_waypoint_not_to_a_later_pass_running_by() {
        // East along y = 0, back west along y = 0.3 (a lane closer than the robot's path is to it).
        let mut wps: Vec<_> = (0..=20).map(|i| wp(f64::from(i) * 0.25, 0.0)).collect();
        wps.extend((0..=20).map(|i| wp(5.0 - f64::from(i) * 0.25, 0.3)));
        let body = DiffDrive::at(1.0, 0.2, 0.0); // nearer the return lane than its own
        let patched_at = |from: usize, to: usize, inserted: usize| {
            let mut p = wps[..from].to_vec();
            p.extend((0..inserted).map(|i| wp(3.0 + f64::from(i as u32) * 0.1, -0.4)));
            p.extend_from_slice(&wps[to..]);
            p
        };
        // A patch further on (waypoints 12..14 → 5): the target (5, at x = 1.25) keeps naming that waypoint.
        let mut f = Follower::new(0.2);
        f.target = 5;
        f.corrected(12, 14, 5, &patched_at(12, 14, 5), &body);
        assert_eq!(f.target(), 5);
        // A patch behind: the target shifts with its waypoint.
        f.target = 15;
        let p = patched_at(2, 4, 5);
        f.corrected(2, 4, 5, &p, &body);
        assert_eq!(f.target(), 18);
        assert_eq!((p[18].x, p[18].y), (wps[15].x, wps[15].y));
        // The target replaced: the patch's waypoint nearest the robot, never the return lane running by.
        f.target = 13;
        let p = patched_at(12, 14, 5);
        f.corrected(12, 14, 5, &p, &body);
        assert!((12..=17).contains(&f.target()), "{}", f.target());
        // Whereas the nearest-waypoint search finds the return lane.
        let mut g = Follower::new(0.2);
        g.target = 5;
        g.reacquire(wps.len(), &wps, &body);
        assert!(g.target() > 20, "the search this replaces would jump to {}", g.target());
    }

    /// Targets a metre apart on y = 0 from x = 0 to 4.
    fn sparse() -> Vec<WaypointDoc> {
        (0..=4).map(|i| wp(f64::from(i), 0.0)).collect()
    }

    /// Drives `wps` from `body` with threshold `mu` until finished; the largest |y| after the first two metres,
    /// the stops, and the largest |y| anywhere.
    fn drive_line(wps: &[WaypointDoc], mut body: DiffDrive, mu: f64) -> (f64, usize, f64) {
        let mut f = Follower::new(mu);
        let (mut worst, mut t, mut stops, mut moving) = (0.0f64, 0.0f64, 0, false);
        let mut anywhere = 0.0f64;
        while !f.is_finished() && t < 200.0 {
            let c = f.command(wps, &body, &LIM);
            body.step(c.v, c.w, &LIM, 0.05);
            t += 0.05;
            anywhere = anywhere.max(body.y.abs());
            if body.x > 2.0 {
                worst = worst.max(body.y.abs());
            }
            if moving && body.v < STOPPED_MPS {
                stops += 1;
                moving = false;
            }
            moving |= body.v > 0.05;
        }
        assert!(f.is_finished(), "not finished after {t} s at {body:?}");
        (worst, stops, anywhere)
    }

    #[test]
    fn targets_far_apart_are_reached_along_the_straight_line_between_them() {
        // Leaving the first target 30° off the line: steering for the target itself (an arc through a point a
        // metre on) bows out 5.5 cm and is still 1 cm off after two metres; steering for a point on the segment
        // stays within 2 cm and is back on the line (both measured with this body's limits).
        let (worst, _, anywhere) = drive_line(&sparse(), DiffDrive::at(0.0, 0.0, 0.5), 0.2);
        assert!(worst < 0.005 && anywhere < 0.03, "{worst} {anywhere}");
    }

    #[test]
    fn goal_by_goal_turns_on_the_spot_until_it_faces_the_next_target() {
        let wps = sparse();
        let mut f = Follower::new(0.0);
        // 30° off: under the 45° of a moving robot's on-the-spot turn, but a standing one aligns first.
        let body = DiffDrive::at(0.0, 0.0, 0.5);
        f.target = 1;
        let c = f.command(&wps, &body, &LIM);
        assert!(c.v == 0.0 && c.w < 0.0, "{c:?}");
        // Stop-and-go stays on the line and stops at each of the four targets.
        let (worst, stops, _) = drive_line(&wps, DiffDrive::at(0.0, 0.0, 0.0), 0.0);
        assert!(worst < 0.01 && stops >= 4, "{worst} {stops}");
    }

    #[test]
    fn a_stuck_robot_retraces_from_its_nearest_waypoint_goal_by_goal_then_takes_up_mu_again() {
        let wps = ell();
        let mut f = Follower::new(0.2);
        f.target = 18; // (4, 0.5), round the corner
        let body = DiffDrive::at(3.45, 0.08, 0.0); // cut the corner, stuck near (3.5, 0)
        assert!(f.retrace(&wps, &body, 1.0));
        assert_eq!(f.target(), 14, "the waypoint nearest the body within a metre back");
        assert!(
            f.is_retracing() && !f.retrace(&wps, &body, 1.0),
            "one retrace at a time"
        );
        // Goal by goal round the corner, then mu again.
        let mut body = body;
        let mut t = 0.0;
        while f.target() <= 18 && t < 60.0 {
            assert!(f.is_retracing());
            let c = f.command(&wps, &body, &LIM);
            body.step(c.v, c.w, &LIM, 0.05);
            t += 0.05;
            let along = if body.x <= 4.0 {
                body.y.abs()
            } else {
                body.x.hypot(body.y)
            };
            let up = if body.y >= 0.0 {
                (body.x - 4.0).abs()
            } else {
                (body.x - 4.0).hypot(body.y)
            };
            let off = along.min(up);
            assert!(off < 0.1, "{body:?}");
        }
        assert!(f.target() > 18 && !f.is_retracing(), "{} after {t} s", f.target());
    }
}
