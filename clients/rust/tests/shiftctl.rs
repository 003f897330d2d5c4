//! `shiftctl` end to end: every command runs as the real binary against a daemon started in-process on
//! 127.0.0.1; outputs are parsed back and compared with what the API serves.

mod common;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail, ensure};
use common::{ctl, json, ok};
use serde_json::Value;
use shift_client::Client;
use shift_client::proto::{
    PlanAccepted, PlanDocument, PlanList, PlanStatus, PlanStatusResponse, SiteList, SiteSummary, WaypointKindDoc,
};
use shift_tests::{TestServer, test_config};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/fixtures")
        .join(name)
}

/// The plan id in `plan p-N <status> …`.
fn plan_id_of(line: &str) -> Result<String> {
    let mut words = line.split_whitespace();
    ensure!(words.next() == Some("plan"), "not a plan line: {line}");
    words.next().map(str::to_owned).context("plan id")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_command_against_a_real_daemon() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let base = server.base.clone();
    let b = base.as_str();
    let client = Client::new(b)?;

    // Sites: upload the fixture map (its image found beside the YAML), show, list.
    let yaml = fixture("four-rooms-obstacles/map.yaml");
    let yaml = yaml.to_str().context("fixture path")?;
    let up: SiteSummary = json(b, &["site", "upload", "rooms", "--yaml", yaml]).await?;
    assert_eq!(up.site, "rooms");
    assert!(up.free_cells > 0 && up.width > 0);
    let shown: SiteSummary = json(b, &["site", "show", "rooms"]).await?;
    assert_eq!(
        (shown.width, shown.height, shown.free_cells),
        (up.width, up.height, up.free_cells)
    );
    let human = ok(b, &["site", "show", "rooms"]).await?;
    assert!(
        human.contains("rooms") && human.contains(&format!("{} × {} cells", up.width, up.height)),
        "{human}"
    );
    let sites: SiteList = json(b, &["sites"]).await?;
    let names: Vec<&str> = sites.items.iter().map(|s| s.site.as_str()).collect();
    assert_eq!(names, ["demo", "rooms"], "name order");
    let human = ok(b, &["sites"]).await?;
    assert!(
        human.lines().count() == 3 && human.contains("demo") && human.contains("rooms"),
        "{human}"
    );

    // A plan followed with --watch: the progress ends in the metrics table.
    let watched = ok(b, &["plan", "--site", "demo", "--start", "0.5,0.5", "--watch"]).await?;
    let first_line = watched.lines().next().context("output")?;
    assert!(first_line.contains(" ready "), "{watched}");
    let watched_id = plan_id_of(first_line)?;
    for label in ["coverage", "length", "turns", "duration"] {
        assert!(watched.contains(label), "metrics table lacks {label}: {watched}");
    }
    let status = client.plan(&watched_id).await?;
    let m = status.metrics.context("metrics")?;
    assert!(watched.contains(&format!("{:.1} %", m.coverage_pct)), "{watched}");

    // A plan submitted for scripts, then shown.
    let acc: PlanAccepted = json(
        b,
        &[
            "plan",
            "--site",
            "rooms",
            "--start",
            "0.5,0.5",
            "--robot-radius",
            "0.15",
            "--tool-width",
            "0.3",
            "--objective",
            "time",
        ],
    )
    .await?;
    assert_eq!(acc.status, PlanStatus::Queued);
    let id = acc.plan_id;
    let done = client
        .wait_plan(&id, Duration::from_millis(50), Duration::from_secs(120))
        .await?;
    assert_eq!(done.status, PlanStatus::Ready, "{done:?}");
    let shown: PlanStatusResponse = json(b, &["plan", "show", &id]).await?;
    assert_eq!(shown.metrics, done.metrics);
    let human = ok(b, &["plan", "show", &id]).await?;
    assert!(human.contains("ready") && human.contains("coverage"), "{human}");

    // Listing: newest first, paged, filtered.
    let list: PlanList = json(b, &["plans"]).await?;
    let ids: Vec<&str> = list.items.iter().map(|p| p.plan_id.as_str()).collect();
    assert_eq!(ids, [id.as_str(), watched_id.as_str()]);
    let page: PlanList = json(b, &["plans", "--limit", "1"]).await?;
    assert_eq!(page.items.len(), 1);
    assert_eq!(page.next.as_deref(), Some(id.as_str()));
    let rest: PlanList = json(b, &["plans", "--limit", "1", "--after", &id]).await?;
    assert_eq!(rest.items[0].plan_id, watched_id);
    assert_eq!(rest.next, None);
    let all: PlanList = json(b, &["plans", "--limit", "1", "--all"]).await?;
    assert_eq!(all.items.len(), 2);
    let on_rooms: PlanList = json(b, &["plans", "--site", "rooms", "--status", "ready"]).await?;
    assert_eq!(on_rooms.items.len(), 1);
    let human = ok(b, &["plans", "--limit", "1"]).await?;
    assert!(
        human.contains(&id) && human.contains(&format!("--after {id}")),
        "{human}"
    );

    let doc = client.path(&id).await?;
    exports_parse_back(b, &id, &doc, dir.path()).await?;
    render_draws_the_plan(b, &id, dir.path()).await?;

    // Assign to a robot, list robots.
    let assigned: PlanStatusResponse = json(b, &["plan", "assign", &id, "r1"]).await?;
    assert_eq!(assigned.robot.as_deref(), Some("r1"));
    let on_r1: PlanList = json(b, &["plans", "--robot", "r1"]).await?;
    assert_eq!(on_r1.items.len(), 1);
    assert_eq!(on_r1.items[0].plan_id, id);
    let robots: Vec<Value> = json(b, &["robots"]).await?;
    assert!(robots.iter().all(|r| r["robot"].is_string()));
    ok(b, &["robots"]).await?;

    // Cancel: a finished plan cannot be (the server says no: 1); a fresh one can, unless it finished first.
    let (code, _, err) = ctl(b, &["--json", "plan", "cancel", &watched_id]).await?;
    assert_eq!(code, 1, "{err}");
    let body: Value = serde_json::from_str(err.trim())?;
    assert_eq!(
        (body["status"].as_u64(), body["error"]["code"].as_str()),
        (Some(409), Some("invalid_state"))
    );
    let fresh: PlanAccepted = json(b, &["plan", "--site", "rooms", "--start", "0.5,0.5"]).await?;
    let (code, out, err) = ctl(b, &["--json", "plan", "cancel", &fresh.plan_id]).await?;
    match code {
        0 => assert_eq!(
            serde_json::from_str::<PlanStatusResponse>(&out)?.status,
            PlanStatus::Cancelled
        ),
        1 => assert!(err.contains("invalid_state"), "{err}"),
        c => bail!("cancel exited {c}: {err}"),
    }

    // The server said no: 1.
    for args in [
        &["plan", "show", "p-999"][..],
        &["site", "show", "nowhere"],
        &["export", "p-999", "--format", "csv"],
        &["render", "p-999", "x.png"],
        &["plan", "--site", "nowhere", "--start", "0,0"],
        &["plans", "--after", "p-999"],
    ] {
        let (code, _, err) = ctl(b, args).await?;
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.starts_with("shiftctl: "), "{err}");
    }
    // Bad input: 2 (clap's own errors too), before anything is sent.
    let missing = dir.path().join("missing.yaml");
    for args in [
        &["plan", "--site", "demo", "--start", "abc"][..],
        &["plan", "--site", "demo"],
        &["plan", "--site", "demo", "--start", "0,0", "--tool-width", "-1"],
        &["plan", "--site", "demo", "--start", "0,0", "--region", "0,0 1,1"],
        &["plan", "--site", "demo", "--start", "0,0", "--objective", "fastest"],
        &["export", &id, "--format", "kml"],
        &["plans", "--status", "busy"],
        &["plans", "--limit", "0"],
        &["site", "upload", "x", "--yaml", missing.to_str().context("path")?],
        &["--http", "localhost:1", "sites"],
        &["frobnicate"],
    ] {
        let (code, _, err) = ctl(b, args).await?;
        assert_eq!(code, 2, "{args:?}: {err}");
    }
    // Unreachable daemon: 1.
    let (code, _, _) = ctl("http://127.0.0.1:9", &["sites"]).await?;
    assert_eq!(code, 1);
    server.stop().await
}

