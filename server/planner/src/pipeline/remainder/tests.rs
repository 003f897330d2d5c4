use super::*;
use crate::divide::FleetRobot;
use crate::geom::polyline_length;
use crate::map::{CellState, GridGeometry};
use crate::metrics::CoverageRaster;
use crate::pipeline::{NoMonitor, plan};
use crate::space::RobotShape;
use crate::speed::SpeedLimits;

pub(crate) const SHAPE: RobotShape = RobotShape {
    radius_m: 0.3,
    tool_width_m: 0.6,
};

/// A walled 14 m × 9 m room at 0.1 m with pillars and a box.
pub(crate) fn room() -> OccupancyGrid {
    let g = GridGeometry::new(140, 90, 0.1, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    for (x0, y0, x1, y1) in [
        (0.0, 0.0, 14.0, 0.2),
        (0.0, 8.8, 14.0, 9.0),
        (0.0, 0.0, 0.2, 9.0),
        (13.8, 0.0, 14.0, 9.0),
        (6.0, 3.0, 7.5, 4.0),
    ] {
        grid.fill_rect(x0, y0, x1, y1, CellState::Occupied);
    }
    for (x, y, r) in [(3.0, 6.0, 0.4), (10.0, 2.5, 0.5), (11.0, 6.5, 0.3)] {
        grid.fill_disk(Point2::new(x, y), r, CellState::Occupied);
    }
    grid
}

fn stamp(space: &CoverageSpace, path: &[Point2]) -> Vec<bool> {
    let mut raster = CoverageRaster::new(*space.geometry(), space.robot.tool_width_m / 2.0);
    raster.stamp_polyline(path);
    raster.covered().to_vec()
}

fn speed(space: &CoverageSpace) -> SpeedParams {
    SpeedParams::new(SpeedLimits::default(), space.robot.tool_width_m)
}

/// Checks a replan: it plans, covers ≥ 99 % of what was kept, never collides, and returns where it began.
fn check(out: &RemainderPlan, from: Point2) {
    let m = out.plan.metrics;
    assert!(m.coverage_pct >= 99.0, "coverage {:.2} %", m.coverage_pct);
    assert_eq!(m.collisions, 0);
    let pts = out.plan.points();
    assert_eq!(pts.first(), Some(&out.space.start));
    assert_eq!(pts.last(), Some(&out.space.start));
    assert!((out.space.start - from).norm() < 0.2);
    for w in pts.windows(2) {
        assert!(out.space.segment_ok(w[0], w[1]), "{w:?}");
    }
}

/// The figure: plan the site, drive the first half of the path (stamped covered with the tool),
/// replan from there. The replan covers what is left and is no longer than 1.2 × the unfinished half.
#[test]
fn half_driven_replan_is_no_longer_than_the_unfinished_half() {
    for start in [Point2::new(1.0, 1.0), Point2::new(12.5, 7.5)] {
        let space = CoverageSpace::new(room(), SHAPE, start).expect("space");
        let params = PlanParams::default();
        let whole = plan(&space, &params, &mut NoMonitor).expect("plan");
        let path = whole.points();
        let (driven, rest) = split_at_length(&path, polyline_length(&path) / 2.0);
        let covered = stamp(&space, &driven);
        let from = *rest.first().expect("a point");
        let out = plan_remainder(
            &space,
            &covered,
            from,
            (&params, &RemainderParams::default()),
            None,
            &speed(&space),
            &mut NoMonitor,
        )
        .expect("replan");
        check(&out, from);
        eprintln!(
            "start {start:?}: replan {:.1} m, unfinished {:.1} m, {} regions, {}",
            out.plan.metrics.length_m,
            polyline_length(&rest),
            out.plan.regions.len(),
            crate::remainder::tests::figures(&out.remainder)
        );
        let ratio = out.plan.metrics.length_m / polyline_length(&rest);
        assert!(
            ratio <= 1.2,
            "start {start:?}: replan {:.1} m over unfinished {:.1} m = {ratio:.3}",
            out.plan.metrics.length_m,
            polyline_length(&rest)
        );
        assert!(
            out.remainder.work_pieces <= 6,
            "{} work pieces",
            out.remainder.work_pieces
        );
    }
}

/// Shattered remainders plan as a few pieces: a staircase edge, covered lanes with gaps under half a tool,
/// speckle. Each plans, covers what was kept, and stays within a handful of regions.
#[test]
fn shattered_remainders_plan_as_a_few_pieces() {
    let space = CoverageSpace::new(room(), SHAPE, Point2::new(1.0, 1.0)).expect("space");
    let g = *space.geometry();
    let mut s = 0x9E37_79B9_7F4A_7C15_u64;
    let mut noise = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let scenes: Vec<(&str, Vec<bool>)> = vec![
        (
            "staircase",
            (0..g.len())
                .map(|i| {
                    let p = g.center_of(i);
                    p.y < 0.6 * p.x - 1.0
                })
                .collect(),
        ),
        (
            "lanes with thin gaps",
            (0..g.len())
                .map(|i| {
                    let p = g.center_of(i);
                    p.x < 9.0 && ((p.y - 0.2).rem_euclid(0.6 + 0.25) < 0.6 || !(1.0..8.2).contains(&p.x))
                })
                .collect(),
        ),
        (
            "speckle",
            (0..g.len())
                .map(|i| (g.center_of(i).x < 7.0) != noise().is_multiple_of(7))
                .collect(),
        ),
    ];
    let params = PlanParams::default();
    for (name, covered) in scenes {
        let from = Point2::new(1.0, 8.0);
        let out = plan_remainder(
            &space,
            &covered,
            from,
            (&params, &RemainderParams::default()),
            None,
            &speed(&space),
            &mut NoMonitor,
        )
        .expect("replan");
        let r = &out.remainder;
        assert!(
            name == "staircase" || r.pieces_before > 5,
            "{name}: {} pieces before",
            r.pieces_before
        );
        assert!(
            r.pieces_after <= 3 && r.work_pieces <= 3,
            "{name}: {} / {} pieces after",
            r.pieces_after,
            r.work_pieces
        );
        assert!(r.kept_cells > 1000, "{name}: {} kept", r.kept_cells);
        check(&out, from);
        eprintln!(
            "{name}: {:.1} m, {} regions, {}",
            out.plan.metrics.length_m,
            out.plan.regions.len(),
            crate::remainder::tests::figures(r)
        );
        assert!(
            out.plan.regions.len() <= 12,
            "{name}: {} regions",
            out.plan.regions.len()
        );
    }
}

/// Nothing left: the replan is the robot standing where it is (no error).
#[test]
fn nothing_left_plans_nothing() {
    let space = CoverageSpace::new(room(), SHAPE, Point2::new(1.0, 1.0)).expect("space");
    let covered = vec![true; space.geometry().len()];
    let from = Point2::new(5.0, 5.0);
    let out = plan_remainder(
        &space,
        &covered,
        from,
        (&PlanParams::default(), &RemainderParams::default()),
        None,
        &speed(&space),
        &mut NoMonitor,
    )
    .expect("replan");
    assert_eq!(out.remainder.kept_cells, 0);
    assert!(out.plan.metrics.length_m < 1e-9);
}

/// A fleet's replan: the division weighs only the uncovered cells, every part plans its own cleaned
/// remainder, and together they cover what was kept.
#[test]
fn fleet_replans_the_remainder() {
    let grid = room();
    let g = grid.geometry;
    let covered: Vec<bool> = (0..g.len()).map(|i| g.center_of(i).y < 4.5).collect();
    let robots: Vec<FleetRobot> = [Point2::new(1.0, 1.0), Point2::new(12.5, 1.0)]
        .into_iter()
        .map(|start| FleetRobot::disc(start, SHAPE, SpeedLimits::default()))
        .collect();
    let out = plan_fleet_remainder(
        &grid,
        &robots,
        &covered,
        (&PlanParams::default(), &RemainderParams::default()),
        None,
        &FleetParams::default(),
        &mut crate::pipeline::NoMonitor,
    )
    .expect("fleet replan");
    assert_eq!(out.remainders.len(), 2);
    assert!(out.fleet.metrics.union_coverage_pct >= 99.0, "{:?}", out.fleet.metrics);
    for (part, (plan, _)) in out.fleet.division.parts.iter().zip(&out.fleet.plans) {
        assert!((0..g.len()).all(|i| !part.space.coverable[i] || !covered[i]));
        assert_eq!(plan.metrics.collisions, 0);
        assert!(
            plan.metrics.length_m > 0.0,
            "each robot has a share of the uncovered half"
        );
    }
    assert!(out.fleet.metrics.coverable_cells > 0);
}
