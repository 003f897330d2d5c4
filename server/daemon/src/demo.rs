//! `shiftd demo`: the whole fleet loop in one command. Serves the daemon on loopback with the demo site (8 m ×
//! 8 m: two rooms at the bottom, a hall across the middle, two rooms at the top, doors between), and runs the
//! simulator `shift-sim` — a separate program, each robot its own Zenoh participant — with three robots, one
//! band of the site each, and a box the daemon does not know standing in the hall on the middle robot's lanes. Each robot asks for its plan, gets it assigned, drives it; the box shows up in the
//! middle robot's scans, its path is corrected around it. The simulator logs progress; at the end the report it
//! measured (swept area, collisions, corrections) is printed as a table. The API stays reachable at `--bind`
//! while it runs, for curl or the docs page.

use std::path::{Path, PathBuf};
use std::process::Stdio;

use serde_json::{Value, json};

use crate::bail;
use crate::error::{Context, Result};
use crate::server::{DEMO_IMAGE, DEMO_YAML};

/// The hidden box in the hall, `[x0, y0, x1, y1]` metres: lanes at 0.3 m spacing cross it.
pub const HIDDEN_BOX: [f64; 4] = [6.0, 3.8, 6.3, 4.1];

/// What the demo runs with.
#[derive(Debug, Clone)]
pub struct DemoArgs {
    /// HTTP address of the daemon.
    pub bind: std::net::SocketAddr,
    /// The `shift-sim` binary.
    pub sim: PathBuf,
    /// Simulated seconds per real second.
    pub speedup: f64,
    /// Folder for the store, the world file and the report (kept afterwards).
    pub dir: PathBuf,
}

/// The `shift-sim` beside this executable (`cargo build -p shift-sim` puts both in the same folder).
pub fn sim_beside_me() -> Option<PathBuf> {
    let me = std::env::current_exe().ok()?;
    let sim = me.parent()?.join(format!("shift-sim{}", std::env::consts::EXE_SUFFIX));
    sim.is_file().then_some(sim)
}

/// The world the simulator drives in: the demo map, the hidden box, three robots with a band each (the bands
/// overlap by 0.3 m, so no seam is left between them).
pub fn world(map_yaml: &Path) -> Value {
    let band = |y0: f64, y1: f64| json!([[0.0, y0], [8.0, y0], [8.0, y1], [0.0, y1]]);
    json!({
        "map": map_yaml,
        "obstacles": [{"box": HIDDEN_BOX}],
        "robots": [
            {"id": "south", "start": [0.5, 0.5, 0.0], "radius": 0.15, "tool_width": 0.3, "region": band(0.0, 3.3)},
            {"id": "hall", "start": [0.5, 4.0, 0.0], "radius": 0.15, "tool_width": 0.3, "region": band(3.0, 5.3)},
            {"id": "north", "start": [0.5, 7.5, 0.0], "radius": 0.15, "tool_width": 0.3, "region": band(5.0, 8.0)}
        ]
    })
}

