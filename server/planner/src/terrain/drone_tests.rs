use super::*;
use crate::geom::Point2;
use crate::map::GridGeometry;
use crate::terrain::drone_metrics::{DroneMetrics, drone_metrics};
use crate::terrain::mesh::TerrainMesh;

fn surface(nx: usize, ny: usize, g: f64, z: impl Fn(f64, f64) -> f64) -> TerrainSurface {
    let geometry = GridGeometry::new(nx, ny, g, Point2::origin()).expect("geometry");
    TerrainSurface::from_fn(geometry, z).expect("surface")
}

fn measure(s: &TerrainSurface, params: &DroneParams) -> (DronePlan, DroneMetrics) {
    let plan = plan_lanes(s, params).expect("plan");
    let mesh = TerrainMesh::new(s).expect("mesh");
    let m = drone_metrics(s, &mesh, &plan);
    eprintln!(
        "{:?} lanes {} coverage {:.4} spacing p5 {:.4} p50 {:.4} p95 {:.4} m; altitude error p50 {:.2e} p95 {:.2e} \
         max {:.2e} m; max slope {:.1}°",
        plan.axis,
        m.lanes,
        m.surface_coverage,
        m.lane_spacing_m.p5,
        m.lane_spacing_m.p50,
        m.lane_spacing_m.p95,
        m.altitude_error_m.p50,
        m.altitude_error_m.p95,
        m.altitude_error_m.max,
        m.max_path_slope_rad.to_degrees()
    );
    (plan, m)
}

fn params(w: f64, lanes: LaneChoice) -> DroneParams {
    DroneParams {
        tool_width_m: w,
        altitude_offset_m: 3.0,
        station_spacing_m: 0.0,
        lanes,
        region_fill_m: f64::INFINITY,
    }
}

#[test]
fn on_a_plane_the_spacing_is_the_tool_width_and_lanes_run_along_the_long_side() {
    // Domain 30 m × 20 m (cell centres), flat at 2 m.
    let s = surface(121, 81, 0.25, |_, _| 2.0);
    let (plan, m) = measure(&s, &params(2.0, LaneChoice::Auto));
    assert_eq!(plan.axis, LaneAxis::X, "lanes along the 30 m side");
    assert_eq!(m.lanes, 10);
    assert!((m.lane_spacing_m.p5 - 2.0).abs() < 1e-9 && (m.lane_spacing_m.p95 - 2.0).abs() < 1e-9);
    assert!(m.surface_coverage >= 0.999_999, "coverage {}", m.surface_coverage);
    assert!(m.altitude_error_m.max < 1e-9);
    assert_eq!(m.max_path_slope_rad, 0.0);
    // Boustrophedon: lane 0 from t_min to t_max at s = 1 m, lane 1 back, every point 3 m over the ground.
    assert_eq!(plan.path[0], [0.125, 0.125 + 1.0, 5.0]);
    let last = plan.stations_t.len() - 1;
    let lane1 = plan
        .path
        .iter()
        .position(|p| (p[1] - 3.125).abs() < 1e-9)
        .expect("lane 1");
    assert!((plan.path[lane1][0] - plan.stations_t[last]).abs() < 1e-9);
    assert!(plan.path.iter().all(|p| (p[2] - 5.0).abs() < 1e-12));
}

#[test]
fn across_a_steep_ramp_lanes_close_up_in_plan_and_keep_the_tool_width_on_the_surface() {
    // 30° ramp rising along x; domain 17.3 m across (x) → 19.98 m on the surface → 10 lanes of 2 m.
    let tilt = 30f64.to_radians();
    let s = surface(174, 100, 0.1, |x, _| x * tilt.tan());
    let (plan, m) = measure(&s, &params(2.0, LaneChoice::Along(LaneAxis::Y)));
    assert_eq!(m.lanes, 10);
    let want = 17.3 / tilt.cos() / 10.0;
    assert!(want > 0.998 * 2.0 && want <= 2.0);
    assert!((m.lane_spacing_m.p5 - want).abs() < 1e-6 && (m.lane_spacing_m.p95 - want).abs() < 1e-6);
    let plan_gap = plan.lane_s[5][7] - plan.lane_s[4][7];
    assert!((plan_gap - want * tilt.cos()).abs() < 1e-6, "plan spacing {plan_gap}");
    assert!(m.surface_coverage >= 0.999_999);
    assert!(m.altitude_error_m.p95 < 1e-9);
    // The turns climb the ramp: the steepest path segment is the ramp itself.
    assert!((m.max_path_slope_rad - tilt).abs() < 1e-6);
    // Along the slope instead: the sections are flat, lanes 2 m apart in plan too.
    let (_, m) = measure(&s, &params(2.0, LaneChoice::Along(LaneAxis::X)));
    assert!((m.lane_spacing_m.p50 - 9.9 / 5.0).abs() < 1e-9);
}

