//! Steps along walls: the step between two lane ends that lie on a region's contour follows the contour
//! instead of cutting straight across.
//!
//! Along a straight wall the two are the same. Along a ragged wall (real SLAM maps: bumps, nooks, ray fans)
//! the straight step leaves every nook between the two lane ends uncovered, and each needs a targeted pass
//! later — one that drives the same stretch of wall again, plus the way to it and back. Following the
//! contour covers the nooks on the way for the few extra centimetres the contour is longer. A step follows
//! the contour only when that adds at most [`SLACK_WIDTHS`] tool widths (a step across a bay stays straight).

use std::collections::HashMap;

use crate::geom::{Point2, polyline_length, simplify_polyline};
use crate::space::CoverageSpace;

/// Longest detour (contour length minus straight length) a step takes to follow the contour, tool widths.
pub const SLACK_WIDTHS: f64 = 2.0;

/// A contour at most this much longer than the straight step (plus a cell) counts as a straight wall: the
/// cell staircase of a wall at an angle to the grid is up to 8 % longer than the wall.
const STRAIGHT_WALL: f64 = 1.1;

/// The contour loops of every region, with where each contour cell sits on its loop.
#[derive(Debug, Clone, Default)]
pub struct WallSteps {
    /// Per region, its boundary loops (cells in order) as `trace_cells` gives them.
    contours: Vec<Vec<Vec<usize>>>,
    /// Per loop of three cells or more: its region, its index there, and the arc length from the first cell
    /// to each (metres), with the closing length last.
    loops: Vec<(u32, u32, Vec<f64>)>,
    /// Contour cell → (loop, position): the first time the loop passes the cell.
    at: HashMap<usize, (u32, u32)>,
}

impl WallSteps {
    /// The regions' contours: per region, its boundary loops as `trace_cells` gives them.
    pub fn new(space: &CoverageSpace, contours: Vec<Vec<Vec<usize>>>) -> Self {
        let g = space.geometry();
        let mut out = Self::default();
        for (r, region) in contours.iter().enumerate() {
            for (k, lp) in region.iter().enumerate() {
                if lp.len() < 3 {
                    continue;
                }
                let id = out.loops.len() as u32;
                let mut arc = Vec::with_capacity(lp.len() + 1);
                let mut s = 0.0;
                arc.push(0.0);
                for k in 1..=lp.len() {
                    s += (g.center_of(lp[k % lp.len()]) - g.center_of(lp[k - 1])).norm();
                    arc.push(s);
                }
                for (pos, &c) in lp.iter().enumerate() {
                    out.at.entry(c).or_insert((id, pos as u32));
                }
                out.loops.push((r as u32, k as u32, arc));
            }
        }
        out.contours = contours;
        out
    }

    /// The boundary loops of region `id` (empty for an unknown region).
    pub fn contours(&self, id: usize) -> &[Vec<usize>] {
        self.contours.get(id).map_or(&[], Vec::as_slice)
    }

    /// Contour positions within one cell of `p` (nearest first by cell centre).
    fn near(&self, space: &CoverageSpace, p: Point2) -> Vec<(u32, u32)> {
        let g = space.geometry();
        let Some(c) = g.locate(p) else {
            return Vec::new();
        };
        let mut found: Vec<(f64, (u32, u32))> = Vec::new();
        for dy in -1..=1 {
            for dx in -1..=1 {
                if let Some(n) = g.offset(c, dx, dy)
                    && let Some(&pos) = self.at.get(&g.index(n))
                {
                    found.push(((g.center(n) - p).norm(), pos));
                }
            }
        }
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        found.into_iter().map(|(_, pos)| pos).collect()
    }

