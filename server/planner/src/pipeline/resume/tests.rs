use super::*;
use crate::geom::polyline_length;
use crate::map::{CellState, GridGeometry};
use crate::metrics::CoverageRaster;
use crate::pipeline::fleet::{FleetParams, plan_fleet};
use crate::pipeline::remainder::tests::{SHAPE, room};
use crate::pipeline::{NoMonitor, remainder::split_at_length};
use crate::pipeline::{PlanParams, plan_shaped};
use crate::speed::{AttributeBlob, SpeedLimits};

fn stamp(g: GridGeometry, path: &[Point2]) -> Vec<bool> {
    let mut raster = CoverageRaster::new(g, SHAPE.tool_width_m / 2.0);
    raster.stamp_polyline(path);
    raster.covered().to_vec()
}

fn speed() -> SpeedParams {
    SpeedParams::new(SpeedLimits::default(), SHAPE.tool_width_m)
}

/// The plan a robot drives: its profile's (smoothed, sampled) waypoints, as a plan document holds them.
fn driven_plan(space: &CoverageSpace) -> Vec<Waypoint> {
    let (_, profile) = plan_shaped(space, &PlanParams::default(), None, &speed(), &mut NoMonitor).expect("plans");
    profile.waypoints.iter().map(|w| w.waypoint).collect()
}

/// The waypoint a robot `driven_m` along `path` has reached.
fn reached_at(path: &[Waypoint], driven_m: f64) -> usize {
    let pts: Vec<Point2> = path.iter().map(|w| w.position).collect();
    let (driven, _) = split_at_length(&pts, driven_m);
    driven.len().saturating_sub(2)
}

/// Checks a resumed path: from `from` to the previous plan's dock, every segment valid, the kept remainder
/// swept (≥ 99 %), never colliding.
fn check(out: &RemainderPlan, path: &ResumedPath, previous: &[Waypoint], from: Point2) {
    // Every kept cell the previous plan sweeps, the resumed path sweeps (the rest are the plan's own misses).
    let pts: Vec<Point2> = previous.iter().map(|w| w.position).collect();
    let whole = stamp(*out.space.geometry(), &pts);
    let lost = (0..whole.len())
        .filter(|&i| out.remainder.keep[i] && whole[i] && !path.swept[i])
        .count();
    assert_eq!(lost, 0);
    let m = out.plan.metrics;
    assert!(m.coverage_pct >= 99.0, "coverage {:.2} %", m.coverage_pct);
    assert_eq!(m.collisions, 0);
    let pts = out.plan.points();
    assert!((pts[0] - from).norm() < 0.2, "starts at {:?}", pts[0]);
    assert_eq!(pts.last(), previous.last().map(|w| &w.position));
    for w in pts.windows(2) {
        assert!(out.space.segment_ok(w[0], w[1]), "{w:?}");
    }
}

/// The figure for a resume: drive the first half of the plan, resume from there. What is left is
/// covered, and the path is no longer than 1.2 × the unfinished half (here it is that half, shortcut where
/// it crossed driven ground).
#[test]
fn a_plan_driven_half_way_resumes_with_its_unfinished_half() {
    let space = CoverageSpace::new(room(), SHAPE, Point2::new(1.0, 1.0)).expect("space");
    let previous = driven_plan(&space);
    let pts: Vec<Point2> = previous.iter().map(|w| w.position).collect();
    let half = polyline_length(&pts) / 2.0;
    let (driven, rest) = split_at_length(&pts, half);
    let covered = stamp(*space.geometry(), &driven);
    let from = rest[0];
    let prev = Previous {
        path: &previous,
        reached: reached_at(&previous, half),
        from,
    };
    let (out, path) = plan_resume(&space, &covered, prev, &RemainderParams::default(), None, &speed())
        .expect("plans")
        .expect("resumes");
    check(&out, &path, &previous, from);
    let ratio = out.plan.metrics.length_m / polyline_length(&rest);
    assert!(
        ratio <= 1.05,
        "resumed {:.1} m over the unfinished {:.1} m",
        out.plan.metrics.length_m,
        polyline_length(&rest)
    );
    assert_eq!(path.inserted, 0);
}

