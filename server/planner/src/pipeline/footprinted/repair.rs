//! Making a disc plan footprint-feasible: drive it as planned wherever the footprint is clear, and bridge
//! every stretch where it is not with a lattice path ([`crate::footprint::lattice`]).
//!
//! The plan is walked station by station (every quarter cell along each segment at the segment's heading;
//! the turn in place at each vertex). Where a station is blocked — the polygon overlaps a blocked cell at
//! that heading, or the turn to it is — the walk stops at the last clear station and a bridge is searched
//! to a later station, trying in order: the first clear station after the blockage; the first station there
//! where the robot turns freely; the same two from the last point behind where the robot turned freely (the
//! path is cut back to it, e.g. a lane end too close to a wall for the body to turn); then stations beyond
//! further blockages, and at last the dock. What the bridge skips is not covered (the metrics count it).

use crate::error::{PlannerError, Result};
use crate::footprint::lattice::{LatticeParams, connect};
use crate::footprint::poses::segment_heading;
use crate::footprint::{FOOTPRINT_FIELD, FootprintCheck};
use crate::geom::Point2;
use crate::pipeline::{Waypoint, WaypointKind};

/// What the repair did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RepairStats {
    /// Stretches replaced by lattice paths.
    pub bridges: usize,
    /// Length of those lattice paths, metres.
    pub bridge_m: f64,
    /// Length of the planned path they replaced (not driven), metres.
    pub skipped_m: f64,
    /// Lattice searches run (including the straight shots they start with).
    pub searches: usize,
}

/// A station: sample `j` of segment `s`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct At {
    s: usize,
    j: usize,
}

/// Searches beyond the first four targets that are tried before the dock.
const FARTHER_TARGETS: usize = 3;
/// Expansions for a bridge to a station where the robot cannot turn freely (it is often boxed in: a lane
/// end a body length from a wall can only be reached along the lane).
const SMALL_BUDGET: usize = 6_000;
/// How far back along the repaired path a point where the robot turns freely is looked for, metres.
const BACK_M: f64 = 15.0;

struct Walk<'a, 'c> {
    check: &'a FootprintCheck<'c>,
    /// The planned path, consecutive repeats dropped.
    orig: Vec<Waypoint>,
    /// Heading and sample count of each segment.
    seg: Vec<(f64, usize)>,
    lattice: LatticeParams,
    out: Vec<Waypoint>,
    /// Heading of the robot at the end of `out` (`None` at the dock before it moved).
    yaw: Option<f64>,
    stats: RepairStats,
}

/// Repairs `path` (a plan from the dock back to it) for the footprint `check` decides (with its margin).
pub fn repair(
    check: &FootprintCheck<'_>,
    path: &[Waypoint],
    lattice: &LatticeParams,
) -> Result<(Vec<Waypoint>, RepairStats)> {
    let mut orig: Vec<Waypoint> = Vec::with_capacity(path.len());
    for w in path {
        if orig
            .last()
            .is_none_or(|l: &Waypoint| (w.position - l.position).norm() > 1e-9)
        {
            orig.push(*w);
        }
    }
    let Some(&first) = orig.first() else {
        return Ok((Vec::new(), RepairStats::default()));
    };
    let spacing = check.sample_spacing_m();
    let seg = orig
        .windows(2)
        .map(|w| {
            let h = segment_heading(w[0].position, w[1].position).unwrap_or(0.0);
            let m = ((w[1].position - w[0].position).norm() / spacing).ceil().max(1.0) as usize;
            (h, m)
        })
        .collect();
    let mut walk = Walk {
        check,
        orig,
        seg,
        lattice: *lattice,
        out: vec![first],
        yaw: None,
        stats: RepairStats::default(),
    };
    walk.run()?;
    Ok((walk.out, walk.stats))
}

impl Walk<'_, '_> {
    fn pos(&self, at: At) -> Point2 {
        let (a, b) = (self.orig[at.s].position, self.orig[at.s + 1].position);
        a + (b - a) * (at.j as f64 / self.seg[at.s].1 as f64)
    }

    fn heading(&self, at: At) -> f64 {
        self.seg[at.s].0
    }