#[test]
fn a_sphere_cap_is_covered_with_surface_spacing_within_the_tool_width() {
    let r = 30.0;
    let s = surface(101, 101, 0.2, |x, y| {
        (r * r - (x - 10.0).powi(2) - (y - 10.0).powi(2)).sqrt()
    });
    let (plan, m) = measure(&s, &params(2.0, LaneChoice::Auto));
    assert!(m.surface_coverage >= 0.99, "coverage {}", m.surface_coverage);
    assert!(
        m.lane_spacing_m.p95 <= 2.0 + 1e-3,
        "spacing p95 {}",
        m.lane_spacing_m.p95
    );
    assert!(m.lane_spacing_m.p5 >= 0.85 * 2.0, "spacing p5 {}", m.lane_spacing_m.p5);
    assert!(m.altitude_error_m.p95 < 0.01, "altitude p95 {}", m.altitude_error_m.p95);
    // The sphere's area over the 20 m square, ∬ R / √(R² − x² − y²), by a 2000² midpoint rule.
    let h = 20.0 / 2000.0;
    let exact: f64 = (0..2000 * 2000)
        .map(|k| {
            let (x, y) = (
                -10.0 + h * ((k % 2000) as f64 + 0.5),
                -10.0 + h * ((k / 2000) as f64 + 0.5),
            );
            r / (r * r - x * x - y * y).sqrt() * h * h
        })
        .sum();
    assert!(
        (m.total_area_m2 / exact - 1.0).abs() < 1e-3,
        "area {} vs {exact}",
        m.total_area_m2
    );
    assert!(plan.path.len() > 1000);
}

#[test]
fn hills_keep_altitude_and_coverage() {
    let s = surface(161, 121, 0.25, |x, y| 2.0 * (x / 6.0).sin() * (y / 5.0).cos() + 0.1 * x);
    let (_, m) = measure(&s, &params(3.0, LaneChoice::Auto));
    assert!(m.surface_coverage >= 0.99, "coverage {}", m.surface_coverage);
    assert!(m.altitude_error_m.p95 < 0.02, "altitude p95 {}", m.altitude_error_m.p95);
    assert!(m.lane_spacing_m.p95 <= 3.0 + 1e-3 && m.lane_spacing_m.p5 >= 0.85 * 3.0);
}

#[test]
fn bad_params_are_named_and_huge_plans_refused() {
    let s = surface(10, 10, 1.0, |_, _| 0.0);
    let bad = |p: DroneParams| plan_lanes(&s, &p).err();
    assert!(matches!(
        bad(params(0.0, LaneChoice::Auto)),
        Some(PlannerError::InvalidParam {
            name: "tool_width_m",
            ..
        })
    ));
    assert!(matches!(
        bad(DroneParams {
            altitude_offset_m: f64::NAN,
            ..DroneParams::default()
        }),
        Some(PlannerError::NonFinite {
            field: "altitude_offset_m",
            ..
        })
    ));
    assert!(matches!(
        bad(DroneParams {
            altitude_offset_m: -1.0,
            ..DroneParams::default()
        }),
        Some(PlannerError::InvalidParam {
            name: "altitude_offset_m",
            ..
        })
    ));
    assert!(matches!(
        bad(params(1e-9, LaneChoice::Auto)),
        Some(PlannerError::TerrainTooLarge { field: "waypoints", .. })
    ));
    assert!(matches!(
        bad(DroneParams {
            station_spacing_m: 1e-9,
            ..DroneParams::default()
        }),
        Some(PlannerError::TerrainTooLarge { field: "stations", .. })
    ));
}