/// A stretch missed early (a blocked lane the corrections skipped) is put back on the way, and a robot
/// that comes back elsewhere (relocalised across the room) still resumes from where it is.
#[test]
fn a_missed_stretch_is_put_back_and_a_moved_robot_resumes_from_where_it_is() {
    let space = CoverageSpace::new(room(), SHAPE, Point2::new(1.0, 1.0)).expect("space");
    let previous = driven_plan(&space);
    let pts: Vec<Point2> = previous.iter().map(|w| w.position).collect();
    let total = polyline_length(&pts);
    // Driven: the first 60 %, except 10 % to 15 % (missed).
    let (first, _) = split_at_length(&pts, 0.10 * total);
    let (upto, _) = split_at_length(&pts, 0.60 * total);
    let (_, after_gap) = split_at_length(&upto, 0.15 * total);
    let mut covered = stamp(*space.geometry(), &first);
    for (c, d) in covered.iter_mut().zip(stamp(*space.geometry(), &after_gap)) {
        *c |= d;
    }
    let from = Point2::new(12.5, 8.0);
    let prev = Previous {
        path: &previous,
        reached: reached_at(&previous, 0.60 * total),
        from,
    };
    let (out, path) = plan_resume(&space, &covered, prev, &RemainderParams::default(), None, &speed())
        .expect("plans")
        .expect("resumes");
    check(&out, &path, &previous, from);
    assert!(path.inserted >= 1, "the missed stretch is not put back");
    let (_, rest) = split_at_length(&pts, 0.60 * total);
    let missed = polyline_length(&split_at_length(&pts, 0.15 * total).0) - 0.10 * total;
    // The missed stretch and the way to it and back, plus the robot's way to the plan.
    assert!(
        out.plan.metrics.length_m <= polyline_length(&rest) + 3.0 * missed + 30.0,
        "resumed {:.1} m, unfinished {:.1} m + missed {missed:.1} m",
        out.plan.metrics.length_m,
        polyline_length(&rest)
    );
}

/// Nothing left: the resumed path goes home.
#[test]
fn a_finished_plan_resumes_to_its_dock() {
    let space = CoverageSpace::new(room(), SHAPE, Point2::new(1.0, 1.0)).expect("space");
    let previous = driven_plan(&space);
    let pts: Vec<Point2> = previous.iter().map(|w| w.position).collect();
    let covered = stamp(*space.geometry(), &pts);
    let from = Point2::new(7.0, 6.0);
    let prev = Previous {
        path: &previous,
        reached: previous.len() - 1,
        from,
    };
    let (out, path) = plan_resume(&space, &covered, prev, &RemainderParams::default(), None, &speed())
        .expect("plans")
        .expect("resumes");
    assert_eq!(path.runs, 0);
    let ends = out.plan.points();
    assert_eq!(ends.first(), Some(&from));
    assert_eq!(ends.last(), Some(&pts[pts.len() - 1]));
}

/// [`resume_fleet`] with the default remainder rule, which must resume (a refusal fails the test with its
/// reason).
fn must_resume(
    grid: &OccupancyGrid,
    robots: &[FleetRobot],
    plans: (&[Previous<'_>], &[Lost<'_>]),
    covered: &[bool],
    attribute: Option<&AttributeMap>,
    params: &ResumeParams,
) -> Box<FleetRemainderPlan> {
    let rp = RemainderParams::default();
    match resume_fleet(grid, robots, plans, covered, &rp, attribute, params).expect("runs") {
        FleetResume::Resumed(r) => r,
        FleetResume::Refused(why) => panic!("{why}"),
    }
}

fn fleet_robots() -> Vec<FleetRobot> {
    [(1.0, 1.0), (12.5, 7.5)]
        .into_iter()
        .map(|(x, y)| FleetRobot::disc(Point2::new(x, y), SHAPE, SpeedLimits::default()))
        .collect()
}