    fn clear(&self, at: At) -> bool {
        let p = self.pos(at);
        self.check.pose_free(p.x, p.y, self.heading(at))
    }

    fn next(&self, at: At) -> Option<At> {
        if at.j < self.seg[at.s].1 {
            Some(At { s: at.s, j: at.j + 1 })
        } else if at.s + 1 < self.seg.len() {
            Some(At { s: at.s + 1, j: 1 })
        } else {
            None
        }
    }

    /// The last station of the path (the dock).
    fn end(&self) -> At {
        let s = self.seg.len() - 1;
        At { s, j: self.seg[s].1 }
    }

    /// The waypoint a station becomes when the path is cut there (the kind of the segment it lies on).
    fn waypoint(&self, at: At) -> Waypoint {
        Waypoint {
            position: self.pos(at),
            ..self.orig[at.s + 1]
        }
    }

    fn run(&mut self) -> Result<()> {
        if self.seg.is_empty() {
            return Ok(());
        }
        let mut at = At { s: 0, j: 0 };
        loop {
            let p = self.pos(at);
            let h = self.heading(at);
            let turned = match self.yaw {
                None => self.check.pose_free(p.x, p.y, h),
                Some(y) => self.check.rotation_free(p.x, p.y, y, h),
            };
            let blocked = if turned {
                match self.first_blocked_after(at) {
                    None => {
                        self.out.push(self.orig[at.s + 1]);
                        self.yaw = Some(h);
                        if at.s + 1 == self.seg.len() {
                            return Ok(());
                        }
                        at = At { s: at.s + 1, j: 0 };
                        continue;
                    }
                    Some(b) => {
                        let last = At { s: b.s, j: b.j - 1 };
                        if last.j > at.j {
                            self.out.push(self.waypoint(last));
                        }
                        self.yaw = Some(h);
                        b
                    }
                }
            } else {
                at
            };
            match self.bridge(blocked)? {
                Some(b) if b == self.end() => return Ok(()),
                Some(b) if b.j == self.seg[b.s].1 => at = At { s: b.s + 1, j: 0 },
                Some(b) => at = b,
                None => return Ok(()),
            }
        }
    }

    /// The first blocked station on `at`'s segment after it, if any (samples with clearance to spare leap).
    fn first_blocked_after(&self, at: At) -> Option<At> {
        let m = self.seg[at.s].1;
        let (a, b) = (self.orig[at.s].position, self.orig[at.s + 1].position);
        let h = self.heading(at);
        let spacing = (b - a).norm() / m as f64;
        let mut j = at.j + 1;
        while j <= m {
            let p = a + (b - a) * (j as f64 / m as f64);
            let spare = self.check.spare_m(p);
            if spare >= 0.0 {
                j += ((spare / spacing).floor() as usize).max(1);
                continue;
            }
            if !self.check.pose_free(p.x, p.y, h) {
                return Some(At { s: at.s, j });
            }
            j += 1;
        }
        None
    }

    /// The first station at or after `from` for which `want` holds.
    fn find(&self, from: At, want: impl Fn(&Self, At) -> bool) -> Option<At> {
        let mut at = from;
        loop {
            if want(self, at) {
                return Some(at);
            }
            at = self.next(at)?;
        }
    }

    fn turns_freely(&self, at: At) -> bool {
        self.check.turns_freely(self.pos(at))
    }

