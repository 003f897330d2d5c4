//! A rectangle through a doorway between two rooms, at several angles of the walls; a robot that fits
//! nowhere.

use super::*;
use crate::footprint::poses::{visit_poses, wrap_angle};
use crate::map::{CellState, GridGeometry, OccupancyGrid};
use crate::metrics::CoverageRaster;
use crate::pipeline::NoMonitor;
use crate::space::RobotShape;
use crate::speed::SpeedLimits;
use crate::testing::{TwoRooms, two_rooms};

/// What a footprinted plan of two rooms achieves.
struct Figures {
    near_pct: f64,
    far_pct: f64,
    length_m: f64,
    collisions: usize,
}

/// Plans the rooms for `fp` with a tool of `tool_m` and checks what every plan must hold: no footprint
/// collision (counted again here), poses in the dividing wall's band heading through the doorway.
fn plan_rooms(rooms: &TwoRooms, fp: &Footprint, tool_m: f64) -> Figures {
    plan_rooms_with(rooms, fp, tool_m, LaneSpace::Auto, &mut NoMonitor)
}

fn plan_rooms_with(
    rooms: &TwoRooms,
    fp: &Footprint,
    tool_m: f64,
    lanes: LaneSpace,
    monitor: &mut dyn PlanMonitor,
) -> Figures {
    let res = rooms.grid.geometry.resolution;
    let robot = RobotShape {
        radius_m: fp.planning_radius_m(res),
        tool_width_m: tool_m,
    };
    let space = CoverageSpace::new(rooms.grid.clone(), robot, rooms.start).expect("space");
    let speed = SpeedParams::new(SpeedLimits::default(), tool_m);
    let (out, profile) =
        plan_footprinted_with(&space, fp, lanes, &PlanParams::default(), None, &speed, monitor).expect("plan");
    let exact = FootprintCheck::new(&space.grid, &space.clearance, fp).expect("check");
    let pts = profile.points();
    assert_eq!(out.metrics.collisions, exact.count_collisions(&out.points()));
    assert_eq!(profile.metrics.collisions, exact.count_collisions(&pts));
    assert_eq!(pts.first(), Some(&space.start));
    assert_eq!(pts.last(), Some(&space.start));
    visit_poses(&pts, None, None, res / 4.0, 0.02, &mut |p, h| {
        if rooms.in_wall_band(p) {
            let off = wrap_angle(2.0 * (h - rooms.through_rad)).abs() / 2.0;
            assert!(
                off < 35f64.to_radians(),
                "heading {:.1}° in the doorway at {p:?}",
                h.to_degrees()
            );
        }
        std::ops::ControlFlow::Continue(())
    });
    let mut raster = CoverageRaster::new(*space.geometry(), tool_m / 2.0);
    raster.stamp_polyline(&pts);
    let g = space.geometry();
    let pct = |room: &dyn Fn(Point2) -> bool| {
        let cells: Vec<usize> = (0..g.len())
            .filter(|&i| space.coverable[i] && room(g.center_of(i)))
            .collect();
        let covered = cells.iter().filter(|&&i| raster.is_covered(i)).count();
        100.0 * covered as f64 / cells.len().max(1) as f64
    };
    Figures {
        near_pct: pct(&|p| rooms.in_near_room(p)),
        far_pct: pct(&|p| rooms.in_far_room(p)),
        length_m: profile.metrics.length_m,
        collisions: profile.metrics.collisions,
    }
}

/// A 0.8 m × 1.2 m rectangle plans through a doorway 1.0 m wide its circumscribed disc could not pass,
/// heading through it, covers both rooms and collides nowhere.
#[test]
fn a_rectangle_covers_two_rooms_through_a_narrow_doorway() {
    let fp = Footprint::rectangle(1.2, 0.8).expect("valid");
    let rooms = two_rooms((4.0, 4.0), 0.2, 1.0, 0.0, 0.05).expect("scene");
    let disc = RobotShape {
        radius_m: fp.circumscribed_radius_m(),
        tool_width_m: 0.8,
    };
    let space = CoverageSpace::new(rooms.grid.clone(), disc, rooms.start).expect("space");
    let g = space.geometry();
    assert!(
        (0..g.len()).all(|i| !space.reachable[i] || !rooms.in_far_room(g.center_of(i))),
        "the circumscribed disc cannot reach the far room"
    );
    let mut heard = Recorder::default();
    let f = plan_rooms_with(&rooms, &fp, 0.8, LaneSpace::Auto, &mut heard);
    assert!(
        heard.progress.windows(2).all(|w| w[1] >= w[0] - 1e-12),
        "{:?}",
        heard.progress
    );
    assert_eq!(heard.progress.last(), Some(&1.0));
    assert!(!heard.regions.is_empty());
    eprintln!(
        "doorway 0°: near {:.1} %, far {:.1} %, {:.1} m, {} collisions",
        f.near_pct, f.far_pct, f.length_m, f.collisions
    );
    assert_eq!(f.collisions, 0);
    assert!(
        f.far_pct > 60.0 && f.near_pct > 60.0,
        "near {:.1} %, far {:.1} %",
        f.near_pct,
        f.far_pct
    );
}

