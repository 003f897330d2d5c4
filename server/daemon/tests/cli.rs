//! The `shiftd` command line: a plan from the bundled scene, and one-line errors with exit code 2.

use std::process::Command;

fn shiftd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shiftd"))
}

fn fixture() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/four-rooms-obstacles")
}

#[test]
fn plan_writes_a_design_plan_document() {
    let dir = std::env::temp_dir().join(format!("shiftd-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let out = dir.join("plan.json");
    let status = shiftd()
        .args(["plan", "--scene"])
        .arg(fixture())
        .arg("--out")
        .arg(&out)
        .status()
        .expect("runs");
    assert!(status.success());
    let doc: shift_proto::PlanDocument =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("written")).expect("plan JSON");
    assert_eq!(doc.frame, "map");
    assert!(doc.waypoints.len() > 50);
    assert_eq!(doc.metrics.collisions, 0);
    assert!(doc.metrics.coverage_pct >= 99.0);
    // t grows along the path and the first waypoint is the dock.
    assert!(doc.waypoints.windows(2).all(|w| w[1].t >= w[0].t));
    assert_eq!((doc.waypoints[0].x, doc.waypoints[0].y), (0.5, 0.5));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_input_exits_2_with_one_line() {
    let cases: Vec<Vec<String>> = vec![
        vec!["plan".into(), "--scene".into(), "/nonexistent/scene".into()],
        vec![
            "plan".into(),
            "--scene".into(),
            fixture().display().to_string(),
            "--start".into(),
            "100,100".into(),
        ],
        vec![
            "plan".into(),
            "--scene".into(),
            fixture().display().to_string(),
            "--robot-radius".into(),
            "-1".into(),
        ],
        vec![
            "plan".into(),
            "--scene".into(),
            fixture().display().to_string(),
            "--start".into(),
            "NaN,1".into(),
        ],
        vec![
            "plan".into(),
            "--scene".into(),
            fixture().display().to_string(),
            "--v-min".into(),
            "2".into(),
        ],
        vec![
            "plan".into(),
            "--scene".into(),
            fixture().display().to_string(),
            "--attribute".into(),
            "/nonexistent/attribute.pgm".into(),
        ],
    ];
    for args in cases {
        let out = shiftd().args(&args).output().expect("runs");
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(lines.len(), 1, "{args:?}: {err}");
    }
}

#[test]
fn plan_follows_an_attribute_of_blobs() {
    let dir = std::env::temp_dir().join(format!("shiftd-cli-attr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let attr = dir.join("blobs.json");
    std::fs::write(
        &attr,
        r#"{"blobs": [{"x": 2.0, "y": 2.0, "sigma": 1.0, "amplitude": 1.0}]}"#,
    )
    .expect("write");
    let (out, png) = (dir.join("plan.json"), dir.join("plan.png"));
    let status = shiftd()
        .args(["plan", "--scene"])
        .arg(fixture())
        .arg("--attribute")
        .arg(&attr)
        .arg("--out")
        .arg(&out)
        .arg("--render")
        .arg(&png)
        .status()
        .expect("runs");
    assert!(status.success());
    let doc: shift_proto::PlanDocument =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("written")).expect("plan JSON");
    assert!(doc.waypoints.iter().all(|w| (0.1 - 1e-9..=1.0 + 1e-9).contains(&w.v)));
    let (cv, cv_const) = (
        doc.metrics.dwell_cv.expect("dwell_cv"),
        doc.metrics.dwell_cv_const_speed.expect("const"),
    );
    assert!(cv < cv_const, "{cv} vs {cv_const}");
    let last = doc.waypoints.last().expect("waypoints");
    assert!((doc.metrics.duration_s - last.t).abs() < 1e-6 * last.t.max(1.0));
    // Slower near the blob than far from it.
    let near: Vec<f64> = doc
        .waypoints
        .iter()
        .filter(|w| (w.x - 2.0).hypot(w.y - 2.0) < 0.5)
        .map(|w| w.v)
        .collect();
    let far: Vec<f64> = doc
        .waypoints
        .iter()
        .filter(|w| (w.x - 2.0).hypot(w.y - 2.0) > 3.0)
        .map(|w| w.v)
        .collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    assert!(mean(&near) < mean(&far), "{} vs {}", mean(&near), mean(&far));
    assert!(png.is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn eval_divides_a_scene_among_a_fleet_and_prints_its_figures() {
    // A folder holding the fixture scene, as `--scenes` expects.
    let dir = std::env::temp_dir().join(format!("shiftd-cli-fleet-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let scene = dir.join("four-rooms-obstacles");
    if !scene.exists() {
        std::os::unix::fs::symlink(fixture(), &scene).expect("link the fixture");
    }
    let out = shiftd()
        .args(["eval", "--robots", "2,3", "--json", "--scenes"])
        .arg(&dir)
        .output()
        .expect("runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON row"))
        .collect();
    assert_eq!(rows.len(), 2);
    for (row, n) in rows.iter().zip([2, 3]) {
        assert_eq!(row["robots"], n);
        assert_eq!(row["docks"].as_array().map(Vec::len), Some(n));
        assert!(row["coverage_pct"].as_f64().is_some_and(|c| c >= 99.0), "{row}");
        assert!(row["seam_overlap_pct"].as_f64().is_some_and(|s| s <= 3.0), "{row}");
        assert!(row["duration_ratio"].as_f64().is_some_and(|r| r <= 1.15), "{row}");
        assert_eq!(row["collisions"], 0);
    }
    let zero = shiftd()
        .args(["eval", "--robots", "0", "--scenes"])
        .arg(&dir)
        .output()
        .expect("runs");
    assert!(!zero.status.success());
    assert!(String::from_utf8_lossy(&zero.stderr).contains("--robots"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plan_takes_a_footprint_polygon_instead_of_a_radius() {
    let dir = std::env::temp_dir().join(format!("shiftd-cli-fp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let out = dir.join("plan.json");
    let rect = "0.2,0.12;-0.2,0.12;-0.2,-0.12;0.2,-0.12";
    let output = shiftd()
        .args(["plan", "--scene"])
        .arg(fixture())
        .args(["--footprint", rect, "--tool-width", "0.24", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let doc: shift_proto::PlanDocument =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("written")).expect("plan JSON");
    // The metrics count footprint overlaps (DESIGN §6, footprint form).
    assert_eq!(doc.metrics.collisions, 0);
    // Lanes go where the rectangle can turn in place, so it sweeps less along walls than a disc of its width
    // (85 % here; README): a floor under that means the footprint path lost whole rooms.
    assert!(
        doc.metrics.coverage_pct >= 80.0,
        "coverage {}",
        doc.metrics.coverage_pct
    );
    // Not a convex polygon, and a radius besides: exit 2 naming the option.
    for args in [
        vec!["--footprint", "0,0;1,0;0.2,0.2;0,1", "--tool-width", "0.3"],
        vec!["--footprint", rect, "--robot-radius", "0.2"],
    ] {
        let o = shiftd()
            .args(["plan", "--scene"])
            .arg(fixture())
            .args(&args)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("footprint"), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