#[test]
fn an_irregular_tile_is_flown_only_where_it_has_data() {
    // 40 m × 20 m flat, but only a disc of radius 9 m around (20, 10) was measured; the rest is filled.
    let g = GridGeometry::new(160, 80, 0.25, Point2::origin()).expect("geometry");
    let mut s = TerrainSurface::from_fn(g, |_, _| 1.0).expect("surface");
    for i in 0..g.len() {
        let p = g.center_of(i);
        let d = (p.x - 20.0).hypot(p.y - 10.0);
        s.fill_ring[i] = ((d - 9.0).max(0.0) / 0.25).ceil() as u32;
    }
    let all = plan_lanes(&s, &params(2.0, LaneChoice::Auto)).expect("whole grid");
    let disc = plan_lanes(
        &s,
        &DroneParams {
            region_fill_m: 0.5,
            ..params(2.0, LaneChoice::Auto)
        },
    )
    .expect("disc");
    // Every waypoint flown lies over the region or on a turn between lanes near it; lanes over the disc only.
    let near = |p: &[f64; 3]| (p[0] - 20.0).hypot(p[1] - 10.0) < 9.5 + 2.0;
    assert!(disc.path.iter().all(near), "a waypoint far from the data");
    assert!(
        disc.path.len() < all.path.len() / 2,
        "{} of {}",
        disc.path.len(),
        all.path.len()
    );
    let mesh = TerrainMesh::new(&s).expect("mesh");
    let m = drone_metrics(&s, &mesh, &disc);
    // Coverage counts the region only, and all of it is swept.
    let region_area = std::f64::consts::PI * 9.5f64.powi(2);
    assert!(
        (m.total_area_m2 - region_area).abs() < 0.1 * region_area,
        "region {} m²",
        m.total_area_m2
    );
    assert!(m.surface_coverage >= 0.99, "coverage {}", m.surface_coverage);
    assert!(m.lane_spacing_m.p95 <= 2.0 + 1e-9);
    assert!(matches!(
        plan_lanes(
            &s,
            &DroneParams {
                region_fill_m: f64::NAN,
                ..DroneParams::default()
            }
        ),
        Err(PlannerError::InvalidParam {
            name: "region_fill_m",
            ..
        })
    ));
}

#[test]
fn overlap_is_the_surface_swept_twice_where_lanes_are_closer_than_the_tool() {
    // 30 m × 20 m: ten 2 m swaths tile it, nothing is swept twice.
    let s = surface(121, 81, 0.25, |_, _| 2.0);
    let (_, m) = measure(&s, &params(2.0, LaneChoice::Auto));
    assert_eq!(m.overlap_area_m2, 0.0);
    // 20 m × 10.5 m at 5 cm: 2 m swaths cannot tile 10.5 m, so neighbouring lanes close up. On a plane the area
    // swept twice is, per pair of lanes, (tool − gap) × the length along the lanes, up to a row of cells at each
    // edge of each band.
    let g = 0.05;
    let s = surface(401, 211, g, |_, _| 2.0);
    let (plan, m) = measure(&s, &params(2.0, LaneChoice::Auto));
    assert_eq!(plan.axis, LaneAxis::X);
    let along = 401.0 * g;
    let across: Vec<f64> = plan.lane_s.iter().map(|l| l[0]).collect();
    let bands: Vec<f64> = across
        .windows(2)
        .map(|w| (2.0 - (w[1] - w[0])).max(0.0))
        .filter(|&b| b > 0.0)
        .collect();
    assert!(!bands.is_empty(), "lanes closer than the tool: {across:?}");
    let expected: f64 = bands.iter().sum::<f64>() * along;
    let tolerance = bands.len() as f64 * 2.0 * g * along;
    assert!(
        (m.overlap_area_m2 - expected).abs() <= tolerance,
        "overlap {:.2} m², expected {expected:.2} ± {tolerance:.2} (lanes at {across:?})",
        m.overlap_area_m2
    );
    assert!(m.overlap_area_m2 > 0.0 && m.overlap_area_m2 < m.covered_area_m2);
}
