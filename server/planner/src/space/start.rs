//! Where the start leads. On a real map at a realistic robot radius the traversable space falls apart into
//! many pieces (speckle, ray fans, doorways narrower than the robot); a start a few centimetres off can sit
//! in a pocket of a square metre, and a plan of that pocket is "complete". So the start's piece is weighed
//! against the largest one: when it is under half of it the plan says so (a warning naming both areas and
//! how far the largest piece is), and a request may ask to move the start into the largest piece when one
//! of its cells lies within a given distance.

use std::collections::VecDeque;

use crate::geom::Point2;
use crate::map::{Cell, GridGeometry};

use super::flood_fill8;

/// The start's piece is "small" below this share of the largest traversable piece.
pub const SMALL_PIECE_SHARE: f64 = 0.5;

/// The outcome of [`weigh_start`].
#[derive(Debug, Clone, PartialEq)]
pub struct StartChoice {
    /// The start cell to use.
    pub cell: Cell,
    /// The reachable set from it.
    pub reachable: Vec<bool>,
    /// Whether the start moved to the largest piece.
    pub snapped: bool,
    /// A remark for the user, when the start's piece is small.
    pub warning: Option<String>,
}

/// Weighs the piece of `traversable` that holds `cell` (the start `start` after the usual snapping to a
/// traversable cell) against the largest piece, and moves the start to the largest piece's cell nearest to
/// `start` when `snap_within_m` allows it (see the module docs). Pieces are 8-connected, as reachability.
pub fn weigh_start(
    g: &GridGeometry,
    traversable: &[bool],
    (start, cell): (Point2, Cell),
    snap_within_m: Option<f64>,
) -> StartChoice {
    let reachable = flood_fill8(g, traversable, cell);
    let mine = reachable.iter().filter(|&&r| r).count();
    let all = traversable.iter().filter(|&&t| t).count();
    let keep = |reachable, warning| StartChoice {
        cell,
        reachable,
        snapped: false,
        warning,
    };
    // A piece with at least half of all traversable cells is the largest: no labelling needed.
    if mine as f64 >= SMALL_PIECE_SHARE * all as f64 {
        return keep(reachable, None);
    }
    let (largest, size) = largest_piece(g, traversable);
    if size == 0 || mine as f64 >= SMALL_PIECE_SHARE * size as f64 {
        return keep(reachable, None);
    }
    let Some((nearest, dist)) = largest
        .iter()
        .enumerate()
        .filter(|&(_, &in_it)| in_it)
        .map(|(i, _)| (i, (g.center_of(i) - start).norm()))
        .min_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return keep(reachable, None);
    };
    let cell_area = g.resolution * g.resolution;
    let (mine_m2, largest_m2) = (mine as f64 * cell_area, size as f64 * cell_area);
    match snap_within_m {
        Some(d) if dist <= d => {
            let c = g.cell(nearest);
            let p = g.center(c);
            StartChoice {
                cell: c,
                reachable: largest,
                snapped: true,
                warning: Some(format!(
                    "start ({:.3}, {:.3}) leads to a traversable piece of {mine_m2:.1} m²; moved {dist:.2} m to \
                     ({:.3}, {:.3}) in the largest piece ({largest_m2:.1} m²), as snap_start_m {d} allows",
                    start.x, start.y, p.x, p.y
                )),
            }
        }
        _ => keep(
            reachable,
            Some(format!(
                "start ({:.3}, {:.3}) leads to a traversable piece of {mine_m2:.1} m², {:.1} % of the largest \
                 piece ({largest_m2:.1} m², {dist:.2} m away); the plan covers only this piece. Move the start, \
                 or set snap_start_m ≥ {dist:.2} to start in the largest piece",
                start.x,
                start.y,
                100.0 * mine as f64 / size as f64
            )),
        ),
    }
}

