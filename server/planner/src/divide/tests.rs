use proptest::prelude::*;

use super::*;
use crate::decompose::DecompositionMethod;
use crate::map::{CellState, GridGeometry};
use crate::pipeline::PlanParams;
use crate::pipeline::fleet::{FleetParams, plan_fleet};
use crate::space::flood_fill8;

fn robot(x: f64, y: f64) -> FleetRobot {
    FleetRobot {
        start: Point2::new(x, y),
        shape: RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        },
        limits: SpeedLimits::new(0.1, 0.6, 0.5),
        footprint: None,
    }
}

/// A walled `w × h` m room at 0.1 m.
fn room(w: f64, h: f64) -> OccupancyGrid {
    let g = GridGeometry::new((w * 10.0) as usize, (h * 10.0) as usize, 0.1, Point2::origin()).expect("geometry");
    let mut grid = OccupancyGrid::filled(g, CellState::Free);
    grid.fill_rect(0.0, 0.0, w, 0.1, CellState::Occupied);
    grid.fill_rect(0.0, h - 0.1, w, h, CellState::Occupied);
    grid.fill_rect(0.0, 0.0, 0.1, h, CellState::Occupied);
    grid.fill_rect(w - 0.1, 0.0, w, h, CellState::Occupied);
    grid
}

/// A 30 m corridor (y 0–2) with six 4 m × 4 m rooms above it (y 2.2–6.2), each entered by a 1 m doorway;
/// returns the grid and each room's interior rectangle.
fn corridor_with_rooms() -> (OccupancyGrid, Vec<[f64; 4]>) {
    let mut grid = room(30.0, 6.4);
    // The wall between corridor and rooms, with a doorway per room; the walls between rooms.
    let mut rooms = Vec::new();
    for k in 0..6 {
        let x0 = 0.1 + k as f64 * 5.0;
        grid.fill_rect(x0, 2.0, x0 + 2.0, 2.2, CellState::Occupied);
        grid.fill_rect(x0 + 3.0, 2.0, x0 + 5.0, 2.2, CellState::Occupied);
        if k > 0 {
            grid.fill_rect(x0 - 0.1, 2.0, x0 + 0.1, 6.4, CellState::Occupied);
        }
        rooms.push([x0 + 0.2, 2.3, x0 + 4.7, 6.2]);
    }
    (grid, rooms)
}

/// The invariants every division keeps: one owner per cell (by construction), every part's reachable cells
/// connected and holding its start, and every coverable cell of the fleet inside some part's coverable set.
fn check_invariants(div: &Division, robots: &[FleetRobot]) {
    let g = *div.parts[0].space.geometry();
    for (k, part) in div.parts.iter().enumerate() {
        let s = &part.space;
        assert!(s.reachable[g.index(s.start_cell)], "robot {k} lost its start");
        let again = flood_fill8(&g, &s.reachable, s.start_cell);
        assert_eq!(again, s.reachable, "robot {k}'s part is not connected");
        for i in 0..g.len() {
            if s.reachable[i] {
                assert_eq!(div.owner[i], k as u32, "robot {k} stands on a cell it does not own");
            }
        }
        let start = g.locate(robots[k].start).expect("start on the map");
        assert_eq!(
            div.owner[g.index(start)],
            k as u32,
            "robot {k}'s start cell is someone else's"
        );
    }
    let missed = (0..g.len())
        .filter(|&i| div.coverable[i] && !div.parts.iter().any(|p| p.space.coverable[i]))
        .count();
    assert_eq!(missed, 0, "coverable cells in no part");
}

#[test]
fn an_open_hall_is_shared_evenly_by_two_three_and_four_robots() {
    let grid = room(20.0, 12.0);
    let docks = [robot(1.0, 1.0), robot(2.0, 1.0), robot(3.0, 1.0), robot(19.0, 11.0)];
    for n in 2..=4 {
        let robots = &docks[..n];
        let div = divide(&grid, robots, None, None, &DivideParams::default()).expect("divides");
        check_invariants(&div, robots);
        assert!(div.load_ratio() <= 1.05, "{n} robots: load ratio {}", div.load_ratio());
        let owned: f64 = div.parts.iter().map(|p| p.owned_area_m2).sum();
        let total = div.coverable.iter().filter(|&&c| c).count() as f64 * 0.01;
        assert!((owned - total).abs() < 1e-6, "owned {owned} of {total} m²");
    }
}

