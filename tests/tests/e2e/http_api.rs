//! End-to-end: shiftd in-process on 127.0.0.1:0, driven over HTTP.

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, Result};
use serde_json::{Value, json};
use shift_planner::geom::Point2;
use shift_planner::map::load_ros_map;
use shift_planner::metrics::evaluate;
use shift_planner::space::{CoverageSpace, RobotShape};
use shift_tests::sse::SseReader;
use shift_tests::{TestServer, demo_request, test_config};

const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/four-rooms-obstacles");
const LONG: Duration = Duration::from_secs(120);

fn fixture(name: &str) -> Result<Vec<u8>> {
    std::fs::read(Path::new(FIXTURE).join(name)).with_context(|| format!("fixture {name}"))
}

async fn upload_fixture(server: &TestServer, site: &str) -> Result<(u16, Value)> {
    let form = reqwest::multipart::Form::new()
        .part(
            "yaml",
            reqwest::multipart::Part::bytes(fixture("map.yaml")?).file_name("map.yaml"),
        )
        .part(
            "image",
            reqwest::multipart::Part::bytes(fixture("map.pgm")?).file_name("map.pgm"),
        );
    let r = server
        .http
        .post(server.url(&format!("/v1/sites/{site}/map")))
        .multipart(form)
        .send()
        .await?;
    let code = r.status().as_u16();
    Ok((code, r.json().await?))
}

fn request_on(site: &str) -> Value {
    let mut r = demo_request();
    r["site"] = json!(site);
    r
}

/// Reads SSE events (name, data) until `stop` says so or the stream ends.
async fn read_events(
    server: &TestServer,
    plan_id: &str,
    stop: impl Fn(&str, &Value) -> bool,
) -> Result<Vec<(String, Value)>> {
    let url = server.url(&format!("/v1/plans/{plan_id}/events"));
    SseReader::open(&server.http, &url).await?.until(LONG, stop).await
}

