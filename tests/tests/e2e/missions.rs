//! Missions from the outside (issue 20): a backend uploads its own site (the shared `warehouse` scene) and asks
//! for one mission for three robots; the robots are separate Zenoh participants that fetch their plans as
//! robots do and drive them by odometry; the daemon measures what their tools swept. Bad requests are refused
//! naming the field, with nothing stored; a restart restores the mission and the measured raster.

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use serde_json::{Value, json};
use shift_tests::TestServer;
use shift_tests::fleet::{LONG, ScriptedRobot, fleet_config, poll, wait_robot_alive};

/// The robots and their docks: spread over the warehouse's free floor (a corner, the far corner, the middle
/// aisle), as a backend names its docks.
const ROBOTS: [(&str, [f64; 2]); 3] = [("wh1", [1.0, 1.0]), ("wh2", [38.0, 23.0]), ("wh3", [20.0, 12.0])];

async fn upload_warehouse(server: &TestServer) -> Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenarios/warehouse");
    let yaml = std::fs::read_to_string(dir.join("map.yaml"))?;
    let image = std::fs::read(dir.join("map.pgm"))?;
    let form = reqwest::multipart::Form::new()
        .part("yaml", reqwest::multipart::Part::text(yaml))
        .part("image", reqwest::multipart::Part::bytes(image).file_name("map.pgm"));
    let r = server
        .http
        .post(server.url("/v1/sites/warehouse/map"))
        .multipart(form)
        .send()
        .await?;
    if !r.status().is_success() {
        bail!("warehouse upload: {} {}", r.status(), r.text().await?);
    }
    Ok(())
}

fn robot(id: &str, start: [f64; 2]) -> Value {
    json!({"id": id, "start": start, "radius": 0.3, "tool_width": 0.6})
}

fn mission_body(robots: &[(&str, [f64; 2])]) -> Value {
    json!({"site": "warehouse", "robots": robots.iter().map(|(id, s)| robot(id, *s)).collect::<Vec<_>>()})
}

async fn refused(server: &TestServer, body: &Value, code: u16, says: &str) -> Result<()> {
    let (got, answer) = server.post("/v1/missions", body).await?;
    let message = answer["error"]["message"].as_str().unwrap_or_default();
    if got != code || !message.contains(says) {
        bail!("expected {code} saying {says:?}, got {got} {answer}");
    }
    Ok(())
}

/// Drives `doc`'s path by odometry every 0.4 m (10 poses per simulated second at 4 m/s, sent as fast as the
/// loopback takes them, a pause every few poses so the daemon's inbox is not flooded).
async fn drive(robot: &ScriptedRobot, name: &str, doc: &shift_proto::PlanDocument) -> Result<()> {
    let w = &doc.waypoints;
    let mut sent = 0usize;
    for pair in w.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let len = (b.x - a.x).hypot(b.y - a.y);
        let yaw = (b.y - a.y).atan2(b.x - a.x);
        let n = (len / 0.4).ceil().max(1.0) as usize;
        for k in 0..n {
            let f = k as f64 / n as f64;
            robot
                .odom(name, a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, yaw)
                .await?;
            sent += 1;
            if sent.is_multiple_of(16) {
                tokio::time::sleep(Duration::from_millis(4)).await;
            }
        }
    }
    if let Some(last) = w.last() {
        for _ in 0..3 {
            robot.odom(name, last.x, last.y, 0.0).await?;
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }
    Ok(())
}