#[test]
fn a_faster_robot_with_a_wider_tool_gets_more_area() {
    let grid = room(20.0, 12.0);
    let mut big = robot(18.0, 6.0);
    big.shape.tool_width_m = 0.6;
    big.limits = SpeedLimits::new(0.1, 1.2, 0.5);
    let robots = [robot(2.0, 6.0), big];
    let div = divide(&grid, &robots, None, None, &DivideParams::default()).expect("divides");
    check_invariants(&div, &robots);
    let ratio = div.parts[1].owned_area_m2 / div.parts[0].owned_area_m2;
    // Four times the rate, less its dearer turns: a U-turn costs a robot 2·v/a seconds, so on lanes of the
    // hall's length (about 19.8 m) each cell costs 1 + 2·v²/(a·L) times its lane time (see `work`).
    let turns = |v: f64| 1.0 + 2.0 * v * v / (0.5 * 19.8);
    let expected = 4.0 * turns(0.6) / turns(1.2);
    assert!(
        (ratio / expected - 1.0).abs() <= 0.1,
        "area ratio {ratio}, expected about {expected:.2}"
    );
    assert!(div.load_ratio() <= 1.05, "{}", div.load_ratio());
}

#[test]
fn rooms_off_a_corridor_are_not_cut() {
    // How "not cut" is told: every room's interior cells have one owner. Robots start in the corridor; a
    // part may end anywhere along the corridor but never inside a room.
    let (grid, rooms) = corridor_with_rooms();
    let robots = [robot(1.0, 1.0), robot(15.0, 1.0), robot(29.0, 1.0)];
    let div = divide(&grid, &robots, None, None, &DivideParams::default()).expect("divides");
    check_invariants(&div, &robots);
    let g = grid.geometry;
    for (k, r) in rooms.iter().enumerate() {
        let owners: std::collections::BTreeSet<u32> = (0..g.len())
            .filter(|&i| {
                let p = g.center_of(i);
                p.x > r[0] && p.x < r[2] && p.y > r[1] && p.y < r[3] && div.owner[i] != NO_OWNER
            })
            .map(|i| div.owner[i])
            .collect();
        assert_eq!(owners.len(), 1, "room {k} is shared by robots {owners:?}");
    }
    assert!(div.load_ratio() <= 1.15, "{}", div.load_ratio());
}

#[test]
fn a_robot_too_wide_for_a_passage_leaves_what_lies_beyond_to_one_that_fits() {
    // Two halls joined by a 0.5 m gap: the 0.3 m-radius robot cannot pass it, the 0.15 m one can.
    let mut grid = room(20.0, 8.0);
    grid.fill_rect(9.9, 0.0, 10.1, 3.75, CellState::Occupied);
    grid.fill_rect(9.9, 4.25, 10.1, 8.0, CellState::Occupied);
    let mut wide = robot(2.0, 4.0);
    wide.shape.radius_m = 0.3;
    let robots = [wide, robot(4.0, 4.0)];
    let div = divide(&grid, &robots, None, None, &DivideParams::default()).expect("divides");
    check_invariants(&div, &robots);
    let g = grid.geometry;
    let beyond = (0..g.len()).filter(|&i| g.center_of(i).x > 10.5 && div.coverable[i]);
    for i in beyond {
        assert_eq!(div.owner[i], 1, "cell {:?} beyond the gap", g.center_of(i));
    }
}

#[test]
fn bad_fleets_are_refused_naming_the_robot() {
    let grid = room(10.0, 10.0);
    let p = DivideParams::default();
    let err = divide(&grid, &[], None, None, &p).expect_err("no robots");
    assert!(err.to_string().contains("robots"), "{err}");
    let err = divide(&grid, &[robot(2.0, 2.0), robot(2.02, 2.03)], None, None, &p).expect_err("one cell");
    assert!(err.to_string().contains("robots[1].start"), "{err}");
    let err = divide(&grid, &[robot(2.0, 2.0), robot(40.0, 2.0)], None, None, &p).expect_err("off the map");
    assert!(err.to_string().contains("robots[1]"), "{err}");
    let err = divide(&grid, &[robot(2.0, f64::NAN)], None, None, &p).expect_err("NaN");
    assert!(err.to_string().contains("robots[0]"), "{err}");
}

#[test]
fn fleet_plans_cover_the_site_with_balanced_durations_and_a_thin_seam() {
    let (grid, _) = corridor_with_rooms();
    let robots = [robot(1.0, 1.0), robot(15.0, 1.0), robot(29.0, 1.0)];
    let params = PlanParams {
        decomposition: DecompositionMethod::Auto,
        threads: 1,
        ..PlanParams::default()
    };
    let fleet = plan_fleet(&grid, &robots, &params, None, &FleetParams::default()).expect("plans");
    let m = &fleet.metrics;
    eprintln!("corridor, 3 robots: {m:?}, {} rounds", fleet.rounds);
    assert!(m.union_coverage_pct >= 99.0, "{m:?}");
    assert!(m.seam_overlap_pct <= 3.0, "{m:?}");
    assert!(m.duration_ratio <= 1.15, "{m:?}");
    for ((_, profile), part) in fleet.plans.iter().zip(&fleet.division.parts) {
        assert_eq!(profile.metrics.collisions, 0);
        let pts = profile.points();
        assert_eq!(pts.first(), Some(&part.space.start));
        for p in &pts {
            // Smoothing may round a corner through the corner of a cell beside the part.
            let g = part.space.geometry();
            let c = g.locate(*p).expect("on the map");
            let near = std::iter::once(c).chain(g.neighbors8(c));
            assert!(
                near.into_iter().any(|n| part.space.reachable[g.index(n)]),
                "{p:?} off the robot's part"
            );
        }
    }
}

