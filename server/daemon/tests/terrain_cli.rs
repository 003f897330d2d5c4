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
    assert!(
        d.lane_spacing_m.p5 >= 0.85 * 5.0 && d.lane_spacing_m.p95 <= 1.15 * 5.0,
        "lane spacing p5 {} p95 {}",
        d.lane_spacing_m.p5,
        d.lane_spacing_m.p95
    );
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