    /// Bridges the blockage at station `blocked`: pushes the lattice path and returns the station it reaches
    /// (`None`: the path ends where it is, which only the dock may do).
    fn bridge(&mut self, blocked: At) -> Result<Option<At>> {
        let end = self.end();
        let first_clear = self.find(blocked, |w, a| w.clear(a));
        let first_free = self.find(blocked, |w, a| w.turns_freely(a));
        let mut targets: Vec<(At, bool)> = Vec::new();
        if let Some(b) = first_clear {
            targets.push((b, self.turns_freely(b)));
        }
        if let Some(b) = first_free
            && Some(b) != first_clear
        {
            targets.push((b, true));
        }
        // Beyond the next blockages: the first station past each where the robot turns freely.
        let mut from = first_free;
        for _ in 0..FARTHER_TARGETS {
            let Some(b) = from
                .and_then(|f| self.find(f, |w, a| !w.turns_freely(a)))
                .and_then(|x| self.find(x, |w, a| w.turns_freely(a)))
            else {
                break;
            };
            targets.push((b, true));
            from = Some(b);
        }
        if targets.last().is_none_or(|t| t.0 != end) {
            targets.push((end, true));
        }
        // Sources: where the robot stands, then the last point behind it where it turns freely.
        let here = (self.out.len(), self.yaw);
        let back = self.last_free_behind();
        for &(target, open) in &targets {
            let sources: &[Option<(usize, Point2, Option<f64>)>] =
                &[Some((here.0, self.out[here.0 - 1].position, here.1)), back];
            for source in sources.iter().flatten() {
                let (keep, from_p, from_yaw) = *source;
                let to_yaw = (target != end).then(|| self.heading(target));
                let mut params = self.lattice;
                if !open {
                    params.max_expansions = params.max_expansions.min(SMALL_BUDGET);
                }
                self.stats.searches += 1;
                let Some(bridge) = connect(self.check, from_p, from_yaw, self.pos(target), to_yaw, &params) else {
                    continue;
                };
                self.commit(keep, from_p, &bridge, blocked, target);
                return Ok(Some(target));
            }
        }
        Err(PlannerError::InvalidParam {
            name: FOOTPRINT_FIELD,
            reason: format!(
                "the robot cannot get back to its start from ({:.2}, {:.2}): no clear way for its footprint",
                self.out[here.0 - 1].position.x,
                self.out[here.0 - 1].position.y
            ),
        })
    }

    /// The repaired path cut back to its first `keep` waypoints and the point `from` (on the segment after
    /// them), then the bridge to station `target`.
    fn commit(&mut self, keep: usize, from: Point2, bridge: &[Point2], blocked: At, target: At) {
        let mut cut_m = 0.0;
        if keep < self.out.len() {
            let tail: f64 = self.out[keep - 1..]
                .windows(2)
                .map(|w| (w[1].position - w[0].position).norm())
                .sum();
            let base = self.out[keep - 1].position;
            cut_m = tail - (from - base).norm();
            let on = self.out[keep];
            self.out.truncate(keep);
            if (from - base).norm() > 1e-9 {
                self.out.push(Waypoint { position: from, ..on });
            }
        }
        for &p in &bridge[1..] {
            self.out.push(Waypoint {
                position: p,
                kind: WaypointKind::Transit,
                region: None,
            });
        }
        self.yaw = if target == self.end() {
            None
        } else {
            Some(self.heading(target))
        };
        self.stats.bridges += 1;
        self.stats.bridge_m += crate::geom::polyline_length(bridge);
        self.stats.skipped_m += self.arc(blocked, target) + cut_m.max(0.0);
    }

    /// Arc length of the planned path from station `a` to station `b`, metres.
    fn arc(&self, a: At, b: At) -> f64 {
        let mut len = 0.0;
        let mut at = a;
        while at < b {
            let Some(n) = self.next(at) else { break };
            len += (self.pos(n) - self.pos(at)).norm();
            at = n;
        }
        len
    }

    /// The last point of the repaired path, within [`BACK_M`] behind its end, where the robot turns freely:
    /// (waypoints kept before it, the point, the heading there). `None` when that is the end itself or none.
    fn last_free_behind(&self) -> Option<(usize, Point2, Option<f64>)> {
        let spacing = self.check.sample_spacing_m();
        let mut walked = 0.0;
        for k in (1..self.out.len()).rev() {
            let (a, b) = (self.out[k - 1].position, self.out[k].position);
            let len = (b - a).norm();
            let m = (len / spacing).ceil().max(1.0) as usize;
            let h = segment_heading(a, b);
            for j in (0..m).rev() {
                let p = a + (b - a) * (j as f64 / m as f64);
                if self.check.turns_freely(p) {
                    return Some((k, p, h));
                }
            }
            walked += len;
            if walked > BACK_M {
                break;
            }
        }
        None
    }
}
