//! The frame of a region: its contour where it meets walls and obstacles, driven once at the robot's
//! clearance so that the wall band — scallops between lane ends, ragged walls of real maps, rims of round
//! obstacles — is covered in one continuous pass instead of many targeted ones.
//!
//! A region's contour cells are its outermost reachable cells; the stretches of the contour whose cells touch
//! unreachable space (a wall) form the frame, and the stretches along internal borders with neighbouring
//! regions do not (the neighbours' own lanes cover up to the border). With a frame, the region's lanes are
//! inset (see `lanes::Placement::Framed`): they start a tool width from a wall side and their ends keep half
//! a tool width more clearance, so frame and lanes meet without a double sweep.

use super::boundary::{close_gaps, cyclic_runs, split_unsafe_steps};
use super::contour::trace_cells;
use super::lanes::RegionView;
use super::{Task, TaskKind};
use crate::geom::{Point2, simplify_polyline};
use crate::space::CoverageSpace;

/// Frame tasks of one region (map frame, metres): open stretches along its walls, or closed loops where the
/// whole contour is wall. Every segment keeps the robot's clearance.
pub fn frame_tasks(space: &CoverageSpace, region: RegionView<'_>) -> Vec<Task> {
    let g = *space.geometry();
    let res = g.resolution;
    let walled = |i: usize| {
        let c = g.cell(i);
        g.neighbors8(c).count() < 8 || g.neighbors8(c).any(|n| !space.reachable[g.index(n)])
    };
    let mut out = Vec::new();
    for lp in trace_cells(&g, region.cells) {
        let n = lp.len();
        if n < 2 {
            continue;
        }
        let mut keep: Vec<bool> = lp.iter().map(|&i| walled(i)).collect();
        if !keep.iter().any(|&k| k) {
            continue;
        }
        // Bridge short interruptions (a cell or two of internal border between two wall stretches).
        close_gaps(&mut keep, 2);
        for run in cyclic_runs(&keep) {
            let pts: Vec<Point2> = run.iter().map(|&k| g.center_of(lp[k])).collect();
            for piece in split_unsafe_steps(space, &pts) {
                if piece.len() < 2 {
                    continue;
                }
                let simple = simplify_polyline(&piece, res, &|a, b| space.segment_ok(a, b));
                out.push(Task {
                    points: simple,
                    kind: TaskKind::Frame,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, GridGeometry, OccupancyGrid};

    #[test]
    fn a_walled_room_is_framed_by_one_closed_loop_that_keeps_clearance() {
        let g = GridGeometry::new(40, 30, 0.05, Point2::origin()).expect("valid");
        let space = crate::decompose::tests::small_robot_space(OccupancyGrid::filled(g, CellState::Free));
        let region = crate::pattern::WholeRegion::new(&space);
        let view = region.view();
        let frame = frame_tasks(&space, view);
        assert_eq!(frame.len(), 1, "{frame:?}");
        assert!(frame[0].is_closed());
        for s in frame[0].points.windows(2) {
            assert!(space.segment_ok(s[0], s[1]));
        }
        // The loop covers the whole wall band: every coverable cell within a tool width of the wall.
        let m = crate::metrics::evaluate(&space, &frame[0].points);
        let band = (0..g.len())
            .filter(|&i| space.coverable[i] && space.clearance.at(i) <= space.robot.radius_m + 0.1)
            .count();
        assert!(m.covered_coverable_cells >= band, "{m:?} band {band}");
    }
}
