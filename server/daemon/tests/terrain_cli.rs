//! `shiftd plan --terrain` as other programs call it (issue 23): the Autzen LiDAR tile (LAZ, in feet)
//! planned for a drone and a ground robot, and broken clouds refused with one line and no plan written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use shift_proto::{RobotKindDoc, TerrainPlanDocument, WaypointKindDoc};

fn shiftd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shiftd"))
}

fn autzen() -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/terrain/autzen_trim.laz");
    assert!(
        p.is_file(),
        "{} is missing: the shared terrain samples sit beside the repository",
        p.display()
    );
    p
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shiftd-terrain-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    dir
}

fn run(args: &[&str], cloud: &Path, dir: &Path) -> (Output, PathBuf) {
    let out = dir.join("plan.json");
    let output = shiftd()
        .args(["plan", "--terrain"])
        .arg(cloud)
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    (output, out)
}

fn plan_of(output: &Output, out: &Path) -> TerrainPlanDocument {
    assert!(
        output.status.success(),
        "shiftd failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    eprintln!("{}", String::from_utf8_lossy(&output.stderr));
    serde_json::from_str(&std::fs::read_to_string(out).expect("written")).expect("terrain plan JSON")
}

/// The drone bars: surface coverage ≥ 98 %, altitude error p95 ≤ 0.2 m, lane spacing on the surface
/// p5/p95 within ±15 % of the tool width.
fn meets_the_surface_bars(d: &shift_proto::DroneMetricsDoc, tool_width_m: f64) {
    assert!(
        d.surface_coverage_pct >= 98.0,
        "surface coverage {}",
        d.surface_coverage_pct
    );
    assert!(
        d.altitude_error_m.p95 <= 0.2,
        "altitude error p95 {}",
        d.altitude_error_m.p95
    );
    let (p5, p95) = (d.lane_spacing_m.p5, d.lane_spacing_m.p95);
    assert!(
        p5 >= 0.85 * tool_width_m && p95 <= 1.15 * tool_width_m,
        "lane spacing p5 {p5} p95 {p95} for a {tool_width_m} m tool"
    );
}

fn png_size(p: &Path) -> (u32, u32) {
    image::image_dimensions(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn autzen_plans_for_a_drone_with_3d_waypoints_on_the_surface() {
    let dir = scratch("drone");
    let (png, maps) = (dir.join("plan.png"), dir.join("maps"));
    let (output, out) = run(
        &[
            "--robot-kind",
            "drone",
            "--tool-width",
            "5",
            "--altitude-offset",
            "3",
            "--grid-m",
            "0.5",
            "--v-max",
            "5",
            "--a-max",
            "2",
            "--render",
            png.to_str().expect("utf-8"),
            "--render-maps",
            maps.to_str().expect("utf-8"),
        ],
        &autzen(),
        &dir,
    );
    let doc = plan_of(&output, &out);
    let t = &doc.terrain;
    // The file's header says international feet (GeoTIFF key and WKT); the plan is in metres and says how.
    assert_eq!(t.robot_kind, RobotKindDoc::Drone);
    assert_eq!(t.source.format, "laz");
    assert_eq!(t.source.horizontal_unit, "foot", "{:?}", t.source);
    assert!(t.source.conversion.contains("0.3048 "), "{}", t.source.conversion);
    assert!(
        t.source.points_read > 100_000 && t.source.points_used > 10_000,
        "{:?}",
        t.source
    );
    // Seed 000 §IV.B figures at a 0.5 m grid.
    let d = t.drone.expect("drone metrics");
    meets_the_surface_bars(&d, 5.0);
    // 3-D waypoints: z follows the ground (it varies by metres over the tile) 3 m above it; times increase.
    let w = &doc.plan.waypoints;
    let (zlo, zhi) = w
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.z), b.max(p.z)));
    let [slo, shi] = t.surface.z_range_m;
    assert!(
        zhi - zlo > 1.0 && zlo >= slo + 3.0 - 0.5 && zhi <= shi + 3.0 + 0.5,
        "z {zlo}..{zhi}, ground {slo}..{shi}"
    );
    assert!(w.windows(2).all(|p| p[1].t > p[0].t));
    assert!(w.iter().all(|p| p.v >= 0.1 - 1e-9 && p.v <= 5.0 + 1e-9));
    assert!(w.iter().filter(|p| p.kind == WaypointKindDoc::Cover).count() > w.len() / 2);
    assert_eq!(doc.plan.metrics.duration_s, w.last().expect("a waypoint").t);
    // The renderings exist at the grid's size.
    let (sw, sh) = (t.surface.width as u32, t.surface.height as u32);
    for name in ["elevation.png", "gaussian-curvature.png", "mean-curvature.png"] {
        let (pw, ph) = png_size(&maps.join(name));
        assert!(
            pw >= sw && ph >= sh && pw % sw == 0 && ph % sh == 0,
            "{name}: {pw} × {ph} for {sw} × {sh}"
        );
    }
    let (pw, _) = png_size(&png);
    assert!(pw > sw);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn autzen_plans_for_a_ground_robot_around_what_is_too_steep() {
    let dir = scratch("ground");
    let (output, out) = run(
        &[
            "--robot-kind",
            "ground",
            "--tool-width",
            "1.0",
            "--grid-m",
            "0.5",
            "--max-slope-deg",
            "12",
        ],
        &autzen(),
        &dir,
    );
    let doc = plan_of(&output, &out);
    let g = doc.terrain.ground.expect("ground figures");
    assert_eq!(doc.plan.metrics.collisions, 0);
    assert!(g.blocked_pct > 0.5, "some of the tile is too steep or rough: {g:?}");
    assert!(
        g.max_path_slope_deg <= 12.0 + 1e-9,
        "the path stays on drivable ground: {g:?}"
    );
    assert!(
        doc.plan.metrics.coverage_pct >= 95.0,
        "coverage {}",
        doc.plan.metrics.coverage_pct
    );
    // z is the ground under each waypoint.
    let [slo, shi] = doc.terrain.surface.z_range_m;
    assert!(
        doc.plan
            .waypoints
            .iter()
            .all(|w| w.z >= slo - 1e-6 && w.z <= shi + 1e-6)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A broken cloud: exit code 2, one line naming the problem, and no plan file.
fn refused(name: &str, bytes: &[u8], want: &str) {
    let dir = scratch(name);
    let cloud = dir.join(name);
    std::fs::write(&cloud, bytes).expect("write");
    let (output, out) = run(&["--tool-width", "5"], &cloud, &dir);
    let err = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{name}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{name}: one line: {err}");
    assert!(err.to_lowercase().contains(want), "{name}: {err:?} should say {want:?}");
    assert!(!out.exists(), "{name}: no plan written");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn broken_clouds_are_refused_with_one_line_and_no_plan() {
    let laz = std::fs::read(autzen()).expect("autzen");
    refused("cut.laz", &laz[..laz.len() / 2], "truncat");
    refused("header.laz", &laz[..300], "laz");
    refused(
        "lying.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n",
        "1000",
    );
    refused(
        "empty.ply",
        b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        "no points",
    );
    refused("noise.pcd", b"this is not a point cloud at all", "pcd");
}

/// A tile nobody tuned for: a binary PLY in metres (UTM-sized coordinates) whose data is a 120 m × 60 m strip
/// turned 35°, over rolling ground with a 0.4 m kerb across it. Drone lanes stay over the strip and keep the
/// surface figures; a ground robot treats the kerb as a wall.
#[test]
fn an_unseen_rotated_ply_tile_plans_for_a_drone_and_a_ground_robot() {
    let dir = scratch("ply");
    let (ox, oy) = (512_345.0, 5_123_456.0);
    let (c, s) = (35f64.to_radians().cos(), 35f64.to_radians().sin());
    let ground = |u: f64, v: f64| 20.0 + 3.0 * (u / 15.0).sin() * (v / 20.0).cos() + if u > 70.0 { 0.4 } else { 0.0 };
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut unit = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let n = 60_000;
    let mut body = Vec::with_capacity(n * 12);
    for _ in 0..n {
        let (u, v) = (120.0 * unit(), 60.0 * unit());
        let z = ground(u, v) + 0.02 * (unit() - 0.5);
        let (x, y) = (ox + c * u - s * v, oy + s * u + c * v);
        // Doubles for x and y (UTM metres lose centimetres in f32), a float z.
        body.extend_from_slice(&x.to_le_bytes());
        body.extend_from_slice(&y.to_le_bytes());
        body.extend_from_slice(&(z as f32).to_le_bytes());
    }
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment made by the test\nelement vertex {n}\nproperty double x\n\
         property double y\nproperty float z\nend_header\n"
    );
    let cloud = dir.join("strip.ply");
    std::fs::write(&cloud, [header.as_bytes(), &body].concat()).expect("write");
    let inside = |x: f64, y: f64, margin: f64| {
        let (dx, dy) = (x - ox, y - oy);
        let (u, v) = (c * dx + s * dy, -s * dx + c * dy);
        u > -margin && u < 120.0 + margin && v > -margin && v < 60.0 + margin
    };

    let (output, out) = run(
        &["--robot-kind", "drone", "--tool-width", "4", "--grid-m", "0.5"],
        &cloud,
        &dir,
    );
    let doc = plan_of(&output, &out);
    let t = &doc.terrain;
    assert_eq!(
        (t.source.format.as_str(), t.source.horizontal_unit.as_str()),
        ("ply", "metre")
    );
    assert!(t.source.unit_source.contains("assumed"), "{}", t.source.unit_source);
    let d = t.drone.expect("drone metrics");
    meets_the_surface_bars(&d, 4.0);
    // The strip covers 40 % of its bounding box: the corners without data are not flown (region = ground
    // within twice the tool width of points, plus half a swath).
    let w = &doc.plan.waypoints;
    assert!(
        w.iter().all(|p| inside(p.x, p.y, 8.0 + 2.0 + 1.0)),
        "a waypoint over the empty corners"
    );
    let area = 120.0 * 60.0;
    assert!(
        d.surface_area_m2 < 1.5 * area,
        "the region is the strip, not its box: {} m²",
        d.surface_area_m2
    );

    let (output, out) = run(
        &[
            "--robot-kind",
            "ground",
            "--tool-width",
            "1",
            "--grid-m",
            "0.5",
            "--max-slope-deg",
            "20",
        ],
        &cloud,
        &dir,
    );
    let doc = plan_of(&output, &out);
    let g = doc.terrain.ground.expect("ground figures");
    assert_eq!(doc.plan.metrics.collisions, 0);
    assert!(
        doc.plan.metrics.coverage_pct >= 95.0,
        "coverage {}",
        doc.plan.metrics.coverage_pct
    );
    // The kerb (0.4 m where 0.10 m is allowed) is a wall across the strip: the path never steps over it where
    // there are points. (Ground interpolated up to 4 cells beyond the strip's edge counts as drivable, so the
    // robot may pass round the kerb's ends there.)
    let uv = |p: &shift_proto::WaypointDoc| {
        let (dx, dy) = (p.x - ox, p.y - oy);
        (c * dx + s * dy, -s * dx + c * dy)
    };
    for pair in doc.plan.waypoints.windows(2) {
        let ((u0, v0), (u1, v1)) = (uv(&pair[0]), uv(&pair[1]));
        if (u0 - 70.0) * (u1 - 70.0) < 0.0 {
            let v = v0 + (v1 - v0) * (70.0 - u0) / (u1 - u0);
            assert!(
                !(1.0..=59.0).contains(&v),
                "the path steps over the kerb at v = {v:.2} m"
            );
        }
    }
    assert!(g.blocked_pct > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}