#[test]
fn a_cancelled_fleet_plan_stops_within_its_part_plans() {
    use crate::pipeline::PlanMonitor;
    use crate::pipeline::fleet::plan_fleet_monitored;
    /// Cancels after `polls` looks: the first part's plan is well under way by then.
    struct CancelAfter {
        polls: std::cell::Cell<usize>,
    }
    impl PlanMonitor for CancelAfter {
        fn cancelled(&self) -> bool {
            let n = self.polls.get();
            self.polls.set(n.saturating_sub(1));
            n == 0
        }
    }
    let (grid, _) = corridor_with_rooms();
    let robots = [robot(1.0, 1.0), robot(15.0, 1.0), robot(29.0, 1.0)];
    let params = PlanParams {
        threads: 1,
        ..PlanParams::default()
    };
    for polls in [0, 1, 5, 50] {
        let mut monitor = CancelAfter {
            polls: std::cell::Cell::new(polls),
        };
        let out = plan_fleet_monitored(&grid, &robots, &params, None, &FleetParams::default(), &mut monitor);
        assert!(
            matches!(out, Err(crate::PlannerError::Cancelled)),
            "after {polls} polls: {:?}",
            out.map(|f| f.rounds)
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    /// On random cluttered rooms with random docks, every division keeps its invariants.
    #[test]
    fn random_divisions_keep_their_invariants(seed in any::<u64>(), n in 2usize..5) {
        let grid = crate::testing::cluttered_site(14.0, 9.0, 0.1, 12, seed).expect("site");
        let g = grid.geometry;
        let mut s = seed | 1;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 10_000) as f64 / 10_000.0
        };
        let mut robots: Vec<FleetRobot> = Vec::new();
        let mut tries = 0;
        while robots.len() < n && tries < 1000 {
            tries += 1;
            let p = Point2::new(0.5 + next() * 13.0, 0.5 + next() * 8.0);
            let Some(c) = g.locate(p) else { continue };
            let clear = crate::space::CoverageSpace::new(grid.clone(), robot(0.0, 0.0).shape, p)
                .is_ok_and(|sp| sp.start_cell == c && sp.reachable_count() > 2000);
            if clear && robots.iter().all(|r| g.locate(r.start) != Some(c)) {
                robots.push(robot(p.x, p.y));
            }
        }
        prop_assume!(robots.len() == n);
        let div = divide(&grid, &robots, None, None, &DivideParams::default()).expect("divides");
        // Docks in separate pieces of the site are legal; the invariants hold per piece.
        check_invariants(&div, &robots);
    }
}

#[test]
fn a_doorway_beside_the_boundary_keeps_the_part_connected_and_the_inset_elsewhere() {
    // Robot 0 owns x < 2 m of a 4 m × 2 m room, robot 1 the rest. A wall at y = 1 m runs from the left wall
    // to x = 1.8 m: the lower half of robot 0's part is entered by a doorway beside the boundary, inside the
    // half-tool inset. The part stays connected, and keeps the inset everywhere but near that doorway.
    let mut grid = room(4.0, 2.0);
    grid.fill_rect(0.0, 1.0, 1.8, 1.1, CellState::Occupied);
    let g = grid.geometry;
    let shape = RobotShape {
        radius_m: 0.15,
        tool_width_m: 0.3,
    };
    let space = CoverageSpace::new(grid, shape, Point2::new(0.5, 1.5)).expect("space");
    let owner: Vec<u32> = (0..g.len())
        .map(|i| {
            if !space.reachable[i] && !space.coverable[i] {
                NO_OWNER
            } else if g.center_of(i).x < 2.0 {
                0
            } else {
                1
            }
        })
        .collect();
    let (keep, _) = ownership::part_masks(&space, space.start_cell, &owner, 0, 1, shape.tool_width_m / 2.0);
    let reached = flood_fill8(&g, &keep, space.start_cell);
    assert_eq!(keep, reached, "the part's reachable mask is connected from its start");
    let at = |x: f64, y: f64| keep[g.index(g.locate(Point2::new(x, y)).expect("on the map"))];
    assert!(at(0.5, 0.5), "the lower half is kept");
    assert!(at(1.95, 1.05), "the doorway is passable");
    for y in [0.3, 0.5, 1.5, 1.7] {
        assert!(
            !at(1.95, y),
            "the inset holds at y = {y} (the centre stays half a tool from robot 1's part)"
        );
    }
}