/// Records what a plan reports.
#[derive(Default)]
struct Recorder {
    progress: Vec<f64>,
    regions: Vec<Vec<Point2>>,
}

impl PlanMonitor for Recorder {
    fn progress(&mut self, fraction: f64) {
        self.progress.push(fraction);
    }
    fn region_ready(&mut self, _region: &RegionSummary, path: &[Point2]) {
        assert!(path.len() >= 2);
        self.regions.push(path.to_vec());
    }
}

/// Lanes in the inscribed space itself (the repair does most of the work: lane ends a body length from the
/// walls cannot be turned at): still no collision, and both rooms covered, if less.
#[test]
fn lanes_in_the_inscribed_space_are_repaired_collision_free() {
    let fp = Footprint::rectangle(1.2, 0.8).expect("valid");
    let rooms = two_rooms((4.0, 4.0), 0.2, 1.0, 0.0, 0.05).expect("scene");
    let f = plan_rooms_with(&rooms, &fp, 0.8, LaneSpace::Inscribed, &mut NoMonitor);
    eprintln!(
        "doorway 0°, lanes in the inscribed space: near {:.1} %, far {:.1} %, {:.1} m, {} collisions",
        f.near_pct, f.far_pct, f.length_m, f.collisions
    );
    assert_eq!(f.collisions, 0);
    assert!(
        f.far_pct > 50.0 && f.near_pct > 50.0,
        "near {:.1} %, far {:.1} %",
        f.near_pct,
        f.far_pct
    );
}

/// The same through doorways at other angles of the whole site.
#[test]
fn doorways_at_any_angle_pass() {
    let fp = Footprint::rectangle(1.2, 0.8).expect("valid");
    for deg in [17.0_f64, 33.0, 45.0, 71.0] {
        let rooms = two_rooms((4.0, 4.0), 0.2, 1.0, deg.to_radians(), 0.05).expect("scene");
        let f = plan_rooms(&rooms, &fp, 0.8);
        eprintln!(
            "doorway {deg}°: near {:.1} %, far {:.1} %, {:.1} m, {} collisions",
            f.near_pct, f.far_pct, f.length_m, f.collisions
        );
        assert_eq!(f.collisions, 0, "{deg}°");
        assert!(f.far_pct > 60.0, "{deg}°: far room {:.1} %", f.far_pct);
    }
}

/// A footprint that fits nowhere round its start is refused, naming `robot.footprint`.
#[test]
fn a_footprint_that_fits_nowhere_is_refused() {
    let g = GridGeometry::new(60, 40, 0.05, Point2::origin()).expect("valid");
    let mut grid = OccupancyGrid::filled(g, CellState::Occupied);
    grid.fill_rect(0.5, 0.5, 2.0, 2.0, CellState::Free);
    let fp = Footprint::rectangle(2.0, 0.6).expect("valid");
    let robot = RobotShape {
        radius_m: fp.planning_radius_m(0.05),
        tool_width_m: 0.6,
    };
    let space = CoverageSpace::new(grid, robot, Point2::new(1.25, 1.25)).expect("the inscribed disc fits");
    let speed = SpeedParams::new(SpeedLimits::default(), 0.6);
    let e = plan_footprinted(&space, &fp, &PlanParams::default(), None, &speed, &mut NoMonitor)
        .expect_err("a 2 m body in a 1.5 m closet");
    assert!(
        e.to_string().contains("robot.footprint") && e.to_string().contains("start"),
        "{e}"
    );
    let small = RobotShape { radius_m: 0.1, ..robot };
    let space = CoverageSpace::new(space.grid.clone(), small, Point2::new(1.25, 1.25)).expect("space");
    let e = plan_footprinted(&space, &fp, &PlanParams::default(), None, &speed, &mut NoMonitor)
        .expect_err("a space for a smaller disc");
    assert!(e.to_string().contains("robot.footprint"), "{e}");
}