async fn exports_parse_back(b: &str, id: &str, doc: &PlanDocument, dir: &Path) -> Result<()> {
    let w = &doc.waypoints;
    // GeoJSON: the path's coordinates and per-point v and t are the plan's, exactly.
    let file = dir.join("plan.geojson");
    let file_s = file.to_str().context("path")?;
    ok(b, &["export", id, "--format", "geojson", "--out", file_s]).await?;
    let g: Value = serde_json::from_str(&std::fs::read_to_string(&file)?)?;
    assert_eq!(g["type"], "FeatureCollection");
    let path = &g["features"][0];
    assert_eq!(path["geometry"]["type"], "LineString");
    let coords = path["geometry"]["coordinates"].as_array().context("coordinates")?;
    assert_eq!(coords.len(), w.len());
    for (c, p) in coords.iter().zip(w) {
        assert_eq!((c[0].as_f64(), c[1].as_f64()), (Some(p.x), Some(p.y)));
    }
    let vs: Vec<f64> = serde_json::from_value(path["properties"]["v"].clone())?;
    let ts: Vec<f64> = serde_json::from_value(path["properties"]["t"].clone())?;
    assert_eq!(vs, w.iter().map(|p| p.v).collect::<Vec<_>>());
    assert_eq!(ts, w.iter().map(|p| p.t).collect::<Vec<_>>());
    assert_eq!(g["features"].as_array().map(Vec::len), Some(1 + doc.regions.len()));

    // CSV on stdout: header, then one row per waypoint with the same values.
    let csv = ok(b, &["export", id, "--format", "csv"]).await?;
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("x,y,v,t,kind"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), w.len());
    for (row, p) in rows.iter().zip(w) {
        let f: Vec<&str> = row.split(',').collect();
        let num = |i: usize| f[i].parse::<f64>().ok();
        assert_eq!(
            (num(0), num(1), num(2), num(3)),
            (Some(p.x), Some(p.y), Some(p.v), Some(p.t)),
            "{row}"
        );
        let kind = if p.kind == WaypointKindDoc::Cover {
            "cover"
        } else {
            "transit"
        };
        assert_eq!(f[4], kind);
    }

    // nav_msgs/Path JSON: one pose per waypoint, unit quaternions facing the next waypoint.
    let nav: Value = serde_json::from_str(&ok(b, &["export", id, "--format", "nav-path"]).await?)?;
    assert_eq!(nav["header"]["frame_id"], doc.frame.as_str());
    let poses = nav["poses"].as_array().context("poses")?;
    assert_eq!(poses.len(), w.len());
    for (i, pose) in poses.iter().enumerate().take(w.len() - 1) {
        let p = &pose["pose"];
        assert_eq!(p["position"]["x"].as_f64(), Some(w[i].x));
        let (qz, qw) = (
            p["orientation"]["z"].as_f64().unwrap_or(9.0),
            p["orientation"]["w"].as_f64().unwrap_or(9.0),
        );
        assert!((qz * qz + qw * qw - 1.0).abs() < 1e-9);
        let yaw = 2.0 * qz.atan2(qw);
        let (dx, dy) = (w[i + 1].x - w[i].x, w[i + 1].y - w[i].y);
        if dx.hypot(dy) > 1e-9 {
            let d = (yaw - dy.atan2(dx)).rem_euclid(std::f64::consts::TAU);
            assert!(
                !(1e-6..=std::f64::consts::TAU - 1e-6).contains(&d),
                "pose {i} yaw {yaw}"
            );
        }
    }
    Ok(())
}

