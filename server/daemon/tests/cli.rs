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
    ];
    for args in cases {
        let out = shiftd().args(&args).output().expect("runs");
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(lines.len(), 1, "{args:?}: {err}");
    }
}