fn swept_cells(grid: &Value) -> usize {
    grid["cells"]
        .as_array()
        .map_or(0, |c| c.iter().filter(|v| v.as_i64() == Some(100)).count())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_mission_on_a_backends_site_is_divided_planned_driven_measured_and_restored() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (config, endpoint) = fleet_config(dir.path())?;
    let server = TestServer::start(config.clone()).await?;
    upload_warehouse(&server).await?;

    // Refused, naming the field; nothing stored.
    let mut dup = mission_body(&ROBOTS);
    dup["robots"][2]["id"] = json!("wh1");
    refused(&server, &dup, 400, "robots[2].id \"wh1\" is named twice").await?;
    refused(&server, &mission_body(&[]), 400, "robots must name at least one robot").await?;
    refused(&server, &mission_body(&[("wh1", [0.05, 0.05])]), 400, "robots[0].start").await?;
    refused(
        &server,
        &mission_body(&[("wh1", [1.0, 1.0]), ("wh2", [99.0, 1.0])]),
        400,
        "robots[1] (wh2)",
    )
    .await?;
    let mut nan = mission_body(&ROBOTS);
    nan["robots"][1]["tool_width"] = json!(-1.0);
    refused(&server, &nan, 400, "robots[1] (wh2): tool_width must be positive").await?;
    let mut elsewhere = mission_body(&ROBOTS);
    elsewhere["site"] = json!("nowhere");
    refused(&server, &elsewhere, 404, "unknown site").await?;
    let (_, listed) = server.get("/v1/plans?site=warehouse").await?;
    assert_eq!(listed["items"].as_array().map(Vec::len), Some(0), "{listed}");
    assert_eq!(server.get("/v1/missions/m-404").await?.0, 404);

    // Accepted, divided and planned.
    let (code, accepted) = server.post("/v1/missions", &mission_body(&ROBOTS)).await?;
    assert_eq!(code, 202, "{accepted}");
    assert_eq!(accepted["status"], "queued");
    let id = accepted["mission_id"].as_str().context("mission_id")?.to_owned();
    let path = format!("/v1/missions/{id}");
    let ready = poll(
        async || {
            let (_, m) = server.get(&path).await?;
            match m["status"].as_str() {
                Some("ready") => Ok(Some(m)),
                Some("failed") => bail!("mission failed: {m}"),
                _ => Ok(None),
            }
        },
        "the mission to be planned",
    )
    .await?;
    let plans = ready["plans"].as_array().context("plans")?.clone();
    assert_eq!(plans.len(), 3);
    assert!(
        ready["coverage"]["planned_pct"].as_f64().is_some_and(|p| p >= 99.0),
        "{ready}"
    );
    assert!(
        ready["coverage"]["seam_pct"].as_f64().is_some_and(|p| p <= 5.0),
        "{ready}"
    );
    assert!(ready["eta_s"].as_f64().is_some_and(|t| t > 0.0), "{ready}");
    let mut area = 0.0;
    for (p, (name, _)) in plans.iter().zip(ROBOTS) {
        assert_eq!(p["robot"], name);
        area += p["area_m2"].as_f64().context("area")?;
        let plan_id = p["plan_id"].as_str().context("plan_id")?;
        // Each part is an ordinary plan, which names its mission.
        let (_, plan) = server.get(&format!("/v1/plans/{plan_id}")).await?;
        assert_eq!(plan["status"], "ready");
        assert_eq!(plan["mission"], id.as_str());
        assert_eq!(p["planned_duration_s"], plan["metrics"]["duration_s"]);
    }
    // The parts hold the warehouse's floor between them (40 m × 25 m less racks and walls).
    assert!((500.0..1000.0).contains(&area), "{area} m²");

    // The robots join as robots do, the backend assigns the mission, each robot fetches its plan.
    let mut robots = Vec::new();
    for (name, _) in ROBOTS {
        robots.push(ScriptedRobot::join(&endpoint, name).await?);
        wait_robot_alive(&server, name).await?;
    }
    let (code, active) = server.post(&format!("{path}/assign"), &json!({})).await?;
    assert_eq!(code, 200, "{active}");
    assert_eq!(active["status"], "active");
    let mut docs = Vec::new();
    for ((name, _), r) in ROBOTS.iter().zip(&robots) {
        let doc = r.query_plan(name, Duration::from_secs(10)).await?;
        let expected = plans
            .iter()
            .find(|p| p["robot"] == *name)
            .and_then(|p| p["plan_id"].as_str());
        assert_eq!(Some(doc.plan_id.as_str()), expected, "{name} got its own part");
        docs.push(doc);
    }
    // They drive at once.
    let drives = ROBOTS
        .iter()
        .zip(&robots)
        .zip(&docs)
        .map(|(((name, _), r), doc)| drive(r, name, doc));
    for result in futures_util::future::join_all(drives).await {
        result?;
    }
    let done = poll(
        async || {
            let (_, m) = server.get(&path).await?;
            Ok((m["status"] == "done").then_some(m))
        },
        "the mission to be done",
    )
    .await?;
    let measured = done["coverage"]["measured_pct"].as_f64().context("measured")?;
    eprintln!(
        "mission {id}: planned {} %, seams {} %, measured {measured:.2} %, durations {:?} s",
        done["coverage"]["planned_pct"],
        done["coverage"]["seam_pct"],
        plans
            .iter()
            .map(|p| p["planned_duration_s"].as_f64().unwrap_or(0.0).round())
            .collect::<Vec<_>>()
    );
    assert!(
        measured >= 98.0,
        "the robots' tools swept {measured} % of the mission: {done}"
    );
    assert_eq!(done["progress"].as_f64(), Some(1.0));
    assert_eq!(done["eta_s"].as_f64(), Some(0.0));

    // The site's raster: JSON like an OccupancyGrid, and a PNG.
    let (code, grid) = server.get("/v1/sites/warehouse/coverage").await?;
    assert_eq!(code, 200);
    assert_eq!(
        (grid["width"].as_u64(), grid["height"].as_u64()),
        (Some(400), Some(250))
    );
    let swept = swept_cells(&grid);
    assert!(swept > 50_000, "{swept} cells of 0.01 m² swept");
    let png = server
        .http
        .get(server.url("/v1/sites/warehouse/coverage?format=png"))
        .send()
        .await?;
    assert_eq!(
        png.headers().get("content-type").and_then(|v| v.to_str().ok()),
        Some("image/png")
    );
    let png = png.bytes().await?;
    assert!(png.starts_with(b"\x89PNG") && png.len() > 1_000, "{} bytes", png.len());
    assert_eq!(server.get("/v1/sites/warehouse/coverage?format=gif").await?.0, 400);

    // A restart restores the mission and what was swept.
    drop(robots);
    server.stop().await?;
    let server = TestServer::start(config).await?;
    let (_, again) = server.get(&path).await?;
    assert_eq!(again["status"], "done", "{again}");
    assert_eq!(again["coverage"]["measured_pct"].as_f64(), Some(measured));
    let (_, grid) = server.get("/v1/sites/warehouse/coverage").await?;
    assert_eq!(swept_cells(&grid), swept, "the raster survived the restart");
    assert_eq!(server.delete(&path).await?.0, 409, "a done mission cannot be cancelled");
    server.stop().await?;
    Ok(())
}

