//! Excursions: an uncovered pocket close to a task the region drives anyway is covered by a short
//! out-and-back from that task instead of by a task of its own.
//!
//! A pocket (the corner a spiral's rings round off, the nook between two lane ends along a ragged wall, the
//! rim of a post) left to a single visit costs the route a connection from the end of one leg and another to
//! the start of the next — legs end at lane ends and ring starts, often metres from the pocket. The pocket
//! is usually a few centimetres beyond the swath of some lane, ring or frame segment. An [`Excursion`]
//! leaves that segment at the point `at` nearest the uncovered cell, drives straight towards the cell just
//! until the tool reaches it (`end`) and comes back: it costs twice |at end|, often a tenth of a tool
//! width. [`splice`] writes the chosen excursions into their host tasks: as a gentle bump where the host
//! segment is long enough (leave it a few depths before `at`, touch `end`, rejoin as far after: no heading
//! change counts as a turn, and it costs less than the out-and-back), else as the vertices `at, end, at`.

use crate::geom::{Point2, Vector2};
use crate::space::CoverageSpace;

use super::{Task, TaskKind};

/// Farthest an excursion drives from its host segment, in tool widths.
pub const MAX_REACH_WIDTHS: f64 = 1.5;

/// An out-and-back from segment `segment` (vertex `segment` to `segment + 1`) of task `task`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Excursion {
    /// Host task (index among the region's tasks).
    pub task: usize,
    /// Host segment.
    pub segment: usize,
    /// Position of `at` along the segment, 0 … 1.
    pub t: f64,
    /// Where the excursion leaves the host.
    pub at: Point2,
    /// Where it turns back.
    pub end: Point2,
}

impl Excursion {
    /// Length driven (out and back), metres.
    pub fn length(&self) -> f64 {
        2.0 * (self.end - self.at).norm()
    }
}

/// The segments of a region's main-pattern tasks (lanes, rings, frames), bucketed so that the segments near
/// a point are found without scanning the region.
#[derive(Debug, Clone)]
pub struct Hosts {
    origin: Point2,
    bucket_m: f64,
    cols: usize,
    rows: usize,
    /// (task, segment, a, b) per bucket, row-major.
    buckets: Vec<Vec<(usize, usize, Point2, Point2)>>,
}

impl Hosts {
    /// Indexes the lane, ring and frame segments of `tasks` (buckets one [`MAX_REACH_WIDTHS`] wide).
    pub fn new(space: &CoverageSpace, tasks: &[Task]) -> Self {
        let reach_m = MAX_REACH_WIDTHS * space.robot.tool_width_m;
        let segments: Vec<(usize, usize, Point2, Point2)> = tasks
            .iter()
            .enumerate()
            .filter(|(_, t)| matches!(t.kind, TaskKind::Lane | TaskKind::Ring | TaskKind::Frame))
            .flat_map(|(k, t)| t.points.windows(2).enumerate().map(move |(j, s)| (k, j, s[0], s[1])))
            .collect();
        let (mut lo, mut hi) = (Point2::new(f64::MAX, f64::MAX), Point2::new(f64::MIN, f64::MIN));
        for &(_, _, a, b) in &segments {
            lo = Point2::new(lo.x.min(a.x).min(b.x), lo.y.min(a.y).min(b.y));
            hi = Point2::new(hi.x.max(a.x).max(b.x), hi.y.max(a.y).max(b.y));
        }
        let bucket_m = reach_m.max(1e-6);
        if segments.is_empty() {
            return Self {
                origin: Point2::origin(),
                bucket_m,
                cols: 0,
                rows: 0,
                buckets: Vec::new(),
            };
        }
        let cols = ((hi.x - lo.x) / bucket_m).floor() as usize + 1;
        let rows = ((hi.y - lo.y) / bucket_m).floor() as usize + 1;
        let mut buckets = vec![Vec::new(); cols * rows];
        let clamp = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
        for s in segments {
            let (a, b) = (s.2, s.3);
            // Every bucket of the segment's bounding box: lanes are long and straight, so walk along it.
            let len = (b - a).norm();
            let n = (len / bucket_m).ceil().max(1.0) as usize;
            let mut last = usize::MAX;
            for k in 0..=n {
                let p = a + (b - a) * (k as f64 / n as f64);
                let c = clamp((p.x - lo.x) / bucket_m, cols);
                let r = clamp((p.y - lo.y) / bucket_m, rows);
                let i = r * cols + c;
                if i != last {
                    buckets[i].push(s);
                    last = i;
                }
            }
        }
        Self {
            origin: lo,
            bucket_m,
            cols,
            rows,
            buckets,
        }
    }

