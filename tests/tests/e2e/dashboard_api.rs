//! What the operator's page reads, from outside: the page itself, a site's event stream, its live points and a
//! plan's corrections. Two sites, each with a robot driving a plan as a separate Zenoh participant; the hall's
//! stream sees the hall's robot move, its plan corrected after an obstacle and its live map grow, and nothing
//! of the yard.

use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail, ensure};
use serde_json::{Value, json};
use shift_proto::PlanDocument;
use shift_tests::TestServer;
use shift_tests::fleet::{ScriptedRobot, fleet_config, room_grid};
use shift_tests::path::{along, longest_straight, post};
use shift_tests::sse::SseReader;

const LONG: Duration = Duration::from_secs(120);
const SHORT: Duration = Duration::from_secs(15);

/// Plans on `site` from `start` and assigns the plan to `robot`; returns its id and document.
async fn assigned(server: &TestServer, site: &str, start: [f64; 2], robot: &str) -> Result<(String, PlanDocument)> {
    let req = json!({"site": site, "start": start, "robot": {"radius": 0.15, "tool_width": 0.3}});
    let (code, acc) = server.post("/v1/plans", &req).await?;
    ensure!(code == 202, "plan: {code} {acc}");
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    server.wait_plan(&id, LONG, |s| s == "ready").await?;
    let (code, st) = server
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": robot}))
        .await?;
    ensure!(code == 200, "assign: {code} {st}");
    let (_, served) = server.get(&format!("/v1/plans/{id}/path")).await?;
    Ok((id, serde_json::from_value(served)?))
}

/// Events of `reader` until `want` holds for one, failing after `within`.
async fn wait_for(
    reader: &mut SseReader,
    within: Duration,
    mut want: impl FnMut(&str, &Value) -> bool,
) -> Result<Vec<(String, Value)>> {
    let deadline = Instant::now() + within;
    let mut seen = Vec::new();
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let Some((name, value)) = reader.next(left).await? else {
            bail!("the stream ended; saw {seen:?}");
        };
        let done = want(&name, &value);
        seen.push((name, value));
        if done {
            return Ok(seen);
        }
    }
}