async fn render_draws_the_plan(b: &str, id: &str, dir: &Path) -> Result<()> {
    let png = dir.join("plan.png");
    let out: Value = json(b, &["render", id, png.to_str().context("path")?, "--size", "600"]).await?;
    let img = image::open(&png)?.to_rgb8();
    let (w, h) = img.dimensions();
    assert_eq!(
        (Some(u64::from(w)), Some(u64::from(h))),
        (out["width"].as_u64(), out["height"].as_u64())
    );
    // The four-rooms map is square-ish: the long side is 600 px, plus the colour-bar strip.
    assert!(w > 600 && w <= 700 && h > 100 && h <= 600, "{w} × {h}");
    let colours: HashSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    assert!(colours.len() >= 50, "only {} distinct colours", colours.len());
    // Path pixels: saturated colours of the speed ramp (map pixels are grey, regions' outlines are few).
    let saturated = img
        .pixels()
        .filter(|p| {
            let [r, g, b] = p.0;
            r.max(g).max(b) - r.min(g).min(b) > 120
        })
        .count();
    assert!(saturated > 2000, "{saturated} path pixels");
    let dark = img.pixels().filter(|p| p.0.iter().all(|&c| c < 60)).count();
    assert!(dark > 1000, "the map's walls are drawn ({dark} dark pixels)");
    Ok(())
}