    /// Segments indexed in the buckets within `radius` of `p` (a segment may come more than once).
    fn near(&self, p: Point2, radius: f64) -> impl Iterator<Item = &(usize, usize, Point2, Point2)> {
        let span = (radius / self.bucket_m).ceil() as isize + 1;
        let c = ((p.x - self.origin.x) / self.bucket_m).floor() as isize;
        let r = ((p.y - self.origin.y) / self.bucket_m).floor() as isize;
        let (cols, rows) = (self.cols as isize, self.rows as isize);
        (r - span..=r + span)
            .filter(move |&y| y >= 0 && y < rows)
            .flat_map(move |y| {
                (c - span..=c + span)
                    .filter(move |&x| x >= 0 && x < cols)
                    .map(move |x| (y * cols + x) as usize)
            })
            .flat_map(move |i| self.buckets[i].iter())
    }

    /// The shortest excursion that brings the tool within its half width of `target` (an uncovered cell's
    /// centre): from the nearest point of a host segment within [`MAX_REACH_WIDTHS`], straight towards the
    /// target, with clearance all the way. `None` when no host is near enough or the way is blocked.
    pub fn excursion_to(&self, space: &CoverageSpace, target: Point2) -> Option<Excursion> {
        let half = space.robot.tool_width_m / 2.0;
        let reach = MAX_REACH_WIDTHS * space.robot.tool_width_m;
        let mut best: Option<Excursion> = None;
        let mut best_d = f64::INFINITY;
        for &(task, segment, a, b) in self.near(target, reach + half) {
            let ab: Vector2 = b - a;
            let len2 = ab.norm_squared();
            let t = if len2 > 0.0 {
                ((target - a).dot(&ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let at = a + ab * t;
            let to = target - at;
            let dist = to.norm();
            // Drive until the target is a hair inside the half width.
            let drive = (dist - half + 1e-6).max(0.0);
            if drive > reach || drive >= best_d || dist <= 0.0 {
                continue;
            }
            let end = at + to * (drive / dist);
            if space.segment_ok(at, end) {
                best_d = drive;
                best = Some(Excursion {
                    task,
                    segment,
                    t,
                    at,
                    end,
                });
            }
        }
        best
    }
}

/// A gentle detour instead of an out-and-back: leave the host `span` (from the last vertex written to the
/// segment's end) at `from`, a few times the excursion's depth before `at`, touch `end`, rejoin at `to` as
/// far after it; every heading change stays below the 30° that counts as a turn. `None` when the span is
/// too short or the detour would lose clearance.
fn bump(space: &CoverageSpace, (a, b): (Point2, Point2), e: &Excursion) -> Option<(Point2, Point2)> {
    let depth = (e.end - e.at).norm();
    let len = (b - a).norm();
    if len < 1e-9 {
        return None;
    }
    let u = (b - a) / len;
    let along = (e.at - a).dot(&u);
    // tan(7.5°) ≈ 0.13: the apex turns by 15°, each end by 7.5°.
    let run = depth / 0.13;
    if along < run - 1e-9 || len - along < run - 1e-9 {
        return None;
    }
    let (from, to) = (e.at - u * run, e.at + u * run);
    (space.segment_ok(from, e.end) && space.segment_ok(e.end, to)).then_some((from, to))
}

/// Writes `excursions` into their host tasks among `tasks` (in order along each segment). Returns the
/// length they add to the tasks, metres.
pub fn splice(space: &CoverageSpace, tasks: &mut [Task], mut excursions: Vec<Excursion>) -> f64 {
    excursions.sort_by(|a, b| (a.task, a.segment).cmp(&(b.task, b.segment)).then(a.t.total_cmp(&b.t)));
    let mut added: f64 = excursions.iter().map(Excursion::length).sum();
    let mut next = excursions.iter().peekable();
    while let Some(&&first) = next.peek() {
        let k = first.task;
        let old = std::mem::take(&mut tasks[k].points);
        let mut pts = Vec::with_capacity(old.len() + 3);
        for (j, &a) in old.iter().enumerate() {
            pts.push(a);
            let b = old.get(j + 1).copied().unwrap_or(a);
            while let Some(e) = next.next_if(|e| e.task == k && e.segment == j) {
                let last = *pts.last().unwrap_or(&a);
                if let Some((from, to)) = bump(space, (last, b), e) {
                    if (from - last).norm() > 1e-9 {
                        pts.push(from);
                    }
                    pts.push(e.end);
                    pts.push(to);
                    added += (e.end - from).norm() + (to - e.end).norm() - (to - from).norm() - e.length();
                    continue;
                }
                if (e.at - last).norm() > 1e-9 {
                    pts.push(e.at);
                }
                pts.push(e.end);
                pts.push(e.at);
            }
        }
        // Excursions naming a segment the task does not have (none are made that way) are dropped.
        while next.next_if(|e| e.task == k).is_some() {}
        tasks[k].points = pts;
    }
    added
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::space::RobotShape;

    /// 4 m × 3 m at 0.1 m, robot radius and half tool width 0.2 m, a wall at x = 2 m from the floor to 2 m.
    fn room() -> CoverageSpace {
        let g = GridGeometry::new(40, 30, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        for y in 0..20 {
            grid.cells[y * 40 + 20] = CellState::Occupied;
        }
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        CoverageSpace::new(grid, robot, Point2::new(0.5, 0.5)).expect("space")
    }

    fn task(points: &[(f64, f64)], kind: TaskKind) -> Task {
        Task {
            points: points.iter().map(|&(x, y)| Point2::new(x, y)).collect(),
            kind,
        }
    }

    #[test]
    fn excursion_stops_where_the_tool_reaches_the_target() {
        let space = room();
        let tasks = vec![task(&[(0.5, 1.0), (1.5, 1.0)], TaskKind::Lane)];
        let hosts = Hosts::new(&space, &tasks);
        let e = hosts.excursion_to(&space, Point2::new(1.2, 1.5)).expect("in reach");
        assert_eq!((e.task, e.segment), (0, 0));
        assert!((e.at - Point2::new(1.2, 1.0)).norm() < 1e-9);
        // 0.5 m away, half width 0.2 m: drive 0.3 m.
        assert!((e.end - Point2::new(1.2, 1.3)).norm() < 1e-5, "{e:?}");
        assert!((e.length() - 0.6).abs() < 1e-5);
        // Beyond the lane's end the excursion leaves from the end.
        let e = hosts.excursion_to(&space, Point2::new(1.9, 1.0)).expect("in reach");
        assert!((e.at - Point2::new(1.5, 1.0)).norm() < 1e-9 && e.t == 1.0);
    }

    #[test]
    fn no_excursion_through_a_wall_or_out_of_reach() {
        let space = room();
        let tasks = vec![task(&[(1.5, 0.5), (1.5, 1.5)], TaskKind::Lane)];
        let hosts = Hosts::new(&space, &tasks);
        // Behind the wall at x = 2 m.
        assert_eq!(hosts.excursion_to(&space, Point2::new(2.6, 1.0)), None);
        // 1.5 tool widths (0.6 m) of driving is the limit.
        assert!(hosts.excursion_to(&space, Point2::new(1.5, 2.25)).is_some());
        assert_eq!(hosts.excursion_to(&space, Point2::new(1.5, 2.4)), None);
        // Visits and passes are no hosts.
        let visits = vec![
            task(&[(1.0, 1.0)], TaskKind::Visit),
            task(&[(1.0, 1.0), (1.0, 1.2)], TaskKind::Boundary),
        ];
        assert_eq!(
            Hosts::new(&space, &visits).excursion_to(&space, Point2::new(1.0, 1.5)),
            None
        );
    }

    #[test]
    fn long_hosts_get_a_gentle_bump_instead_of_a_reversal() {
        let space = room();
        let mut tasks = vec![task(&[(0.3, 2.5), (3.5, 2.5)], TaskKind::Lane)];
        let hosts = Hosts::new(&space, &tasks);
        let e = hosts.excursion_to(&space, Point2::new(1.5, 2.8)).expect("in reach");
        let out_and_back = e.length();
        let added = splice(&space, &mut tasks, vec![e]);
        let p = &tasks[0].points;
        assert_eq!(p.len(), 5, "{p:?}");
        assert!((p[2] - e.end).norm() < 1e-12);
        assert_eq!(crate::metrics::count_turns(p), 0, "{p:?}");
        assert!(added > 0.0 && added < out_and_back, "{added} vs {out_and_back}");
        assert!((added - (crate::geom::polyline_length(p) - 3.2)).abs() < 1e-9);
        assert!(p.windows(2).all(|s| space.segment_ok(s[0], s[1])));
    }

    #[test]
    fn splices_keep_segment_order_and_closed_loops_closed() {
        let space = room();
        let ring = [(0.5, 0.5), (1.5, 0.5), (1.5, 1.5), (0.5, 1.5), (0.5, 0.5)];
        let mut tasks = vec![task(&ring, TaskKind::Ring)];
        let hosts = Hosts::new(&space, &tasks);
        // Inside the ring's swath, 0.25 m from the first side and 0.3 m from the next.
        let far = hosts
            .excursion_to(&space, Point2::new(1.2, 0.75))
            .expect("from the first side");
        let near = hosts
            .excursion_to(&space, Point2::new(0.8, 0.75))
            .expect("from the first side");
        assert_eq!((far.segment, near.segment), (0, 0));
        let added = splice(&space, &mut tasks, vec![far, near]);
        assert!((added - far.length() - near.length()).abs() < 1e-12);
        let p = &tasks[0].points;
        assert!(tasks[0].is_closed());
        assert_eq!(p.len(), 11);
        assert!((p[1] - near.at).norm() < 1e-9 && (p[2] - near.end).norm() < 1e-9);
        assert!((p[4] - far.at).norm() < 1e-9 && (p[5] - far.end).norm() < 1e-9);
        assert!(p.windows(2).all(|s| space.segment_ok(s[0], s[1])));
    }
}