/// Each robot's plan on `grid` as it drives it (the profiled waypoints of a fleet plan).
fn fleet_paths(grid: &OccupancyGrid, robots: &[FleetRobot]) -> Vec<Vec<Waypoint>> {
    let fleet = plan_fleet(grid, robots, &PlanParams::default(), None, &FleetParams::default()).expect("plans");
    (fleet.plans.iter())
        .map(|(_, p)| p.waypoints.iter().map(|w| w.waypoint).collect())
        .collect()
}

/// Each path driven for its share of its length (`shares`, in the paths' order): the cells swept, and where
/// each robot stands on its path.
fn driven<'a>(g: GridGeometry, paths: &'a [Vec<Waypoint>], shares: &[f64]) -> (Vec<bool>, Vec<Previous<'a>>) {
    let mut covered = vec![false; g.len()];
    let mut previous = Vec::new();
    for (path, share) in paths.iter().zip(shares) {
        let pts: Vec<Point2> = path.iter().map(|w| w.position).collect();
        let at = share * polyline_length(&pts);
        let (swept, rest) = split_at_length(&pts, at);
        for (c, d) in covered.iter_mut().zip(stamp(g, &swept)) {
            *c |= d;
        }
        previous.push(Previous {
            path,
            reached: reached_at(path, at),
            from: rest[0],
        });
    }
    (covered, previous)
}

/// A fleet half-way through its plans resumes them (balanced, nothing they held left out), also round a
/// new obstacle; a fleet whose robots are far apart in progress is divided again.
#[test]
fn a_fleet_resumes_its_plans_round_a_new_obstacle_but_not_when_uneven() {
    let grid = room();
    let robots = fleet_robots();
    let paths = fleet_paths(&grid, &robots);
    let (covered, previous) = driven(grid.geometry, &paths, &[0.5, 0.5]);
    let params = ResumeParams::default();
    let rp = RemainderParams::default();
    let resumed = must_resume(&grid, &robots, (&previous, &[]), &covered, None, &params);
    // Every kept cell the previous plans sweep is swept by the resumed ones (the rest, under 2 % of what is
    // left here, are the plans' own misses along walls and pillars).
    let mut before = vec![false; grid.geometry.len()];
    let mut after = vec![false; grid.geometry.len()];
    for (path, (_, profile)) in paths.iter().zip(&resumed.fleet.plans) {
        let pts: Vec<Point2> = path.iter().map(|w| w.position).collect();
        for (i, c) in stamp(grid.geometry, &pts).into_iter().enumerate() {
            before[i] |= c;
        }
        for (i, c) in stamp(grid.geometry, &profile.points()).into_iter().enumerate() {
            after[i] |= c;
        }
    }
    let coverable = &resumed.fleet.division.coverable;
    let lost = (0..before.len())
        .filter(|&i| coverable[i] && before[i] && !after[i])
        .count();
    assert_eq!(lost, 0);
    assert!(
        resumed.fleet.metrics.union_coverage_pct >= 98.0,
        "{:?}",
        resumed.fleet.metrics
    );
    for (output, _) in &resumed.fleet.plans {
        assert_eq!(output.metrics.collisions, 0);
        assert!(output.metrics.coverage_pct >= 99.0);
    }
    // A live obstacle now stands on robot 1's unfinished lanes (the replan's grid holds it): the fleet still
    // resumes, its paths keep clear of it, and what it loses is the sliver round the obstacle the
    // remainder's rule would drop too.
    let rest1: Vec<Point2> = previous[1].path[previous[1].reached..]
        .iter()
        .map(|w| w.position)
        .collect();
    let block = rest1[rest1.len() / 3];
    let mut blocked = grid.clone();
    blocked.fill_disk(block, 1.0, CellState::Occupied);
    let r = must_resume(&blocked, &robots, (&previous, &[]), &covered, None, &params);
    for (part, (output, _)) in r.fleet.division.parts.iter().zip(&r.fleet.plans) {
        assert_eq!(output.metrics.collisions, 0);
        let pts = output.points();
        assert!(pts.windows(2).all(|w| part.space.segment_ok(w[0], w[1])));
    }
    assert!(r.fleet.metrics.union_coverage_pct >= 97.0, "{:?}", r.fleet.metrics);
    // Robot 0 nearly done while robot 1 has most of its part left: a new division finishes sooner.
    let (uneven, prev) = driven(grid.geometry, &paths, &[0.9, 0.1]);
    match resume_fleet(&grid, &robots, (&prev, &[]), &uneven, &rp, None, &params).expect("runs") {
        FleetResume::Refused(why) => assert!(why.contains("the mean"), "{why}"),
        FleetResume::Resumed(r) => panic!("resumed: {:?}", r.fleet.metrics),
    }
}