/// The largest 8-connected piece of `mask` (the first found among equals, in cell order) and its size.
pub fn largest_piece(g: &GridGeometry, mask: &[bool]) -> (Vec<bool>, usize) {
    const NONE: u32 = u32::MAX;
    let mut label = vec![NONE; g.len()];
    let (mut best, mut best_size) = (NONE, 0usize);
    let mut next = 0u32;
    let mut queue = VecDeque::new();
    for s in 0..g.len() {
        if !mask[s] || label[s] != NONE {
            continue;
        }
        label[s] = next;
        queue.push_back(g.cell(s));
        let mut size = 0;
        while let Some(c) = queue.pop_front() {
            size += 1;
            for n in g.neighbors8(c) {
                let i = g.index(n);
                if mask[i] && label[i] == NONE {
                    label[i] = next;
                    queue.push_back(n);
                }
            }
        }
        if size > best_size {
            (best, best_size) = (next, size);
        }
        next += 1;
    }
    (label.iter().map(|&l| l == best && best != NONE).collect(), best_size)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{CellState, OccupancyGrid};
    use crate::space::{CoverageSpace, RobotShape};
    use proptest::prelude::*;

    /// A 10 m × 4 m hall and, behind a wall at x = 1.2 m, a 1 m pocket.
    fn hall_with_pocket() -> OccupancyGrid {
        let g = GridGeometry::new(100, 40, 0.1, Point2::origin()).expect("valid");
        let mut grid = OccupancyGrid::filled(g, CellState::Free);
        for y in 0..40 {
            for x in 10..14 {
                grid.cells[y * 100 + x] = CellState::Occupied;
            }
        }
        grid
    }

    fn robot() -> RobotShape {
        RobotShape {
            radius_m: 0.2,
            tool_width_m: 0.4,
        }
    }

    #[test]
    fn a_start_in_a_pocket_is_reported_and_snaps_only_when_asked() {
        let start = Point2::new(0.5, 2.0);
        let kept = CoverageSpace::new(hall_with_pocket(), robot(), start).expect("space");
        assert_eq!(kept.start, start);
        let w = kept.warnings.join("\n");
        assert!(w.contains("largest piece") && w.contains("snap_start_m"), "{w}");
        assert!(kept.reachable_area_m2() < 4.0, "{}", kept.reachable_area_m2());
        // Too far to snap: the same plan space, the same warning.
        let near = CoverageSpace::with_start_snap(hall_with_pocket(), robot(), start, Some(0.3)).expect("space");
        assert_eq!(near.reachable, kept.reachable);
        // Within reach: the start moves over the wall into the hall.
        let far = CoverageSpace::with_start_snap(hall_with_pocket(), robot(), start, Some(2.0)).expect("space");
        assert!(far.start.x > 1.4 && (far.start - start).norm() < 1.3, "{:?}", far.start);
        assert!(far.reachable_area_m2() > 25.0, "{}", far.reachable_area_m2());
        assert!(far.warnings.iter().any(|w| w.contains("moved")), "{:?}", far.warnings);
        // A start in the hall is never warned about the pocket.
        let hall = CoverageSpace::with_start_snap(hall_with_pocket(), robot(), Point2::new(5.0, 2.0), Some(2.0))
            .expect("space");
        assert!(hall.warnings.is_empty(), "{:?}", hall.warnings);
    }

    proptest! {
        /// The largest piece is a piece (closed under 8-neighbours within the mask) and no piece is larger
        /// (oracle: a flood fill from every cell).
        #[test]
        fn largest_piece_is_the_largest(cells in proptest::collection::vec(any::<bool>(), 12 * 9)) {
            let g = GridGeometry::new(12, 9, 1.0, Point2::origin()).expect("valid");
            let (piece, size) = largest_piece(&g, &cells);
            prop_assert_eq!(piece.iter().filter(|&&p| p).count(), size);
            let mut best = 0;
            for i in 0..g.len() {
                if cells[i] {
                    let fill = flood_fill8(&g, &cells, g.cell(i));
                    let n = fill.iter().filter(|&&f| f).count();
                    best = best.max(n);
                    if piece[i] {
                        prop_assert_eq!(&fill, &piece);
                    }
                }
            }
            prop_assert_eq!(size, best);
        }
    }
}