    /// The step from `a` to `b` along the contour they both lie on (polyline from `a` to `b`, every segment
    /// keeping clearance), or `None` when they are not on one contour, the contour is more than
    /// [`SLACK_WIDTHS`] longer than the straight step, or it would not keep clearance.
    pub fn along(&self, space: &CoverageSpace, a: Point2, b: Point2) -> Option<Vec<Point2>> {
        let g = space.geometry();
        let straight = (b - a).norm();
        let slack = SLACK_WIDTHS * space.robot.tool_width_m;
        let (pa, pb) = (self.near(space, a), self.near(space, b));
        let (&(la, ia), &(_, ib)) = pa.iter().find_map(|x| pb.iter().find(|y| y.0 == x.0).map(|y| (x, y)))?;
        let (r, k, arc) = &self.loops[la as usize];
        let cells = &self.contours[*r as usize][*k as usize];
        let total = arc[cells.len()];
        let (i, j) = (ia as usize, ib as usize);
        let forward = if j >= i {
            arc[j] - arc[i]
        } else {
            total - (arc[i] - arc[j])
        };
        let backward = total - forward;
        let arc_len = forward.min(backward);
        // A contour hardly longer than the step is a straight wall (its cell staircase): nothing to dip into.
        if arc_len > straight + slack || arc_len <= STRAIGHT_WALL * straight + g.resolution {
            return None;
        }
        let n = cells.len();
        let mut pts = vec![a];
        let mut k = i;
        loop {
            pts.push(g.center_of(cells[k]));
            if k == j {
                break;
            }
            k = if forward <= backward {
                (k + 1) % n
            } else {
                (k + n - 1) % n
            };
        }
        pts.push(b);
        let simple = simplify_polyline(&pts, 0.5 * g.resolution, &|p, q| space.segment_ok(p, q));
        let ok = simple.windows(2).all(|s| space.segment_ok(s[0], s[1]));
        (ok && polyline_length(&simple) <= straight + slack).then_some(simple)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};
    use crate::pattern::contour::trace_cells;
    use crate::space::RobotShape;

    /// 4 m × 3 m at 0.05 m with a nook 0.4 m wide and 0.2 m deep in the bottom wall at x = 2 m.
    fn ragged() -> CoverageSpace {
        let g = GridGeometry::new(80, 60, 0.05, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        grid.fill_rect(0.0, 0.0, 4.0, 0.3, CellState::Occupied);
        grid.fill_rect(1.8, 0.1, 2.2, 0.3, CellState::Free);
        let robot = RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        };
        CoverageSpace::new(grid, robot, Point2::new(1.0, 1.5)).expect("space")
    }

    #[test]
    fn a_step_along_a_ragged_wall_dips_into_the_nook() {
        let space = ragged();
        let g = *space.geometry();
        let cells: Vec<usize> = (0..g.len()).filter(|&i| space.reachable[i]).collect();
        let steps = WallSteps::new(&space, vec![trace_cells(&g, &cells)]);
        // Lane ends on the lowest reachable cells of two columns either side of the nook.
        let lowest = |x: f64| {
            (0..g.height)
                .map(|y| g.center(crate::map::Cell::new((x / 0.05) as usize, y)))
                .find(|&p| g.locate(p).is_some_and(|c| space.reachable[g.index(c)]))
                .expect("a reachable cell")
        };
        let (a, b) = (lowest(1.6), lowest(2.4));
        let deepest = lowest(2.0);
        assert!(deepest.y < a.y - 0.1, "the nook is reachable: {deepest:?} vs {a:?}");
        let path = steps.along(&space, a, b).expect("along the wall");
        assert_eq!(path.first(), Some(&a));
        assert_eq!(path.last(), Some(&b));
        assert!(
            path.iter().any(|p| p.y < a.y - 0.1),
            "the step dips into the nook: {path:?}"
        );
        assert!(path.windows(2).all(|s| space.segment_ok(s[0], s[1])));
        let len = polyline_length(&path);
        let straight = (b - a).norm();
        assert!(
            len > straight + 0.1 && len <= straight + SLACK_WIDTHS * 0.3 + 1e-9,
            "{len}"
        );
        // Points far from every contour get no contour step.
        assert_eq!(steps.along(&space, Point2::new(1.0, 1.5), Point2::new(2.0, 1.5)), None);
    }
}