/// Two robots of one shape in two rooms with no door between them: each resumes in its own room (a space
/// built for one robot's room would leave the other nowhere to go).
#[test]
fn robots_of_one_shape_in_rooms_apart_each_resume_in_their_own() {
    let mut grid = room();
    grid.fill_rect(6.9, 0.0, 7.1, 9.0, CellState::Occupied);
    let robots = fleet_robots();
    let paths = fleet_paths(&grid, &robots);
    let (covered, previous) = driven(grid.geometry, &paths, &[0.5, 0.5]);
    let params = ResumeParams::default();
    let r = must_resume(&grid, &robots, (&previous, &[]), &covered, None, &params);
    for ((output, _), robot) in r.fleet.plans.iter().zip(&robots) {
        let left_room = robot.start.x < 7.0;
        assert!(output.points().iter().all(|p| (p.x < 7.0) == left_room));
        assert!(output.metrics.coverage_pct >= 97.0, "{:?}", output.metrics);
    }
}

/// With an attribute map every resumed plan gets the fleet's one speed law (over all that is left), as a
/// division's plans do: not a law of its own share, which would give the robot on clean floor the whole
/// speed range for a dirt it does not have.
#[test]
fn a_fleet_resumed_with_an_attribute_shares_one_speed_law() {
    let grid = room();
    let robots = fleet_robots();
    let paths = fleet_paths(&grid, &robots);
    let (covered, previous) = driven(grid.geometry, &paths, &[0.5, 0.5]);
    let blob = AttributeBlob {
        centre: Point2::new(12.0, 5.0),
        sigma_m: 1.0,
        amplitude: 1.0,
    };
    let attribute = AttributeMap::from_blobs(grid.geometry, &[blob]).expect("attribute");
    let params = ResumeParams {
        max_over_mean: f64::INFINITY,
        ..ResumeParams::default()
    };
    let r = must_resume(&grid, &robots, (&previous, &[]), &covered, Some(&attribute), &params);
    let laws: Vec<_> = r.fleet.plans.iter().map(|(_, p)| p.law).collect();
    assert_eq!(laws[0], laws[1]);
    let range = attribute.range_over(&r.fleet.division.coverable).expect("range");
    assert!(range.1 - range.0 > 0.5, "{range:?}");
}

/// Three robots, the third added at (7, 8) to the two of [`fleet_robots`].
fn three_robots() -> Vec<FleetRobot> {
    let mut robots = fleet_robots();
    robots.push(FleetRobot {
        start: Point2::new(7.0, 8.0),
        ..robots[0].clone()
    });
    robots
}

