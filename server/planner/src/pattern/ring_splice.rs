//! Connected rings: the closed rings of a spiral spliced into as few loops as possible.
//!
//! Driven one by one, nested rings make the robot go in and out: after the innermost ring of one lobe the
//! way to the next lobe runs back across every ring already swept, and every room reached through a door or
//! ring round an obstacle's inside costs such a trip. Following the connected spirals of layered
//! fabrication (Zhao et al., "Connected Fermat Spirals", 2016), two rings that run side by side about a tool
//! width apart are spliced where they do: the loop leaves ring A at vertex `a`, steps across to the nearest
//! vertex `c` of ring B, drives B all the way round to the vertex `c'` next to `c`, and steps back to `a'`,
//! the vertex after `a` on A. The segments `a a'` and `c' c` are not driven; the two steps, one tool width
//! or so apart, sweep the strip between the rings instead. Splices are chosen cheapest first along a
//! spanning forest of the rings (union-find, every ring segment used by at most one splice), so every ring
//! is still driven once and no trip goes back over swept ground.
//!
//! The spliced loop is handed to the router in pieces of [`PIECE_WIDTHS`] tool widths, open tasks whose
//! ends meet: the sweep order chains them at no cost, and targeted passes can be inserted between two pieces
//! instead of only before or after one loop round the whole region.

use std::collections::HashMap;

use super::{Task, TaskKind};
use crate::geom::{Point2, segments_cross};
use crate::space::CoverageSpace;

/// Rings are spliced where their vertices lie at most this many tool widths apart.
const SPLICE_REACH_WIDTHS: f64 = 1.5;

/// Length of the open pieces a spliced loop is cut into, in tool widths.
pub const PIECE_WIDTHS: f64 = 16.0;

/// One ring vertex, by ring and position.
#[derive(Debug, Clone, Copy)]
struct At {
    ring: usize,
    vertex: usize,
}

/// A way across between segment `seg` of ring `a` (vertices `seg`, `seg + 1`) and the segment of ring `b`
/// whose vertices `b_near_first` and `b_near_second` lie next to them.
#[derive(Debug, Clone, Copy)]
struct Splice {
    cost: f64,
    a: usize,
    seg: usize,
    b: usize,
    b_near_first: usize,
    b_near_second: usize,
}

/// Where a ring segment crosses to another ring: the other ring and its vertices next to the segment's
/// first and second vertex.
type Crossings = HashMap<(usize, usize), (usize, usize, usize)>;

/// `tasks` (a spiral's rings) with their closed rings spliced into connected loops, each cut into open
/// pieces of about [`PIECE_WIDTHS`] tool widths; open tasks and rings that splice with nothing are kept as
/// they are. Every new step keeps the robot's clearance.
pub fn splice_rings(space: &CoverageSpace, tasks: Vec<Task>) -> Vec<Task> {
    let w = space.robot.tool_width_m;
    let (rings, mut out): (Vec<Task>, Vec<Task>) = tasks.into_iter().partition(|t| t.is_closed() && t.points.len() > 3);
    let verts: Vec<&[Point2]> = rings.iter().map(|t| &t.points[..t.points.len() - 1]).collect();
    let splices = choose(space, &verts, SPLICE_REACH_WIDTHS * w);
    let mut crossings: Crossings = HashMap::new();
    let mut linked = vec![false; verts.len()];
    for s in &splices {
        crossings.insert((s.a, s.seg), (s.b, s.b_near_first, s.b_near_second));
        let m = verts[s.b].len();
        // The same crossing seen from ring b: its segment in canonical order (first vertex, first + 1).
        let (b_seg, a_first, a_second) = if (s.b_near_first + 1) % m == s.b_near_second {
            (s.b_near_first, s.seg, (s.seg + 1) % verts[s.a].len())
        } else {
            (s.b_near_second, (s.seg + 1) % verts[s.a].len(), s.seg)
        };
        crossings.insert((s.b, b_seg), (s.a, a_first, a_second));
        (linked[s.a], linked[s.b]) = (true, true);
    }
    let mut done = vec![false; verts.len()];
    for root in 0..verts.len() {
        if done[root] {
            continue;
        }
        if !linked[root] {
            done[root] = true;
            out.push(rings[root].clone());
            continue;
        }
        let looped = walk(&verts, &crossings, root, &mut done);
        out.extend(cut(&looped, PIECE_WIDTHS * w));
    }
    out
}

