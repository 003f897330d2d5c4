use super::*;
use crate::decompose::tests::random_space;
use crate::geom::Point2;
use crate::map::GridGeometry;
use crate::map::{CellState, OccupancyGrid};
use crate::space::RobotShape;
use proptest::prelude::*;

/// A walled 12 m × 8 m room at 0.1 m with three pillars, for the cluttered-site robot (radius 0.3 m,
/// tool 0.6 m).
pub(crate) fn site() -> CoverageSpace {
    let g = GridGeometry::new(120, 80, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    for (x0, y0, x1, y1) in [
        (0.0, 0.0, 12.0, 0.2),
        (0.0, 7.8, 12.0, 8.0),
        (0.0, 0.0, 0.2, 8.0),
        (11.8, 0.0, 12.0, 8.0),
    ] {
        grid.fill_rect(x0, y0, x1, y1, CellState::Occupied);
    }
    for (x, y, r) in [(3.0, 5.0, 0.4), (8.0, 2.5, 0.5), (9.5, 6.0, 0.3)] {
        grid.fill_disk(Point2::new(x, y), r, CellState::Occupied);
    }
    let robot = RobotShape {
        radius_m: 0.3,
        tool_width_m: 0.6,
    };
    CoverageSpace::new(grid, robot, Point2::new(1.0, 1.0)).expect("space")
}

/// The figures of a remainder, without its masks.
pub(crate) fn figures(r: &Remainder) -> String {
    format!(
        "uncovered {} kept {} slivers {} tiny {} pieces {} -> {} work pieces {}",
        r.uncovered_cells,
        r.kept_cells,
        r.dropped_sliver_cells,
        r.dropped_tiny_cells,
        r.pieces_before,
        r.pieces_after,
        r.work_pieces
    )
}

/// Cells whose centre lies within `r` of cell `c`'s centre (oracle for the discs).
fn disc_cells(g: &GridGeometry, c: usize, r: f64) -> Vec<usize> {
    (0..g.len())
        .filter(|&j| (g.center_of(j) - g.center_of(c)).norm() <= r + 1e-9)
        .collect()
}

fn covered_by(space: &CoverageSpace, f: impl Fn(Point2) -> bool) -> Vec<bool> {
    let g = *space.geometry();
    (0..g.len()).map(|i| f(g.center_of(i))).collect()
}

/// Covered below a diagonal drawn on the grid (a staircase edge): the uncovered half stays one piece and
/// loses at most the teeth of the staircase.
#[test]
fn a_staircase_edge_keeps_the_uncovered_half_whole() {
    let space = site();
    let g = *space.geometry();
    let covered = covered_by(&space, |p| p.y < 0.55 * p.x + 0.7);
    let r = remainder(&space, &covered, &RemainderParams::default()).expect("remainder");
    assert_eq!(r.pieces_after, 1, "{}", figures(&r));
    assert_eq!(r.work_pieces, 1);
    assert!(
        r.dropped_area_m2() <= 0.02 * r.uncovered_area_m2(),
        "dropped {} of {}",
        r.dropped_area_m2(),
        r.uncovered_area_m2()
    );
    // Nothing covered is kept, and nothing coverable a tool width clear of the edge is lost.
    for (i, &cov) in covered.iter().enumerate() {
        let p = g.center_of(i);
        assert!(!(r.keep[i] && cov));
        let clear = (p.y - 0.55 * p.x - 0.7) / (1.0_f64 + 0.55 * 0.55).sqrt() > 0.6;
        if clear && space.coverable[i] && !cov {
            let near_wall = space.clearance.at(i) < 0.6;
            assert!(r.keep[i] || near_wall, "cell {i} at {p:?} lost");
        }
    }
}

/// Covered lanes a tool wide with gaps narrower than half a tool between them: a pass along a gap would
/// sweep mostly covered ground, so the gaps are dropped (and reported); gaps wider than half a tool stay,
/// each one piece.
#[test]
fn thin_gaps_between_covered_lanes_are_dropped_and_wide_ones_kept() {
    let space = site();
    let w = 0.6;
    for (gap, kept) in [(0.2, false), (0.4 * w, false), (0.8 * w, true), (1.2 * w, true)] {
        let period = w + gap;
        let covered = covered_by(&space, |p| (p.y - 0.2).rem_euclid(period) < w);
        let uncovered_gaps = ((8.0 - 0.4) / period).ceil() as usize;
        let r = remainder(&space, &covered, &RemainderParams::default()).expect("remainder");
        assert!(r.pieces_before >= uncovered_gaps - 1, "gap {gap}: {}", figures(&r));
        if kept {
            assert!(r.kept_cells > 0, "gap {gap}");
            assert!(
                r.pieces_after <= uncovered_gaps + 4,
                "gap {gap}: {} pieces",
                r.pieces_after
            );
            assert!(
                r.dropped_area_m2() < 0.2 * r.uncovered_area_m2(),
                "gap {gap}: {}",
                figures(&r)
            );
        } else {
            assert_eq!(r.kept_cells, 0, "gap {gap}: {} pieces kept", r.pieces_after);
            assert!((r.dropped_area_m2() - r.uncovered_area_m2()).abs() < 1e-9);
            assert!(r.warning().is_some());
        }
    }
}

/// Random speckle: half the site covered with one cell in six left uncovered at random, the other half
/// uncovered with one cell in six covered. Hundreds of pieces before, one after.
#[test]
fn speckle_does_not_shatter_the_remainder() {
    let space = site();
    let g = *space.geometry();
    let mut s = 0x2545_F491_4F6C_DD1D_u64;
    let covered: Vec<bool> = (0..g.len())
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let speck = s.is_multiple_of(6);
            (g.center_of(i).x < 6.0) != speck
        })
        .collect();
    let r = remainder(&space, &covered, &RemainderParams::default()).expect("remainder");
    assert!(r.pieces_before > 200, "{}", figures(&r));
    assert_eq!(r.pieces_after, 1, "{}", figures(&r));
    assert_eq!(r.work_pieces, 1);
    // The specks in the covered half are dropped; the uncovered half is kept but for its covered specks.
    let right: usize = (0..g.len())
        .filter(|&i| g.center_of(i).x > 6.6 && space.coverable[i] && !covered[i])
        .count();
    let kept_right = (0..g.len()).filter(|&i| g.center_of(i).x > 6.6 && r.keep[i]).count();
    assert!(kept_right as f64 >= 0.98 * right as f64, "{kept_right} of {right}");
    let left = (0..g.len()).filter(|&i| g.center_of(i).x < 5.4 && r.keep[i]).count();
    assert_eq!(left, 0);
}