/// The third of [`three_robots`] (their fleet plans `paths` driven as far as `covered` and `previous` say) is
/// lost; the other two resume with its lanes handed over. Checks what any handover must give: no new
/// division, every path valid and collision-free, under 1 % of what the three plans still held left
/// unswept, union coverage ≥ 98 %, durations within 1.3 of each other.
fn hand_over_checked(
    grid: &OccupancyGrid,
    paths: &[Vec<Waypoint>],
    (covered, previous): (&[bool], &[Previous<'_>]),
    attribute: Option<&AttributeMap>,
) -> Box<FleetRemainderPlan> {
    let robots = three_robots();
    let lost = [Lost {
        robot: &robots[2],
        previous: previous[2],
    }];
    let params = ResumeParams::default();
    let handed = must_resume(grid, &robots[..2], (&previous[..2], &lost), covered, attribute, &params);
    let fleet = &handed.fleet;
    assert!(
        fleet.division.warnings[0].contains("handed over"),
        "{:?}",
        fleet.division.warnings
    );
    let mut before = vec![false; grid.geometry.len()];
    let mut after = vec![false; grid.geometry.len()];
    for (path, prev) in paths.iter().zip(previous) {
        let pts: Vec<Point2> = path[prev.reached..].iter().map(|w| w.position).collect();
        for (i, c) in stamp(grid.geometry, &pts).into_iter().enumerate() {
            before[i] |= c;
        }
    }
    for (part, (output, profile)) in fleet.division.parts.iter().zip(&fleet.plans) {
        assert_eq!(output.metrics.collisions, 0);
        let pts = output.points();
        assert!(pts.windows(2).all(|w| part.space.segment_ok(w[0], w[1])));
        for (i, c) in stamp(grid.geometry, &profile.points()).into_iter().enumerate() {
            after[i] |= c;
        }
    }
    let coverable = &fleet.division.coverable;
    let held = (0..before.len()).filter(|&i| coverable[i] && before[i]).count();
    let lost_cells = (0..before.len())
        .filter(|&i| coverable[i] && before[i] && !after[i])
        .count();
    assert!(
        (lost_cells as f64) < 0.01 * held as f64,
        "{lost_cells} of {held} held cells left"
    );
    assert!(fleet.metrics.union_coverage_pct >= 98.0, "{:?}", fleet.metrics);
    assert!(fleet.metrics.duration_ratio <= 1.3, "{:?}", fleet.metrics);
    handed
}

/// Three robots 30 % through their plans; one is lost. The two that go on resume their own plans and take
/// the lost plan's unfinished lanes over (no new division): every kept cell any of the three plans held is
/// swept, each path valid and collision-free, and the two finish within the resume's balance bar.
#[test]
fn a_lost_robots_lanes_are_handed_to_the_robots_that_go_on() {
    let grid = room();
    let robots = three_robots();
    let paths = fleet_paths(&grid, &robots);
    let (covered, previous) = driven(grid.geometry, &paths, &[0.3, 0.3, 0.3]);
    let handed = hand_over_checked(&grid, &paths, (&covered, &previous), None);
    let fleet = &handed.fleet;
    let going = &robots[..2];
    // Both took a share of the lost robot's lanes: each sweeps more than its own plan alone would.
    let alone = ResumeParams {
        max_unswept_share: 1.0,
        max_over_mean: f64::INFINITY,
    };
    let own = must_resume(&grid, going, (&previous[..2], &[]), &covered, None, &alone);
    for (with, without) in fleet.division.parts.iter().zip(&own.fleet.division.parts) {
        assert!(
            with.owned_area_m2 > without.owned_area_m2 + 2.0,
            "{} / {}",
            with.owned_area_m2,
            without.owned_area_m2
        );
    }
}

/// The same handover where the outside world differs: a robot lost before it moved (its whole plan to hand
/// over, the others half-way), and a fleet with an attribute map (the lost plan timed on its profile, which
/// follows the dirt).
#[test]
fn a_robot_lost_at_its_dock_or_on_a_dirty_floor_is_handed_over_too() {
    let grid = room();
    let paths = fleet_paths(&grid, &three_robots());
    let (covered, previous) = driven(grid.geometry, &paths, &[0.5, 0.5, 0.0]);
    hand_over_checked(&grid, &paths, (&covered, &previous), None);
    let blob = AttributeBlob {
        centre: Point2::new(8.0, 6.0),
        sigma_m: 1.5,
        amplitude: 1.0,
    };
    let attribute = AttributeMap::from_blobs(grid.geometry, &[blob]).expect("attribute");
    let (covered, previous) = driven(grid.geometry, &paths, &[0.3, 0.3, 0.3]);
    hand_over_checked(&grid, &paths, (&covered, &previous), Some(&attribute));
}