/// A robot as a backend's robot software drives: it follows its plan by odometry and, when a new version of
/// its plan arrives on its plan key (a replan), drops what it drives and follows the new one from its start;
/// it stops for good once `stop_at` of its plan is driven (killed), else at the end of its latest version.
async fn follow(
    robot: ScriptedRobot,
    name: &str,
    first: shift_proto::PlanDocument,
    stop_at: Option<f64>,
) -> Result<u64> {
    let updates = robot
        .session
        .declare_subscriber(format!("shift/default/robots/{name}/plan"))
        .await
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut doc = first;
    'plan: loop {
        let w = doc.waypoints.clone();
        let total: f64 = w.windows(2).map(|p| (p[1].x - p[0].x).hypot(p[1].y - p[0].y)).sum();
        let mut driven = 0.0;
        let mut sent = 0usize;
        for pair in w.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let len = (b.x - a.x).hypot(b.y - a.y);
            let yaw = (b.y - a.y).atan2(b.x - a.x);
            let n = (len / 0.4).ceil().max(1.0) as usize;
            for k in 0..n {
                let f = k as f64 / n as f64;
                if stop_at.is_some_and(|s| driven + f * len >= s * total) {
                    drop(robot);
                    return Ok(doc.version);
                }
                robot
                    .odom(name, a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, yaw)
                    .await?;
                sent += 1;
                if sent.is_multiple_of(16) {
                    tokio::time::sleep(Duration::from_millis(4)).await;
                    if let Ok(Some(sample)) = updates.try_recv() {
                        let next: shift_proto::PlanDocument = serde_json::from_slice(&sample.payload().to_bytes())?;
                        if next.version > doc.version {
                            doc = next;
                            continue 'plan;
                        }
                    }
                }
            }
            driven += len;
        }
        // At the end: stand there (odometry goes on) until a newer version comes or a while passes.
        let deadline = tokio::time::Instant::now() + Duration::from_secs(8);
        if let Some(last) = w.last() {
            while tokio::time::Instant::now() < deadline {
                robot.odom(name, last.x, last.y, 0.0).await?;
                if let Ok(Some(sample)) = updates.try_recv() {
                    let next: shift_proto::PlanDocument = serde_json::from_slice(&sample.payload().to_bytes())?;
                    if next.version > doc.version {
                        doc = next;
                        continue 'plan;
                    }
                }
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
        }
        return Ok(doc.version);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_killed_at_thirty_percent_hands_its_rest_to_the_others_who_finish() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (config, endpoint) = fleet_config(dir.path())?;
    let server = TestServer::start(config).await?;
    upload_warehouse(&server).await?;
    let (_, accepted) = server.post("/v1/missions", &mission_body(&ROBOTS)).await?;
    let id = accepted["mission_id"].as_str().context("mission_id")?.to_owned();
    let path = format!("/v1/missions/{id}");
    poll(
        async || {
            let (_, m) = server.get(&path).await?;
            Ok((m["status"] == "ready").then_some(()))
        },
        "the mission to be planned",
    )
    .await?;
    let mut robots = Vec::new();
    for (name, _) in ROBOTS {
        robots.push(ScriptedRobot::join(&endpoint, name).await?);
        wait_robot_alive(&server, name).await?;
    }
    let (code, _) = server.post(&format!("{path}/assign"), &json!({})).await?;
    assert_eq!(code, 200);
    let mut tasks = Vec::new();
    for ((name, _), r) in ROBOTS.iter().zip(robots) {
        let doc = r.query_plan(name, Duration::from_secs(10)).await?;
        // wh3 is killed (its session and token gone) at 30 % of its plan.
        let stop = (*name == "wh3").then_some(0.3);
        tasks.push(tokio::spawn(follow(r, name, doc, stop)));
    }
    let mut versions = Vec::new();
    for t in tasks {
        versions.push(t.await??);
    }
    assert_eq!(versions[2], 1, "wh3 was killed on its first version");
    assert!(
        versions[..2].iter().all(|&v| v >= 2),
        "the others got new versions: {versions:?}"
    );
    let done = poll(
        async || {
            let (_, m) = server.get(&path).await?;
            Ok((m["status"] == "done").then_some(m))
        },
        "the mission to be done",
    )
    .await?;
    let measured = done["coverage"]["measured_pct"].as_f64().context("measured")?;
    eprintln!(
        "killed at 30 %: versions {versions:?}, measured {measured:.2} %, warnings {}",
        done["warnings"]
    );
    if let Ok(dir) = std::env::var("SHIFT_TEST_ARTIFACTS") {
        let png = server
            .http
            .get(server.url("/v1/sites/warehouse/coverage?format=png"))
            .send()
            .await?
            .bytes()
            .await?;
        std::fs::write(Path::new(&dir).join("mission_killed_coverage.png"), &png)?;
        for p in done["plans"].as_array().context("plans")? {
            let pid = p["plan_id"].as_str().unwrap_or_default();
            let (_, doc) = server.get(&format!("/v1/plans/{pid}")).await?;
            eprintln!("{pid}: {}", doc["metrics"]);
        }
    }
    assert!(measured >= 98.0, "{measured} % swept: {done}");
    let plans = done["plans"].as_array().context("plans")?;
    assert_eq!(plans[2]["status"], "cancelled", "wh3's part went to the others: {done}");
    assert!(done["warnings"].to_string().contains("robot wh3 lost"), "{done}");
    // The others resumed their own plans and took wh3's unfinished lanes over (no new division).
    assert!(done["warnings"].to_string().contains("handed over"), "{done}");
    server.stop().await?;
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_mission_is_followed_over_sse_and_cancelled_with_its_plans() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (config, _) = fleet_config(dir.path())?;
    let server = TestServer::start(config).await?;
    upload_warehouse(&server).await?;
    let (_, accepted) = server.post("/v1/missions", &mission_body(&ROBOTS[..2])).await?;
    let id = accepted["mission_id"].as_str().context("mission_id")?.to_owned();
    let mut events = server
        .http
        .get(server.url(&format!("/v1/missions/{id}/events")))
        .send()
        .await?;
    assert_eq!(events.status().as_u16(), 200);
    // Read `mission` events until the mission is ready.
    let mut text = String::new();
    let deadline = tokio::time::Instant::now() + LONG;
    while !text.contains("\"status\":\"ready\"") {
        let chunk = tokio::time::timeout_at(deadline, events.chunk())
            .await
            .context("no ready event in time")??
            .context("stream ended before ready")?;
        text.push_str(&String::from_utf8_lossy(&chunk));
    }
    assert!(text.starts_with("event: mission\n"), "{text}");
    let statuses: Vec<&str> = ["queued", "planning", "ready"]
        .into_iter()
        .filter(|s| text.contains(&format!("\"status\":\"{s}\"")))
        .collect();
    assert!(statuses.ends_with(&["ready"]), "{statuses:?}: {text}");
    // A third robot joins the planned mission: refused naming the field when its dock is bad, else it gets a
    // plan of its own from a replan of what is left.
    let joins = format!("/v1/missions/{id}/robots");
    let (code, bad) = server.post(&joins, &robot("wh9", [0.05, 0.05])).await?;
    assert_eq!(code, 400, "{bad}");
    assert!(
        bad["error"]["message"]
            .as_str()
            .unwrap_or_default()
            .contains("robots[2].start"),
        "{bad}"
    );
    let (code, joined) = server.post(&joins, &robot("wh9", ROBOTS[2].1)).await?;
    assert_eq!(code, 202, "{joined}");
    let grown = poll(
        async || {
            let (_, m) = server.get(&format!("/v1/missions/{id}")).await?;
            let ready = m["plans"].as_array().is_some_and(|p| {
                p.len() == 3
                    && p.iter()
                        .all(|p| p["status"] == "ready" && p["area_m2"].as_f64() > Some(0.0))
            });
            Ok(ready.then_some(m))
        },
        "the joined robot's share",
    )
    .await?;
    assert_eq!(grown["plans"][2]["robot"], "wh9", "{grown}");
    let (code, cancelled) = server.delete(&format!("/v1/missions/{id}")).await?;
    assert_eq!(code, 200, "{cancelled}");
    assert_eq!(cancelled["status"], "cancelled");
    for p in cancelled["plans"].as_array().context("plans")? {
        assert_eq!(p["status"], "cancelled", "{p}");
    }
    assert_eq!(
        server.post(&format!("/v1/missions/{id}/assign"), &json!({})).await?.0,
        409
    );
    server.stop().await?;
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recorded_mission_replays_to_the_same_division_and_replan() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (mut config, endpoint) = fleet_config(&dir.path().join("data"))?;
    let record_dir = dir.path().join("rec");
    config.record.dir = record_dir.clone();
    config.demo.enabled = true;
    let server = TestServer::start(config).await?;
    let robot = |id: &str, start: [f64; 2]| json!({"id": id, "start": start, "radius": 0.15, "tool_width": 0.3});
    let body = json!({"site": "demo", "robots": [robot("d1", [0.5, 0.5]), robot("d2", [7.5, 7.5])]});
    let (code, accepted) = server.post("/v1/missions", &body).await?;
    assert_eq!(code, 202, "{accepted}");
    let id = accepted["mission_id"].as_str().context("mission_id")?.to_owned();
    let path = format!("/v1/missions/{id}");
    poll(
        async || {
            let (_, m) = server.get(&path).await?;
            Ok((m["status"] == "ready").then_some(()))
        },
        "the mission to be planned",
    )
    .await?;
    let (d1, d2) = (
        ScriptedRobot::join(&endpoint, "d1").await?,
        ScriptedRobot::join(&endpoint, "d2").await?,
    );
    wait_robot_alive(&server, "d1").await?;
    wait_robot_alive(&server, "d2").await?;
    assert_eq!(server.post(&format!("{path}/assign"), &json!({})).await?.0, 200);
    let doc1 = d1.query_plan("d1", Duration::from_secs(10)).await?;
    let doc2 = d2.query_plan("d2", Duration::from_secs(10)).await?;
    for (r, name, doc) in [(&d1, "d1", &doc1), (&d2, "d2", &doc2)] {
        for w in doc.waypoints.iter().take(doc.waypoints.len() / 3) {
            r.odom(name, w.x, w.y, 0.0).await?;
        }
    }
    // d2 leaves: its rest goes to d1, who gets version 2.
    drop(d2);
    poll(
        async || {
            let (_, m) = server.get(&path).await?;
            Ok((m["plans"][0]["version"].as_u64() == Some(2)).then_some(()))
        },
        "d1's plan replanned after d2 left",
    )
    .await?;
    drop(d1);
    server.stop().await?;

    // The recording replays through the engine to the same decisions: the division and the replan come back
    // as the jobs' recorded outcomes, every decision around them is the engine's own again.
    let files = shiftd::record::writer::recordings_in(&record_dir)?;
    let rec = shiftd::replay::Recorded::read(&files)?;
    let mut out = Vec::new();
    let report = shiftd::replay::into_engine(&rec, &mut out, true)?;
    assert!(report.mismatches.is_empty(), "{:#?}", report.mismatches);
    let text = String::from_utf8(out)?;
    for kind in [
        "\"start_mission\"",
        "\"store_mission\"",
        "\"replace_plan\"",
        "\"mission\"",
    ] {
        assert!(text.contains(kind), "no {kind} decision replayed");
    }
    assert_eq!(
        text.matches("\"start_mission\"").count(),
        2,
        "the division and one replan"
    );
    Ok(())
}