#[test]
fn bad_inputs_are_refused() {
    let space = site();
    let n = space.geometry().len();
    assert!(remainder(&space, &vec![false; n - 1], &RemainderParams::default()).is_err());
    for params in [
        RemainderParams {
            min_new_share: 1.5,
            ..RemainderParams::default()
        },
        RemainderParams {
            min_piece_discs: f64::NAN,
            ..RemainderParams::default()
        },
    ] {
        assert!(matches!(
            remainder(&space, &vec![false; n], &params),
            Err(PlannerError::InvalidParam { .. })
        ));
    }
    // Nothing covered: everything coverable is kept, one work zone per reachable set.
    let r = remainder(&space, &vec![false; n], &RemainderParams::default()).expect("remainder");
    assert_eq!(r.kept_cells, space.coverable_count());
    assert_eq!(r.work, space.reachable);
}

#[test]
fn strip_share_is_the_disc_area_in_a_centred_strip() {
    assert!(strip_share(0.0).abs() < 1e-12);
    assert!((strip_share(1.0) - 1.0).abs() < 1e-12);
    assert!((strip_share(0.5) - 0.609).abs() < 1e-3);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Against brute force on random rooms and random covered blots and speckle: nothing covered or
    /// uncoverable is kept; every tool disc of uncovered ground around a reachable cell is kept whole; the
    /// work zone is exactly the reachable cells within half a tool of a kept cell; the figures add up.
    #[test]
    fn the_keep_rule_matches_its_oracle(
        seed in 1u64..500,
        obstacles in 0usize..6,
        blots in proptest::collection::vec((0.0f64..4.0, 0.0f64..3.0, 0.1f64..1.2), 0..8),
        speckle in 0u64..5,
    ) {
        let Some(space) = random_space(seed, 40, 30, obstacles) else { return Ok(()) };
        let g = *space.geometry();
        let mut s = seed | 1;
        let covered: Vec<bool> = (0..g.len()).map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let p = g.center_of(i);
            blots.iter().any(|&(x, y, r)| (p - Point2::new(x, y)).norm() <= r) != (speckle > 0 && s % 9 < speckle)
        }).collect();
        let r = remainder(&space, &covered, &RemainderParams::default()).expect("remainder");
        let half = space.robot.tool_width_m / 2.0;
        for i in 0..g.len() {
            prop_assert!(!r.keep[i] || (space.coverable[i] && !covered[i]), "cell {} kept", i);
            if space.reachable[i] {
                let disc = disc_cells(&g, i, half);
                if disc.iter().all(|&j| space.coverable[j] && !covered[j]) {
                    prop_assert!(disc.iter().all(|&j| r.keep[j]), "the disc around {} lost a cell", i);
                }
                let work = disc.iter().any(|&j| r.keep[j]);
                prop_assert_eq!(r.work[i], work, "work at {}", i);
            } else {
                prop_assert!(!r.work[i]);
            }
        }
        let uncovered = (0..g.len()).filter(|&i| space.coverable[i] && !covered[i]).count();
        prop_assert_eq!(r.uncovered_cells, uncovered);
        prop_assert_eq!(r.kept_cells + r.dropped_sliver_cells + r.dropped_tiny_cells, uncovered);
        prop_assert_eq!(r.kept_cells, r.keep.iter().filter(|&&k| k).count());
    }
}
