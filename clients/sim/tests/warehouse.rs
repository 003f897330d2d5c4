//! The whole fleet loop from outside, as issue 19 asks: `shift-sim` (a separate process, each robot its own
//! Zenoh participant) drives two robots on the shared `warehouse` map against a real shiftd on loopback. One
//! plan's lane crosses a box the daemon does not know; a disc walks back and forth across the other robot's
//! aisle. Both robots finish, the blocked one receives and applies a correction, nothing touches the hidden
//! world, and the fleet sweeps at least 97 % of what could be covered, by the simulator's own measure.

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use anyhow::{Context, Result, ensure};
use shift_client::Client;
use shift_sim::Report;
use shift_tests::TestServer;
use shift_tests::fleet::fleet_config;

fn warehouse() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenarios/warehouse")
}

/// The hidden box: 0.8 m square in the middle aisle of the left half (any plan covering that aisle with a
/// 0.6 m body on lanes 1 m apart drives into it).
const BOX: [f64; 4] = [7.0, 12.3, 7.8, 13.1];

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_robots_cover_the_warehouse_round_a_hidden_box_and_a_walker() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (config, endpoint) = fleet_config(dir.path())?;
    let server = TestServer::start(config).await?;
    let client = Client::new(&server.base)?;

    // The backend uploads its own map.
    let scene = warehouse();
    let yaml = std::fs::read_to_string(scene.join("map.yaml"))?;
    let image = std::fs::read(scene.join("map.pgm"))?;
    client.upload_map("wh", yaml, image, "map.pgm").await?;

    // Two halves that overlap by 2 m, so the seam is swept from both sides.
    let world = serde_json::json!({
        "map": scene.join("map.yaml"),
        "obstacles": [{"box": BOX}],
        "movers": [{"r": 0.25, "from": [28.0, 0.6], "to": [28.0, 3.8], "speed": 0.4}],
        "robots": [
            {"id": "left", "start": [1.0, 1.0, 0.0], "radius": 0.3, "tool_width": 1.0, "v_max": 1.0,
             "region": [[0.0, 0.0], [21.0, 0.0], [21.0, 25.0], [0.0, 25.0]]},
            {"id": "right", "start": [39.0, 1.0, 3.0], "radius": 0.3, "tool_width": 1.0, "v_max": 1.0,
             "region": [[19.0, 0.0], [40.0, 0.0], [40.0, 25.0], [19.0, 25.0]]}
        ]
    });
    let world_path = dir.path().join("world.json");
    std::fs::write(&world_path, serde_json::to_vec_pretty(&world)?)?;
    let report_path = dir.path().join("report.json");
    let trace = dir.path().join("trace");

    let sim = tokio::task::spawn_blocking({
        let (http, world_path, report_path, trace) = (
            server.base.clone(),
            world_path.clone(),
            report_path.clone(),
            trace.clone(),
        );
        move || {
            Command::new(env!("CARGO_BIN_EXE_shift-sim"))
                .args([
                    "--http",
                    &http,
                    "--zenoh",
                    &endpoint,
                    "--site",
                    "wh",
                    "--robots",
                    "2",
                    "--plan-per-robot",
                ])
                .args([
                    "--speedup",
                    "25",
                    "--mu",
                    "0.2",
                    "--timeout-s",
                    "4000",
                    "--beams",
                    "180",
                ])
                .arg("--world")
                .arg(&world_path)
                .arg("--report")
                .arg(&report_path)
                .arg("--trace")
                .arg(&trace)
                .output()
        }
    });
    let out = tokio::time::timeout(Duration::from_secs(900), sim)
        .await
        .context("shift-sim ran over 15 min")???;
    let stderr = String::from_utf8_lossy(&out.stderr);
    let report: Report =
        serde_json::from_slice(&std::fs::read(&report_path).with_context(|| format!("no report; stderr:\n{stderr}"))?)?;
    eprintln!("{stderr}\n{}", serde_json::to_string_pretty(&report)?);
    ensure!(out.status.code() == Some(0), "shift-sim exited {:?}", out.status);

    ensure!(report.robots.len() == 2);
    for r in &report.robots {
        ensure!(r.finished, "{} did not finish", r.id);
        ensure!(
            r.collisions == 0,
            "{} touched the hidden world {} times",
            r.id,
            r.collisions
        );
        ensure!(r.driven_m > 100.0, "{} drove only {} m", r.id, r.driven_m);
    }
    let left = &report.robots[0];
    ensure!(left.corrections_applied >= 1, "the blocked robot applied no correction");
    ensure!(
        left.final_version >= Some(2),
        "left ended on version {:?}",
        left.final_version
    );
    ensure!(report.fleet.collisions == 0);
    ensure!(
        report.fleet.covered_pct >= 97.0,
        "fleet covered {:.2} %",
        report.fleet.covered_pct
    );

    // The daemon agrees: the left plan was corrected, at the version the robot ended on.
    let plan_id = left.plan_id.clone().context("left followed no plan")?;
    let status = client.plan(&plan_id).await?;
    ensure!(
        status.corrections >= 1,
        "daemon reports {} corrections",
        status.corrections
    );
    ensure!(
        Some(status.version) == left.final_version,
        "daemon {} vs robot {:?}",
        status.version,
        left.final_version
    );

    // The trace is ground truth every 0.05 s: rows advance in time and the body never overlaps the box.
    let csv = std::fs::read_to_string(trace.join("left.csv"))?;
    let mut rows = csv.lines();
    ensure!(rows.next() == Some("t,x,y,yaw,v"));
    let mut last_t = 0.0;
    let mut n = 0;
    for line in rows {
        let v: Vec<f64> = line.split(',').map(str::parse).collect::<Result<_, _>>()?;
        ensure!(v.len() == 5 && v[0] > last_t);
        last_t = v[0];
        n += 1;
        // Distance from the robot's centre to the box: the body may reach half a 0.1 m cell plus the 2 cm
        // tracking tolerance into it (as into a wall whose cell centres the plan keeps the radius from), no more.
        let dx = (BOX[0] - v[1]).max(v[1] - BOX[2]).max(0.0);
        let dy = (BOX[1] - v[2]).max(v[2] - BOX[3]).max(0.0);
        ensure!(dx.hypot(dy) >= 0.3 - 0.05 - 0.02, "the body overlaps the box at {line}");
    }
    ensure!((n as f64 - last_t / 0.05).abs() < 2.0, "{n} rows for {last_t} s");
    server.stop().await
}