/// The splices of a spanning forest of the rings, cheapest first: per ring segment and other ring, the
/// cheapest way across.
fn choose(space: &CoverageSpace, verts: &[&[Point2]], reach: f64) -> Vec<Splice> {
    let bucket = reach.max(1e-6);
    let key = |p: Point2| ((p.x / bucket).floor() as i64, (p.y / bucket).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<At>> = HashMap::new();
    for (ring, vs) in verts.iter().enumerate() {
        for (vertex, &p) in vs.iter().enumerate() {
            grid.entry(key(p)).or_default().push(At { ring, vertex });
        }
    }
    let mut candidates: Vec<Splice> = Vec::new();
    for (a, va) in verts.iter().enumerate() {
        let ma = va.len();
        for seg in 0..ma {
            let (p, q) = (va[seg], va[(seg + 1) % ma]);
            let (kx, ky) = key(p);
            let mut best: HashMap<usize, Splice> = HashMap::new();
            for cell in (kx - 1..=kx + 1).flat_map(|x| (ky - 1..=ky + 1).map(move |y| (x, y))) {
                for near in grid.get(&cell).into_iter().flatten() {
                    // Each pair of rings once, from its lower index.
                    if near.ring <= a || (verts[near.ring][near.vertex] - p).norm() > reach {
                        continue;
                    }
                    let vb = verts[near.ring];
                    let mb = vb.len();
                    for other in [(near.vertex + 1) % mb, (near.vertex + mb - 1) % mb] {
                        let (c, c2) = (vb[near.vertex], vb[other]);
                        if (c2 - q).norm() > reach || segments_cross(p, c, q, c2) {
                            continue;
                        }
                        let cost = (c - p).norm() + (c2 - q).norm() - (q - p).norm() - (c2 - c).norm();
                        if best.get(&near.ring).is_some_and(|s| s.cost <= cost) {
                            continue;
                        }
                        best.insert(
                            near.ring,
                            Splice {
                                cost,
                                a,
                                seg,
                                b: near.ring,
                                b_near_first: near.vertex,
                                b_near_second: other,
                            },
                        );
                    }
                }
            }
            candidates.extend(best.into_values());
        }
    }
    // Cheapest first; ties broken by position so the plan does not depend on hash order.
    candidates.sort_by(|x, y| {
        x.cost
            .total_cmp(&y.cost)
            .then((x.a, x.seg, x.b, x.b_near_first).cmp(&(y.a, y.seg, y.b, y.b_near_first)))
    });
    let mut parent: Vec<usize> = (0..verts.len()).collect();
    let mut used: std::collections::HashSet<(usize, usize)> = std::collections::HashSet::new();
    let mut chosen = Vec::new();
    for s in candidates {
        let mb = verts[s.b].len();
        let b_seg = if (s.b_near_first + 1) % mb == s.b_near_second {
            s.b_near_first
        } else {
            s.b_near_second
        };
        if find(&mut parent, s.a) == find(&mut parent, s.b)
            || used.contains(&(s.a, s.seg))
            || used.contains(&(s.b, b_seg))
        {
            continue;
        }
        // Clearance is checked only for splices the forest would take (most candidates never are).
        let (va, vb) = (verts[s.a], verts[s.b]);
        let (p, q) = (va[s.seg], va[(s.seg + 1) % va.len()]);
        if !space.segment_ok(p, vb[s.b_near_first]) || !space.segment_ok(q, vb[s.b_near_second]) {
            continue;
        }
        union(&mut parent, s.a, s.b);
        used.insert((s.a, s.seg));
        used.insert((s.b, b_seg));
        chosen.push(s);
    }
    chosen
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

/// One ring being driven: where it is, which way it goes, how many segments are left, and whether the
/// crossing on the next segment has been driven already.
struct Frame {
    ring: usize,
    at: usize,
    forward: bool,
    left: usize,
    crossed: bool,
}

/// The closed loop through `root` and every ring spliced to it (depth first, without recursion), marking
/// them `done`.
fn walk(verts: &[&[Point2]], crossings: &Crossings, root: usize, done: &mut [bool]) -> Vec<Point2> {
    let mut out = vec![verts[root][0]];
    done[root] = true;
    let mut stack = vec![Frame {
        ring: root,
        at: 0,
        forward: true,
        left: verts[root].len(),
        crossed: false,
    }];
    while let Some(f) = stack.last_mut() {
        if f.left == 0 {
            stack.pop();
            continue;
        }
        let m = verts[f.ring].len();
        let next = if f.forward { (f.at + 1) % m } else { (f.at + m - 1) % m };
        let seg = if f.forward { f.at } else { next };
        if !f.crossed
            && let Some(&(other, near_first, near_second)) = crossings.get(&(f.ring, seg))
            && !done[other]
        {
            f.crossed = true;
            let (entry, exit) = if f.forward {
                (near_first, near_second)
            } else {
                (near_second, near_first)
            };
            let mo = verts[other].len();
            // Round the other ring the long way: away from the vertex it leaves by.
            let forward = (entry + 1) % mo != exit;
            done[other] = true;
            out.push(verts[other][entry]);
            stack.push(Frame {
                ring: other,
                at: entry,
                forward,
                left: mo - 1,
                crossed: false,
            });
            continue;
        }
        f.crossed = false;
        f.at = next;
        f.left -= 1;
        out.push(verts[f.ring][next]);
    }
    out
}

/// `looped` (a closed polyline) cut into open pieces of about `piece_m` whose ends meet.
fn cut(looped: &[Point2], piece_m: f64) -> Vec<Task> {
    let mut pieces = Vec::new();
    let mut piece = vec![looped[0]];
    let mut len = 0.0;
    for s in looped.windows(2) {
        len += (s[1] - s[0]).norm();
        piece.push(s[1]);
        if len >= piece_m {
            pieces.push(std::mem::replace(&mut piece, vec![s[1]]));
            len = 0.0;
        }
    }
    if piece.len() > 1 {
        pieces.push(piece);
    }
    pieces
        .into_iter()
        .map(|points| Task {
            points,
            kind: TaskKind::Ring,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::metrics::{CoverageRaster, coverage_of};
    use crate::pattern::WholeRegion;
    use crate::pattern::spiral::plan_rings;
    use crate::space::RobotShape;

    /// 6 m × 4 m at 0.1 m, tool 0.4 m: a free-standing post in the middle, and a wall at x = 3 m from the
    /// floor up to 3 m (a door above it), so rings run round the post, through the door and along both
    /// sides of the wall.
    fn site() -> CoverageSpace {
        let g = GridGeometry::new(60, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(0.0, 0.0, 6.0, 0.1, CellState::Occupied);
        grid.fill_rect(0.0, 3.9, 6.0, 4.0, CellState::Occupied);
        grid.fill_rect(0.0, 0.0, 0.1, 4.0, CellState::Occupied);
        grid.fill_rect(5.9, 0.0, 6.0, 4.0, CellState::Occupied);
        grid.fill_rect(2.9, 0.0, 3.1, 3.0, CellState::Occupied);
        grid.fill_rect(1.2, 1.5, 1.6, 2.1, CellState::Occupied);
        let robot = RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        };
        CoverageSpace::new(grid, robot, Point2::new(0.5, 0.5)).expect("space")
    }

    fn rings(space: &CoverageSpace) -> Vec<Task> {
        plan_rings(space, WholeRegion::new(space).view())
    }

    fn covered_pct(space: &CoverageSpace, tasks: &[Task]) -> f64 {
        let mut raster = CoverageRaster::new(*space.geometry(), space.robot.tool_width_m / 2.0);
        for t in tasks {
            raster.stamp_polyline(&t.points);
        }
        coverage_of(space, &raster, 1.0).coverage_pct
    }

    #[test]
    fn nested_rings_become_one_chain_of_pieces_that_keeps_clearance_and_coverage() {
        let space = site();
        let rings = rings(&space);
        let closed = rings.iter().filter(|t| t.is_closed()).count();
        assert!(closed >= 4, "{closed} closed rings");
        let ring_m: f64 = rings.iter().map(Task::length).sum();
        let spliced = splice_rings(&space, rings.clone());
        // The closed rings are gone: one loop, cut into open pieces whose ends meet, round to the start.
        assert!(spliced.iter().all(|t| !t.is_closed()), "every ring spliced in");
        let pieces: Vec<&Task> = spliced
            .iter()
            .filter(|t| !rings.iter().any(|r| r.points == t.points))
            .collect();
        assert!(pieces.len() >= 2);
        for w in pieces.windows(2) {
            assert_eq!(w[0].points.last(), w[1].points.first(), "pieces chain");
        }
        assert_eq!(
            pieces[pieces.len() - 1].points.last(),
            pieces[0].points.first(),
            "the loop closes"
        );
        for t in &spliced {
            for s in t.points.windows(2) {
                assert!(space.segment_ok(s[0], s[1]), "segment {s:?} loses clearance");
            }
        }
        // Every ring vertex is still driven, the splices add little length, and what is swept barely moves.
        let driven: Vec<Point2> = spliced.iter().flat_map(|t| t.points.iter().copied()).collect();
        for r in &rings {
            for p in &r.points {
                assert!(driven.contains(p), "vertex {p:?} dropped");
            }
        }
        let spliced_m: f64 = spliced.iter().map(Task::length).sum();
        let w = space.robot.tool_width_m;
        assert!(
            spliced_m < ring_m + w * closed as f64,
            "{spliced_m} m vs rings {ring_m} m"
        );
        let (before, after) = (covered_pct(&space, &rings), covered_pct(&space, &spliced));
        assert!(after > before - 1.0, "coverage {before} → {after}");
    }

    #[test]
    fn rings_too_far_apart_stay_as_they_are() {
        let space = site();
        let far = |x: f64| Task {
            points: [(x, 0.5), (x + 0.4, 0.5), (x + 0.4, 0.9), (x, 0.9), (x, 0.5)]
                .iter()
                .map(|&(x, y)| Point2::new(x, y))
                .collect(),
            kind: TaskKind::Ring,
        };
        let tasks = vec![far(0.5), far(3.5)];
        assert_eq!(splice_rings(&space, tasks.clone()), tasks);
    }

    #[test]
    fn crossing_steps_are_detected() {
        let p = |x: f64, y: f64| Point2::new(x, y);
        assert!(segments_cross(p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0), p(1.0, 0.0)));
        assert!(!segments_cross(p(0.0, 0.0), p(1.0, 0.0), p(0.0, 1.0), p(1.0, 1.0)));
        assert!(
            !segments_cross(p(0.0, 0.0), p(1.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)),
            "touching ends"
        );
    }
}