fn robots_named(v: &Value) -> Vec<String> {
    v["robots"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|r| r["robot"].as_str().map(str::to_owned))
                .collect()
        })
        .unwrap_or_default()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_site_stream_shows_its_robots_plans_corrections_and_live_points_only() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (config, endpoint) = fleet_config(dir.path())?;
    let server = TestServer::start(config).await?;
    for site in ["hall", "yard"] {
        let (code, body) = server
            .post(&format!("/v1/sites/{site}/map"), &room_grid(160, 80, 0.05, &[]))
            .await?;
        ensure!(code == 201, "{site}: {code} {body}");
    }
    // The page and its modules are served from the binary.
    let page = server.http.get(server.url("/")).send().await?;
    ensure!(page.status() == 200);
    let kind = page
        .headers()
        .get("content-type")
        .and_then(|v| v.to_str().ok())
        .map(str::to_owned);
    ensure!(kind.as_deref().is_some_and(|k| k.starts_with("text/html")), "{kind:?}");
    let html = page.text().await?;
    let script = html
        .split("src=\"/dashboard/")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .context("the page loads a script from /dashboard/")?
        .to_owned();
    let js = server
        .http
        .get(server.url(&format!("/dashboard/{script}")))
        .send()
        .await?;
    ensure!(js.status() == 200, "{script}: {}", js.status());
    let (code, _) = server.get("/dashboard/..%2FCargo.toml").await?;
    ensure!(code == 404, "only the page's own files are served: {code}");

    let hall_robot = ScriptedRobot::join(&endpoint, "r1").await?;
    let yard_robot = ScriptedRobot::join(&endpoint, "r2").await?;
    let (hall_plan, doc) = assigned(&server, "hall", [0.5, 0.5], "r1").await?;
    let (yard_plan, _) = assigned(&server, "yard", [0.5, 0.5], "r2").await?;
    yard_robot.odom("r2", 0.5, 0.5, 0.0).await?;

    let mut hall = SseReader::open(&server.http, &server.url("/v1/sites/hall/events")).await?;
    let mut yard = SseReader::open(&server.http, &server.url("/v1/sites/yard/events")).await?;
    let (first, summary) = hall.next(SHORT).await?.context("a first event")?;
    ensure!(first == "site" && summary["site"] == "hall", "{first} {summary}");

    // r1 drives to its longest lane and along its first metre; the stream shows it there.
    let w = &doc.waypoints;
    let seg = longest_straight(w);
    for k in (0..seg.0).step_by(4) {
        hall_robot.odom("r1", w[k].x, w[k].y, 0.0).await?;
    }
    let mut at = (0.0, 0.0, 0.0);
    for k in 0..5 {
        at = along(w, seg, 0.2 * k as f64);
        hall_robot.odom("r1", at.0, at.1, at.2).await?;
        tokio::time::sleep(Duration::from_millis(30)).await;
    }
    let seen = wait_for(&mut hall, SHORT, |name, v| {
        name == "robots"
            && v["robots"].as_array().is_some_and(|a| {
                a.iter().any(|r| {
                    r["robot"] == "r1"
                        && (r["pose"]["x"].as_f64().unwrap_or(f64::NAN) - at.0).abs() < 1e-6
                        && (r["pose"]["y"].as_f64().unwrap_or(f64::NAN) - at.1).abs() < 1e-6
                })
            })
    })
    .await?;
    for (name, v) in &seen {
        if name == "robots" {
            ensure!(
                !robots_named(v).contains(&"r2".to_owned()),
                "the yard's robot on the hall's stream: {v}"
            );
            ensure!(v["robots"][0]["plan_id"] == hall_plan.as_str(), "{v}");
        }
    }

    // A post on the lane 2 m ahead: the hall's stream carries the correction and a live map change.
    let (ox, oy, _) = along(w, seg, 0.8 + 2.0);
    hall_robot.cloud("r1", &post(ox, oy)).await?;
    let seen = wait_for(&mut hall, LONG, |name, v| {
        name == "correction" && v["plan_id"] == hall_plan.as_str()
    })
    .await?;
    let (_, correction) = seen.last().context("a correction")?;
    ensure!(
        correction["type"] == "correction" && correction["version"] == 2,
        "{correction}"
    );
    wait_for(&mut hall, SHORT, |name, v| {
        name == "live" && v["count"].as_u64().unwrap_or(0) > 0
    })
    .await?;

    // The live points are there, near the post; the corrections are kept for a page that opens later.
    let (code, live) = server.get("/v1/sites/hall/live?max_points=10").await?;
    ensure!(code == 200, "{code} {live}");
    let pts = live["points"].as_array().context("points")?;
    ensure!(!pts.is_empty() && pts.len() <= 10, "{live}");
    let count = live["count"].as_u64().unwrap_or(0);
    ensure!(live["truncated"] == (count > 10), "{live}");
    for p in pts {
        let (x, y) = (p[0].as_f64().unwrap_or(f64::NAN), p[1].as_f64().unwrap_or(f64::NAN));
        ensure!(
            (x - ox).hypot(y - oy) < 0.5,
            "live point ({x}, {y}) far from the post at ({ox}, {oy})"
        );
    }
    let (code, kept) = server.get(&format!("/v1/plans/{hall_plan}/corrections")).await?;
    ensure!(code == 200, "{code} {kept}");
    ensure!(
        kept[0]["version"] == 2 && kept[0]["plan_id"] == hall_plan.as_str(),
        "{kept}"
    );
    let (code, none) = server.get(&format!("/v1/plans/{yard_plan}/corrections")).await?;
    ensure!(
        code == 200 && none.as_array().is_some_and(Vec::is_empty),
        "{code} {none}"
    );
    let (code, yard_live) = server.get("/v1/sites/yard/live").await?;
    ensure!(code == 200 && yard_live["count"] == 0, "{yard_live}");
    for (path, want) in [
        ("/v1/sites/nowhere/live", 404),
        ("/v1/sites/hall/live?max_points=0", 400),
        ("/v1/sites/hall/live?points=3", 400),
        ("/v1/sites/nowhere/events", 404),
        ("/v1/plans/p-nope/corrections", 404),
    ] {
        let (code, body) = server.get(path).await?;
        ensure!(code == want, "{path}: {code} {body}");
    }

    // The yard's stream: its site, its robot, and nothing of the hall's.
    let mut yard_events = Vec::new();
    while let Ok(Some(e)) = yard.next(Duration::from_millis(1500)).await {
        yard_events.push(e);
    }
    ensure!(
        yard_events
            .first()
            .is_some_and(|(n, v)| n == "site" && v["site"] == "yard"),
        "{yard_events:?}"
    );
    ensure!(
        yard_events
            .iter()
            .any(|(n, v)| n == "robots" && robots_named(v) == ["r2".to_owned()]),
        "{yard_events:?}"
    );
    for (name, v) in &yard_events {
        let text = v.to_string();
        ensure!(
            !text.contains(&hall_plan) && !text.contains("\"r1\""),
            "hall's {name} on the yard's stream: {v}"
        );
    }

    // The new routes are in the API description.
    let (_, doc) = server.get("/openapi.json").await?;
    for path in [
        "/v1/sites/{site}/live",
        "/v1/sites/{site}/events",
        "/v1/plans/{id}/corrections",
    ] {
        ensure!(doc["paths"][path].is_object(), "{path} missing from openapi.json");
    }
    drop((hall_robot, yard_robot));
    server.stop().await
}