/// Runs the demo: the daemon in this process, the simulator as a child, until the simulator ends. Returns the
/// simulator's report (`shift-sim --report`).
pub async fn run(args: DemoArgs) -> Result<Value> {
    std::fs::create_dir_all(&args.dir).with_context(|| format!("creating {}", args.dir.display()))?;
    let map_yaml = args.dir.join("demo-map.yaml");
    std::fs::write(&map_yaml, DEMO_YAML.replace("image: map.pgm", "image: demo-map.pgm"))?;
    std::fs::write(args.dir.join("demo-map.pgm"), DEMO_IMAGE)?;
    let world_path = args.dir.join("world.json");
    std::fs::write(&world_path, serde_json::to_vec_pretty(&world(&map_yaml))?)?;
    let report_path = args.dir.join("report.json");

    let zenoh_port = std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port();
    let endpoint = format!("tcp/127.0.0.1:{zenoh_port}");
    let mut config = crate::Config::default();
    config.http.bind = args.bind;
    config.store.data_dir = args.dir.join("data");
    config.zenoh.listen = vec![endpoint.clone()];
    config.zenoh.site = config.demo.site.clone();
    let listener = tokio::net::TcpListener::bind(args.bind)
        .await
        .with_context(|| format!("binding {}", args.bind))?;
    let http = format!("http://{}", listener.local_addr()?);
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let server = tokio::spawn(crate::run(config, listener, async move {
        let _ = stopped.await;
    }));
    wait_ready(&http).await?;
    tracing::info!(%http, zenoh = %endpoint, dir = %args.dir.display(), "demo daemon serving; starting shift-sim");

    let sim = args.sim.clone();
    let child_args = {
        let mut a: Vec<std::ffi::OsString> = Vec::new();
        for s in [
            "--http",
            &http,
            "--zenoh",
            &endpoint,
            "--site",
            "demo",
            "--robots",
            "3",
            "--plan-per-robot",
        ] {
            a.push(s.into());
        }
        for s in [
            "--speedup",
            &args.speedup.to_string(),
            "--mu",
            "0.1",
            "--timeout-s",
            "900",
        ] {
            a.push(s.into());
        }
        a.extend(["--world".into(), world_path.clone().into_os_string()]);
        a.extend(["--report".into(), report_path.clone().into_os_string()]);
        a
    };
    let status = tokio::task::spawn_blocking(move || {
        std::process::Command::new(&sim)
            .args(child_args)
            .stdin(Stdio::null())
            .status()
            .with_context(|| format!("starting {}", sim.display()))
    })
    .await??;
    let _ = stop.send(());
    server.await??;
    let report: Value = serde_json::from_slice(
        &std::fs::read(&report_path).with_context(|| format!("shift-sim wrote no report ({status})"))?,
    )?;
    if !status.success() {
        tracing::warn!("shift-sim: {status} (a robot did not finish its plan)");
    }
    Ok(report)
}

/// Polls `/readyz` until the daemon answers (plain HTTP/1.1 on loopback; no client library needed).
async fn wait_ready(http: &str) -> Result<()> {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let addr = http.trim_start_matches("http://").to_owned();
    for _ in 0..400 {
        if let Ok(mut s) = tokio::net::TcpStream::connect(&addr).await {
            let req = format!("GET /readyz HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
            if s.write_all(req.as_bytes()).await.is_ok() {
                let mut head = [0u8; 12];
                if s.read_exact(&mut head).await.is_ok() && head.ends_with(b"200") {
                    return Ok(());
                }
            }
        }
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    bail!("the demo daemon did not become ready at {http}")
}

/// The report as a table, one line per robot and one for the fleet.
pub fn table(report: &Value) -> String {
    let mut out = format!(
        "{:<8} {:>9} {:>8} {:>6} {:>11} {:>12} {:>9} {:>9}\n",
        "robot", "driven_m", "time_s", "stops", "collisions", "corrections", "covered%", "finished"
    );
    let n = |v: &Value| v.as_u64().unwrap_or(0);
    let x = |v: &Value| v.as_f64().unwrap_or(0.0);
    for r in report["robots"].as_array().into_iter().flatten() {
        out += &format!(
            "{:<8} {:>9.1} {:>8.1} {:>6} {:>11} {:>12} {:>9.1} {:>9}\n",
            r["id"].as_str().unwrap_or("?"),
            x(&r["driven_m"]),
            x(&r["time_s"]),
            n(&r["stops"]),
            n(&r["collisions"]),
            n(&r["corrections_applied"]),
            x(&r["covered_pct"]),
            r["finished"].as_bool().unwrap_or(false),
        );
    }
    let f = &report["fleet"];
    out += &format!(
        "{:<8} {:>9} {:>8.1} {:>6} {:>11} {:>12} {:>9.1}\n",
        "fleet",
        "",
        x(&f["time_s"]),
        "",
        n(&f["collisions"]),
        "",
        x(&f["covered_pct"]),
    );
    out
}