fn fixture_space() -> Result<CoverageSpace> {
    let yaml = String::from_utf8(fixture("map.yaml")?)?;
    let map = load_ros_map(&yaml, |_| fixture("map.pgm").map_err(|e| e.to_string()))?;
    Ok(CoverageSpace::new(
        map.grid,
        RobotShape {
            radius_m: 0.15,
            tool_width_m: 0.3,
        },
        Point2::new(0.5, 0.5),
    )?)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn upload_plan_poll_path_events_metrics() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;

    let (code, site) = upload_fixture(&server, "rooms").await?;
    assert_eq!(code, 201, "{site}");
    assert_eq!(site["site"], "rooms");
    assert_eq!(site["resolution"], 0.05);
    let (code, again) = server.get("/v1/sites/rooms").await?;
    assert_eq!(code, 200);
    assert_eq!(again["width"], site["width"]);

    // One worker: the first plan keeps it busy, so the second is seen from "queued" on.
    let (code, first) = server.post("/v1/plans", &request_on("rooms")).await?;
    assert_eq!(code, 202, "{first}");
    let mut second_req = request_on("rooms");
    second_req["options"] = json!({"decomposition": "bcd", "seed": 3});
    let r = server
        .http
        .post(server.url("/v1/plans"))
        .json(&second_req)
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 202);
    let location = r
        .headers()
        .get("location")
        .and_then(|v| v.to_str().ok())
        .map(str::to_owned);
    let second: Value = r.json().await?;
    let id = second["plan_id"].as_str().context("plan_id")?.to_owned();
    assert_eq!(second["status"], "queued");
    assert_eq!(location.as_deref(), Some(format!("/v1/plans/{id}").as_str()));

    let events = read_events(&server, &id, |name, v| name == "status" && v["status"] == "ready").await?;
    // In order: queued → planning → (progress…, region-ready…) → ready.
    let statuses: Vec<&str> = events
        .iter()
        .filter(|(n, _)| n == "status")
        .filter_map(|(_, v)| v["status"].as_str())
        .collect();
    assert_eq!(statuses, vec!["queued", "planning", "ready"], "{events:?}");
    let progress: Vec<f64> = events
        .iter()
        .filter(|(n, _)| n == "progress")
        .filter_map(|(_, v)| v["progress"].as_f64())
        .collect();
    assert!(!progress.is_empty(), "progress events");
    assert!(
        progress.windows(2).all(|w| w[0] < w[1]),
        "progress advances: {progress:?}"
    );
    let regions = events.iter().filter(|(n, _)| n == "region-ready").count();
    assert!(regions > 0, "region-ready events");
    let first_region = events.iter().position(|(n, _)| n == "region-ready");
    let planning = events
        .iter()
        .position(|(n, v)| n == "status" && v["status"] == "planning");
    assert!(planning < first_region);
    // Regions stream while the plan is still being linked: progress keeps advancing after the first one
    // (the rest are computing), and every region is announced before the plan is ready.
    let last_progress = events.iter().rposition(|(n, _)| n == "progress");
    assert!(regions > 1, "the test map decomposes into several regions: {events:?}");
    assert!(
        first_region < last_progress,
        "regions arrive while the job runs: {events:?}"
    );
    let ready = events.iter().position(|(n, v)| n == "status" && v["status"] == "ready");
    let last_region = events.iter().rposition(|(n, _)| n == "region-ready");
    assert!(last_region < ready);

    let status = server.wait_plan(&id, LONG, |s| s == "ready").await?;
    assert_eq!(status["progress"], 1.0);
    assert_eq!(status["regions_ready"].as_u64(), Some(regions as u64));
    let (code, path) = server.get(&format!("/v1/plans/{id}/path")).await?;
    assert_eq!(code, 200);
    assert_eq!(path["plan_id"], id.as_str());
    assert_eq!(path["frame"], "map");
    // Judge the served path with the shared metrics module, not with what the server claims.
    let pts: Vec<Point2> = path["waypoints"]
        .as_array()
        .context("waypoints")?
        .iter()
        .map(|w| Point2::new(w["x"].as_f64().unwrap_or(f64::NAN), w["y"].as_f64().unwrap_or(f64::NAN)))
        .collect();
    let m = evaluate(&fixture_space()?, &pts);
    assert!(m.coverage_pct >= 99.0, "coverage {}", m.coverage_pct);
    assert_eq!(m.collisions, 0);
    assert!((path["metrics"]["coverage_pct"].as_f64().unwrap_or(0.0) - m.coverage_pct).abs() < 1e-9);

    let (code, profile) = server.get(&format!("/v1/plans/{id}/speed-profile")).await?;
    assert_eq!(code, 200);
    let samples = profile["samples"].as_array().context("samples")?;
    assert_eq!(samples.len(), pts.len());
    let s: Vec<f64> = samples.iter().filter_map(|x| x["s"].as_f64()).collect();
    let t: Vec<f64> = samples.iter().filter_map(|x| x["t"].as_f64()).collect();
    assert!(s.windows(2).all(|w| w[1] >= w[0]) && t.windows(2).all(|w| w[1] >= w[0]));
    assert!((s[s.len() - 1] - m.length_m).abs() < 1e-6);

    // The first plan finished too; a path of an unknown plan is 404.
    server
        .wait_plan(first["plan_id"].as_str().context("id")?, LONG, |s| s == "ready")
        .await?;
    assert_eq!(server.get("/v1/plans/p-999/path").await?.0, 404);

    let text = server.http.get(server.url("/metrics")).send().await?.text().await?;
    assert!(text.contains("shift_http_requests_total"), "{text}");
    assert!(text.contains("route=\"/v1/plans/{id}\""), "requests by route template");
    assert!(text.contains("shift_plan_compute_seconds"));
    assert!(text.contains("shift_plan_queue_depth"));
    assert!(text.contains("shift_plans{status=\"ready\"}"));

    let (code, api) = server.get("/openapi.json").await?;
    assert_eq!(code, 200);
    for p in [
        "/v1/plans",
        "/v1/plans/{id}",
        "/v1/plans/{id}/events",
        "/v1/sites/{site}/map",
    ] {
        assert!(api["paths"][p].is_object(), "openapi lacks {p}");
    }
    assert!(api["components"]["schemas"]["PlanRequest"].is_object());
    let docs = server.http.get(server.url("/docs")).send().await?.text().await?;
    assert!(docs.contains("/openapi.json"));
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn demo_site_plans_with_embedded_defaults() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let (code, site) = server.get("/v1/sites/demo").await?;
    assert_eq!(code, 200, "{site}");
    let (code, acc) = server.post("/v1/plans", &demo_request()).await?;
    assert_eq!(code, 202, "{acc}");
    let id = acc["plan_id"].as_str().context("id")?;
    let st = server.wait_plan(id, LONG, |s| s != "queued" && s != "planning").await?;
    assert_eq!(st["status"], "ready", "{st}");
    assert!(st["metrics"]["coverage_pct"].as_f64().unwrap_or(0.0) >= 99.0);
    // The areas say how much of the site the start leads to: on the demo site, all of it that a robot fits.
    let area = |k: &str| st["metrics"][k].as_f64().unwrap_or(f64::NAN);
    let (reach, cover, free) = (
        area("reachable_area_m2"),
        area("coverable_area_m2"),
        area("free_area_m2"),
    );
    assert!(reach > 0.0 && reach < cover && cover <= free, "{st}");
    // Another objective is a request away; an unknown one is refused naming the field.
    let mut turns = demo_request();
    turns["objective"] = json!("turns");
    turns["snap_start_m"] = json!(1.0);
    let (code, acc) = server.post("/v1/plans", &turns).await?;
    assert_eq!(code, 202, "{acc}");
    let id = acc["plan_id"].as_str().context("id")?;
    let st = server.wait_plan(id, LONG, |s| s != "queued" && s != "planning").await?;
    assert_eq!(st["status"], "ready", "{st}");
    let mut bad = demo_request();
    bad["objective"] = json!("fastest");
    let (code, body) = server.post("/v1/plans", &bad).await?;
    assert_eq!(code, 400, "{body}");
    assert!(
        body["error"]["message"].as_str().unwrap_or("").contains("objective"),
        "{body}"
    );
    let mut bad = demo_request();
    bad["snap_start_m"] = json!(-1.0);
    let (code, body) = server.post("/v1/plans", &bad).await?;
    assert_eq!(code, 400, "{body}");
    assert!(
        body["error"]["message"].as_str().unwrap_or("").contains("snap_start_m"),
        "{body}"
    );
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancel_and_every_error_code() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.jobs.queue_capacity = 1;
    config.http.max_body_bytes = 64 * 1024;
    let server = TestServer::start(config).await?;

    // 429: one running, one waiting, the next is refused.
    let (c1, running) = server.post("/v1/plans", &demo_request()).await?;
    let (c2, queued) = server.post("/v1/plans", &demo_request()).await?;
    let (c3, full) = server.post("/v1/plans", &demo_request()).await?;
    assert_eq!((c1, c2, c3), (202, 202, 429), "{full}");
    assert_eq!(full["error"]["code"], "queue_full");
    let running = running["plan_id"].as_str().context("id")?.to_owned();
    let queued = queued["plan_id"].as_str().context("id")?.to_owned();

    // Cancel the waiting one, then the running one; both answer at once and stay cancelled.
    let (code, body) = server.delete(&format!("/v1/plans/{queued}")).await?;
    assert_eq!((code, body["status"].as_str()), (200, Some("cancelled")));
    let (code, body) = server.delete(&format!("/v1/plans/{running}")).await?;
    assert_eq!(code, 200, "{body}");
    assert_eq!(body["status"], "cancelled");
    // 409: cancelling again; the path of a cancelled plan.
    let (code, body) = server.delete(&format!("/v1/plans/{running}")).await?;
    assert_eq!((code, body["error"]["code"].as_str()), (409, Some("invalid_state")));
    assert_eq!(server.get(&format!("/v1/plans/{running}/path")).await?.0, 409);
    // The worker is freed promptly: a new plan gets computed.
    let (code, next) = server.post("/v1/plans", &demo_request()).await?;
    assert_eq!(code, 202);
    let next = next["plan_id"].as_str().context("id")?.to_owned();
    server.wait_plan(&next, LONG, |s| s == "ready").await?;
    assert_eq!(
        server.get(&format!("/v1/plans/{running}")).await?.1["status"],
        "cancelled"
    );

    // 400s: malformed JSON, unknown field, negative radius, start outside the map, bad option.
    let r = server
        .http
        .post(server.url("/v1/plans"))
        .header("content-type", "application/json")
        .body("{\"site\": ")
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 400);
    let body: Value = r.json().await?;
    assert!(body["error"]["message"].as_str().is_some_and(|m| !m.is_empty()));
    let mut bad = demo_request();
    bad["extra"] = json!(1);
    assert_eq!(server.post("/v1/plans", &bad).await?.0, 400);
    let mut bad = demo_request();
    bad["robot"]["radius"] = json!(-0.1);
    let (code, body) = server.post("/v1/plans", &bad).await?;
    assert_eq!(code, 400);
    assert!(
        body["error"]["message"].as_str().unwrap_or("").contains("robot.radius"),
        "{body}"
    );
    let mut bad = demo_request();
    bad["start"] = json!([1e6, 0.5]);
    let (code, body) = server.post("/v1/plans", &bad).await?;
    assert_eq!(code, 400);
    assert!(
        body["error"]["message"]
            .as_str()
            .unwrap_or("")
            .contains("outside the map")
    );
    let r = server
        .http
        .post(server.url("/v1/plans"))
        .header("content-type", "application/json")
        .body(r#"{"site":"demo","start":[NaN,0.5],"robot":{"radius":0.15,"tool_width":0.3}}"#)
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 400);
    let mut bad = demo_request();
    bad["options"] = json!({"order": "fastest"});
    assert_eq!(server.post("/v1/plans", &bad).await?.0, 400);
    // A map that is not a map.
    let r = server
        .http
        .post(server.url("/v1/sites/x/map"))
        .json(&json!({"resolution": -1, "origin": [0, 0], "width": 1, "height": 1, "cells": [0]}))
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 400);
    let r = server
        .http
        .post(server.url("/v1/sites/x/map"))
        .body("hello")
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 415);

    // 404s.
    assert_eq!(server.get("/v1/plans/p-nope").await?.0, 404);
    assert_eq!(server.delete("/v1/plans/p-nope").await?.0, 404);
    assert_eq!(server.get("/v1/sites/nope").await?.0, 404);
    assert_eq!(server.post("/v1/plans", &request_on("nope")).await?.0, 404);
    let (code, body) = server.get("/v1/nothing").await?;
    assert_eq!((code, body["error"]["code"].as_str()), (404, Some("not_found")));

    // 413: a body over the configured limit.
    let cells = vec![0; 200 * 200];
    let big = json!({"resolution": 0.1, "origin": [0, 0], "width": 200, "height": 200, "cells": cells});
    let r = server
        .http
        .post(server.url("/v1/sites/big/map"))
        .json(&big)
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 413);
    let body: Value = r.json().await?;
    assert_eq!(body["error"]["code"], "payload_too_large");
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bearer_token_guards_mutating_routes() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.http.auth_token = "s3cret".into();
    let server = TestServer::start(config).await?;
    let (code, body) = server.post("/v1/plans", &demo_request()).await?;
    assert_eq!((code, body["error"]["code"].as_str()), (401, Some("unauthorized")));
    let r = server
        .http
        .post(server.url("/v1/plans"))
        .bearer_auth("wrong")
        .json(&demo_request())
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 403);
    let r = server
        .http
        .post(server.url("/v1/plans"))
        .bearer_auth("s3cret")
        .json(&demo_request())
        .send()
        .await?;
    assert_eq!(r.status().as_u16(), 202);
    let id = r.json::<Value>().await?["plan_id"].as_str().context("id")?.to_owned();
    // Reads stay open.
    assert_eq!(server.get(&format!("/v1/plans/{id}")).await?.0, 200);
    assert_eq!(server.delete(&format!("/v1/plans/{id}")).await?.0, 401);
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn restart_serves_finished_plans_and_requeues_interrupted_ones() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let (_, done) = server.post("/v1/plans", &demo_request()).await?;
    let done = done["plan_id"].as_str().context("id")?.to_owned();
    server.wait_plan(&done, LONG, |s| s == "ready").await?;
    let (_, path_before) = server.get(&format!("/v1/plans/{done}/path")).await?;
    // One running and one waiting when the server stops (grace 0: the running one is interrupted, unless it
    // finishes first; the waiting one is certainly still queued).
    let (_, a) = server.post("/v1/plans", &demo_request()).await?;
    let (_, b) = server.post("/v1/plans", &demo_request()).await?;
    let a = a["plan_id"].as_str().context("id")?.to_owned();
    let b = b["plan_id"].as_str().context("id")?.to_owned();
    server.stop().await?;

    // A crash mid-plan leaves a record saying "planning": write one as a kill -9 would have left it.
    let crashed = {
        let store = shiftd::store::Store::open(dir.path())?;
        let mut rec = store
            .plans()?
            .into_iter()
            .find(|r| r.plan_id == b)
            .context("queued record")?;
        assert_eq!(rec.status, shift_proto::PlanStatus::Queued);
        rec.plan_id = "p-77".into();
        rec.seq = 77;
        rec.status = shift_proto::PlanStatus::Planning;
        store.put_plan(&rec)?;
        rec.plan_id
    };

    let server = TestServer::start(test_config(dir.path())).await?;
    let (code, path_after) = server.get(&format!("/v1/plans/{done}/path")).await?;
    assert_eq!(code, 200);
    assert_eq!(path_after, path_before, "finished plans are served again unchanged");
    for id in [&a, &b, &crashed] {
        let st = server.wait_plan(id, LONG, |s| s == "ready" || s == "failed").await?;
        assert_eq!(st["status"], "ready", "{id}: {st}");
    }
    let st = server.get(&format!("/v1/plans/{crashed}")).await?.1;
    assert!(
        st["warnings"]
            .as_array()
            .is_some_and(|w| w.iter().any(|x| x == "re-queued after a restart")),
        "{st}"
    );
    // New ids never collide with restored ones.
    let (_, fresh) = server.post("/v1/plans", &demo_request()).await?;
    assert_eq!(fresh["plan_id"], "p-78");
    server.stop().await
}
