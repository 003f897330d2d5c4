//! The doors of the HTTP API (DESIGN §8, issue 22): body limits before and while a body is read, slow clients,
//! the connection cap, whole-input validation before anything is stored, the bearer token, and 429 with
//! `Retry-After`. shiftd runs in-process on 127.0.0.1:0; `shift_tests::raw` sends the bytes a polite client
//! would not.

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use serde_json::{Value, json};
use shift_tests::raw::{self, RawResponse};
use shift_tests::{TestServer, demo_request, test_config};
use shiftd::Config;
use tokio::io::AsyncWriteExt;

const SHORT: Duration = Duration::from_secs(10);

/// Plan bodies up to 64 KiB, map uploads up to 256 KiB.
fn small_limits(dir: &Path) -> Config {
    let mut c = test_config(dir);
    c.http.max_request_bytes = 64 << 10;
    c.http.max_body_bytes = 256 << 10;
    c
}

fn message(body: &Value) -> &str {
    body["error"]["message"].as_str().unwrap_or("")
}

/// Nothing but the demo site and no plan: what every refused request must leave behind.
async fn nothing_stored(server: &TestServer) -> Result<()> {
    let (_, sites) = server.get("/v1/sites").await?;
    let names: Vec<&str> = sites["items"]
        .as_array()
        .or(sites.as_array())
        .context("site list")?
        .iter()
        .filter_map(|s| s["site"].as_str())
        .collect();
    assert_eq!(names, vec!["demo"], "{sites}");
    let (_, plans) = server.get("/v1/plans").await?;
    assert_eq!(plans["items"].as_array().map(Vec::len), Some(0), "{plans}");
    Ok(())
}

fn assert_too_large(r: &RawResponse, key: &str) {
    assert_eq!(r.status, 413, "{r:?}");
    let body = r.json();
    assert_eq!(body["error"]["code"], "payload_too_large", "{body}");
    assert!(message(&body).contains(key), "{body}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_declared_length_over_the_limit_is_413_before_any_body_byte() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(small_limits(dir.path())).await?;
    let addr = raw::addr(&server.base);
    // 300 MiB declared and not one byte of it sent: the answer comes anyway, at once.
    for (path, content_type, key) in [
        ("/v1/sites/big/map", "application/json", "max_body_bytes"),
        ("/v1/sites/big/map", "multipart/form-data; boundary=x", "max_body_bytes"),
        ("/v1/sites/big/field", "application/geo+json", "max_body_bytes"),
        ("/v1/sites/big/terrain", "application/octet-stream", "max_body_bytes"),
        ("/v1/plans", "application/json", "max_request_bytes"),
        ("/v1/plans/p-1/assign", "application/json", "max_request_bytes"),
    ] {
        let head = format!(
            "POST {path} HTTP/1.1\r\nHost: shift\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\r\n",
            300u64 << 20
        );
        let mut s = raw::send(addr, head.as_bytes()).await?;
        let r = raw::read_response(&mut s, SHORT).await?;
        assert_too_large(&r, key);
    }
    // Per route: a plan request one byte over its 64 KiB is refused, a map of 100 KiB is taken.
    let head = format!(
        "POST /v1/plans HTTP/1.1\r\nHost: shift\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n",
        (64 << 10) + 1
    );
    let mut s = raw::send(addr, head.as_bytes()).await?;
    assert_too_large(&raw::read_response(&mut s, SHORT).await?, "max_request_bytes");
    nothing_stored(&server).await?;
    let cells = vec![0; 200 * 200];
    let map = json!({"resolution": 0.05, "origin": [0, 0], "width": 200, "height": 200, "cells": cells});
    assert!(map.to_string().len() > 64 << 10);
    let (code, body) = server.post("/v1/sites/mid/map", &map).await?;
    assert_eq!(code, 201, "{body}");
    // Answers no handler wrote carry the API's error body too: 405 keeps its Allow header.
    let r = server.http.put(server.url("/v1/plans")).send().await?;
    assert_eq!(r.status().as_u16(), 405);
    assert!(r.headers().get("allow").is_some());
    assert_eq!(r.json::<Value>().await?["error"]["code"], "method_not_allowed");
    server.stop().await
}

/// Sends a chunked body of `total` bytes (`prefix` first, then `fill`), ignoring write errors (the server may
/// stop reading at its limit), then reads the answer.
async fn send_chunked(addr: &str, head: &str, prefix: &[u8], fill: u8, total: usize) -> Result<RawResponse> {
    let mut s = raw::send(addr, head.as_bytes()).await?;
    let mut body = prefix.to_vec();
    body.resize(total, fill);
    for piece in body.chunks(8 << 10) {
        let mut frame = format!("{:x}\r\n", piece.len()).into_bytes();
        frame.extend_from_slice(piece);
        frame.extend_from_slice(b"\r\n");
        if s.write_all(&frame).await.is_err() {
            break;
        }
    }
    raw::read_response(&mut s, SHORT).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_chunked_body_is_cut_at_the_limit_with_413() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(small_limits(dir.path())).await?;
    let addr = raw::addr(&server.base);
    let chunked = |path: &str, content_type: &str| {
        format!(
            "POST {path} HTTP/1.1\r\nHost: shift\r\nContent-Type: {content_type}\r\nTransfer-Encoding: chunked\r\n\r\n"
        )
    };
    // A plan request with a region of endless vertices: 96 KiB against a 64 KiB limit.
    let head = chunked("/v1/plans", "application/json");
    let prefix = br#"{"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}, "region": ["#;
    let r = send_chunked(addr, &head, prefix, b' ', 96 << 10).await?;
    assert_too_large(&r, "");
    // A JSON map and a multipart map image: 320 KiB against 256 KiB.
    let head = chunked("/v1/sites/big/map", "application/json");
    let r = send_chunked(addr, &head, br#"{"cells": ["#, b' ', 320 << 10).await?;
    assert_too_large(&r, "");
    let head = chunked("/v1/sites/big/map", "multipart/form-data; boundary=XyZ");
    let part = b"--XyZ\r\nContent-Disposition: form-data; name=\"image\"; filename=\"m.pgm\"\r\n\r\nP5\n";
    let r = send_chunked(addr, &head, part, 0, 320 << 10).await?;
    assert_too_large(&r, "");
    nothing_stored(&server).await?;
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn slow_clients_are_cut() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.http.header_read_timeout_s = 1;
    config.http.request_timeout_s = 2;
    let server = TestServer::start(config).await?;
    let addr = raw::addr(&server.base);

    // A connection that sends nothing is closed after the header read timeout.
    let mut idle = tokio::net::TcpStream::connect(addr).await?;
    let t = Instant::now();
    let (closed, _) = raw::closed_within(&mut idle, SHORT).await;
    assert!(
        closed && t.elapsed() < Duration::from_secs(5),
        "idle: {:?}",
        t.elapsed()
    );

    // A head trickled one byte per 100 ms (the whole would take 7 s) is cut after ~1 s, never answered 200.
    let head = format!(
        "GET /healthz HTTP/1.1\r\nHost: shift\r\nX-Slow: {}\r\n\r\n",
        "a".repeat(30)
    );
    let (mut rd, mut wr) = tokio::net::TcpStream::connect(addr).await?.into_split();
    let writer = tokio::spawn(async move {
        let mut sent = 0usize;
        for b in head.bytes() {
            if wr.write_all(&[b]).await.is_err() {
                break;
            }
            sent += 1;
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
        sent
    });
    let t = Instant::now();
    let (closed, got) = raw::closed_within(&mut rd, SHORT).await;
    let took = t.elapsed();
    assert!(closed, "the trickling client was not cut");
    assert!(took < Duration::from_secs(4), "cut after {took:?}");
    assert!(!String::from_utf8_lossy(&got).contains(" 200 "), "answered: {got:?}");
    let sent = writer.await?;
    assert!(sent < 70, "the head was cut before it was complete: {sent} bytes sent");

    // A body trickled past the request timeout: 408 with the API's error body.
    let head = "POST /v1/plans HTTP/1.1\r\nHost: shift\r\nContent-Type: application/json\r\nContent-Length: 200\r\n\r\n{\"site\"";
    let mut s = raw::send(addr, head.as_bytes()).await?;
    let r = raw::read_response(&mut s, SHORT).await?;
    assert_eq!(r.status, 408, "{r:?}");
    assert_eq!(r.json()["error"]["code"], "request_timeout", "{r:?}");
    nothing_stored(&server).await?;
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn connections_over_the_cap_wait_for_a_free_slot() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.http.max_connections = 2;
    config.http.header_read_timeout_s = 3;
    let server = TestServer::start(config).await?;
    let addr = raw::addr(&server.base).to_owned();
    // Let the server close the harness's pooled keep-alive connection (idle past the header timeout).
    tokio::time::sleep(Duration::from_millis(3500)).await;
    let a = tokio::net::TcpStream::connect(&addr).await?;
    let _b = tokio::net::TcpStream::connect(&addr).await?;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let fresh = || {
        reqwest::Client::builder()
            .pool_max_idle_per_host(0)
            .timeout(Duration::from_secs(1))
            .build()
    };
    let third = fresh()?.get(server.url("/healthz")).send().await;
    assert!(
        third.is_err(),
        "a third connection is served only when a slot frees: {third:?}"
    );
    drop(a);
    let r = fresh()?.get(server.url("/healthz")).send().await?;
    assert_eq!(r.status().as_u16(), 200);
    server.stop().await
}

/// A binary PGM of `w × h` free cells.
fn free_pgm(w: usize, h: usize) -> Vec<u8> {
    let mut v = format!("P5\n{w} {h}\n255\n").into_bytes();
    v.resize(v.len() + w * h, 255);
    v
}

async fn upload_pgm(server: &TestServer, site: &str, image: Vec<u8>) -> Result<(u16, Value)> {
    let yaml = "image: m.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
    let form = reqwest::multipart::Form::new()
        .part("yaml", reqwest::multipart::Part::text(yaml))
        .part("image", reqwest::multipart::Part::bytes(image).file_name("m.pgm"));
    let r = server
        .http
        .post(server.url(&format!("/v1/sites/{site}/map")))
        .multipart(form)
        .send()
        .await?;
    let code = r.status().as_u16();
    Ok((code, r.json().await.unwrap_or(Value::Null)))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_reader_that_stops_reading_is_cut() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.http.write_stall_s = 1;
    let server = TestServer::start(config).await?;
    // 2500 × 2500 cells: the grid read back is ~12.5 MB of JSON, far more than the socket buffers hold.
    let (code, body) = upload_pgm(&server, "big", free_pgm(2500, 2500)).await?;
    assert_eq!(code, 201, "{body}");
    let socket = tokio::net::TcpSocket::new_v4()?;
    socket.set_recv_buffer_size(4096)?;
    let mut s = socket.connect(raw::addr(&server.base).parse()?).await?;
    s.write_all(b"GET /v1/sites/big/map HTTP/1.1\r\nHost: shift\r\n\r\n")
        .await?;
    // Read nothing for longer than the stall limit, then drain what the kernel kept.
    tokio::time::sleep(Duration::from_secs(4)).await;
    let (closed, got) = raw::closed_within(&mut s, Duration::from_secs(30)).await;
    assert!(closed, "the connection stayed open");
    let text = String::from_utf8_lossy(&got[..got.len().min(1024)]).into_owned();
    let declared: usize = text
        .lines()
        .find_map(|l| {
            l.to_ascii_lowercase()
                .strip_prefix("content-length:")
                .map(|v| v.trim().to_owned())
        })
        .context("content-length")?
        .parse()?;
    assert!(declared > 10_000_000, "{declared}");
    assert!(
        got.len() < declared,
        "got the whole body ({} bytes): not cut",
        got.len()
    );
    server.stop().await
}

/// POSTs `body` as JSON text; expects 400 whose message names `field`.
async fn refused(server: &TestServer, path: &str, body: &str, field: &str) -> Result<()> {
    let r = server
        .http
        .post(server.url(path))
        .header("content-type", "application/json")
        .body(body.to_owned())
        .send()
        .await?;
    let code = r.status().as_u16();
    let answer: Value = r.json().await.unwrap_or(Value::Null);
    assert_eq!(code, 400, "{path} {body}: {answer}");
    assert!(answer["error"]["code"].is_string(), "{answer}");
    assert!(
        message(&answer).contains(field),
        "{path} {body}: {field} not named in {answer}"
    );
    Ok(())
}

/// The demo request with `change` applied to it.
fn plan_with(change: impl FnOnce(&mut Value)) -> String {
    let mut r = demo_request();
    change(&mut r);
    r.to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_invalid_input_is_refused_naming_the_field_and_nothing_is_stored() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let robot = r#""robot": {"radius": 0.15, "tool_width": 0.3}"#;
    let raw_plans = [
        (format!(r#"{{"site": "demo", "start": [NaN, 0.5], {robot}}}"#), "start"),
        (
            format!(r#"{{"site": "demo", "start": [1e999, 0.5], {robot}}}"#),
            "start",
        ),
        (
            r#"{"site": "demo", "start": [0.5, 0.5], "robot": {"radius": Infinity, "tool_width": 0.3}}"#.into(),
            "robot",
        ),
    ];
    for (body, field) in &raw_plans {
        refused(&server, "/v1/plans", body, field).await?;
    }
    let cases: Vec<(String, &str)> = vec![
        (plan_with(|r| r["robot"]["radius"] = json!(0)), "robot.radius"),
        (
            plan_with(|r| r["robot"]["tool_width"] = json!(-0.3)),
            "robot.tool_width",
        ),
        (
            plan_with(|r| r["robot"]["tool_width"] = json!(1e-9)),
            "robot.tool_width",
        ),
        (plan_with(|r| r["robot"]["v_min"] = json!(2.0)), "robot.v_min"),
        (plan_with(|r| r["robot"]["a_max"] = json!(0)), "robot.a_max"),
        (plan_with(|r| r["robot"]["colour"] = json!("red")), "colour"),
        (plan_with(|r| r["start"] = json!([1e6, 0.5])), "start"),
        (plan_with(|r| r["snap_start_m"] = json!(-1)), "snap_start_m"),
        (plan_with(|r| r["site"] = json!("a/b")), "site"),
        (plan_with(|r| r["site"] = json!("")), "site"),
        (plan_with(|r| r["site"] = json!("x".repeat(65))), "site"),
        (plan_with(|r| r["extra"] = json!(1)), "extra"),
        (plan_with(|r| r["objective"] = json!("fastest")), "objective"),
        (
            plan_with(|r| r["options"] = json!({"order": "fastest"})),
            "options.order",
        ),
        (plan_with(|r| r["options"] = json!({"colour": 1})), "colour"),
        (plan_with(|r| r["region"] = json!([[0, 0], [1, 1]])), "region"),
        (plan_with(|r| r["region"] = json!(vec![[0.5, 0.5]; 5000])), "region"),
        (
            plan_with(|r| r["attribute"] = json!({"blobs": [{"x": 1, "y": 1, "sigma": 0, "amplitude": 1}]})),
            "attribute.blobs[0].sigma",
        ),
        (
            plan_with(|r| r["attribute"] = json!({"blobs": [{"x": 1, "y": 1, "sigma": 1, "amplitude": 2}]})),
            "attribute.blobs[0].amplitude",
        ),
        (
            plan_with(|r| {
                r["attribute"] = json!({"blobs": vec![json!({"x": 1, "y": 1, "sigma": 1, "amplitude": 1}); 300]})
            }),
            "attribute.blobs",
        ),
    ];
    for (body, field) in &cases {
        refused(&server, "/v1/plans", body, field).await?;
    }

    // Maps: a 10^6 × 10^6 grid declared in a few bytes, bad numbers, unknown fields, bad names, a bad image.
    let maps = [
        (
            r#"{"resolution":1,"origin":[0,0],"width":1000000,"height":1000000,"cells":[]}"#,
            "width",
        ),
        (
            r#"{"resolution":0,"origin":[0,0],"width":1,"height":1,"cells":[0]}"#,
            "resolution",
        ),
        (
            r#"{"resolution":-1,"origin":[0,0],"width":1,"height":1,"cells":[0]}"#,
            "resolution",
        ),
        (
            r#"{"resolution":0.1,"origin":[1e999,0],"width":1,"height":1,"cells":[0]}"#,
            "origin",
        ),
        (
            r#"{"resolution":0.1,"origin":[0,0],"width":0,"height":1,"cells":[]}"#,
            "width",
        ),
        (
            r#"{"resolution":0.1,"origin":[0,0],"width":2,"height":2,"cells":[0]}"#,
            "cells",
        ),
        (
            r#"{"resolution":0.1,"origin":[0,0],"width":1,"height":1,"cells":[101]}"#,
            "cells",
        ),
        (
            r#"{"resolution":0.1,"origin":[0,0],"width":1,"height":1,"cells":[0],"colour":1}"#,
            "colour",
        ),
    ];
    for (body, field) in maps {
        refused(&server, "/v1/sites/x/map", body, field).await?;
    }
    let good = r#"{"resolution":0.1,"origin":[0,0],"width":1,"height":1,"cells":[0]}"#;
    for bad_name in ["a.b", "a%20b", "%C3%A9", &"x".repeat(65)] {
        refused(&server, &format!("/v1/sites/{bad_name}/map"), good, "site").await?;
    }
    let mut huge = b"P5\n1000000 1000000\n255\n".to_vec();
    huge.extend_from_slice(&[255; 16]);
    let (code, body) = upload_pgm(&server, "x", huge).await?;
    assert_eq!(code, 400, "{body}");
    assert!(message(&body).contains("width"), "{body}");

    // Assignments: the robot's name.
    for (body, field) in [
        (r#"{"robot": "a/b"}"#, "robot"),
        (r#"{"robot": "r1", "extra": 1}"#, "extra"),
    ] {
        refused(&server, "/v1/plans/p-1/assign", body, field).await?;
    }
    nothing_stored(&server).await?;
    let (_, robots) = server.get("/v1/robots").await?;
    assert_eq!(robots.as_array().map(Vec::len), Some(0), "{robots}");
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_bearer_token_answers_401_or_403_and_comes_from_config_or_file() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.http.auth_token = "s3cret-token".into();
    let server = TestServer::start(config).await?;
    let post = |auth: Option<&str>| {
        let mut r = server.http.post(server.url("/v1/plans")).json(&demo_request());
        if let Some(a) = auth {
            r = r.header("authorization", a);
        }
        r.send()
    };
    // 401: no credentials, or not a bearer token; the answer says how to authenticate.
    for auth in [
        None,
        Some("Basic czNjcmV0LXRva2Vu"),
        Some("s3cret-token"),
        Some("Bearer"),
    ] {
        let r = post(auth).await?;
        assert_eq!(r.status().as_u16(), 401, "{auth:?}");
        assert_eq!(
            r.headers().get("www-authenticate").and_then(|v| v.to_str().ok()),
            Some("Bearer")
        );
        assert_eq!(r.json::<Value>().await?["error"]["code"], "unauthorized");
    }
    // 403: a bearer token that is wrong, of the same length or not.
    for wrong in ["s3cret-tokeN", "S3cret-token", "s3cret", "s3cret-token-and-more", "x"] {
        let r = post(Some(&format!("Bearer {wrong}"))).await?;
        assert_eq!(r.status().as_u16(), 403, "{wrong}");
        assert_eq!(r.json::<Value>().await?["error"]["code"], "forbidden");
    }
    nothing_stored(&server).await?;
    // The right one, the scheme in any case; reads stay open.
    let r = post(Some("bearer s3cret-token")).await?;
    assert_eq!(r.status().as_u16(), 202);
    assert_eq!(server.get("/v1/plans/p-1").await?.0, 200);
    server.stop().await?;

    // The token from a file (a final newline is not part of it).
    let dir = tempfile::tempdir()?;
    let file = dir.path().join("token");
    std::fs::write(&file, "file-token-42\n")?;
    let mut config = test_config(dir.path());
    config.http.auth_token_file = file.clone();
    let server = TestServer::start(config).await?;
    let send = |token: &str| {
        server
            .http
            .post(server.url("/v1/plans"))
            .bearer_auth(token)
            .json(&demo_request())
            .send()
    };
    assert_eq!(send("file-token-4").await?.status().as_u16(), 403);
    assert_eq!(send("file-token-42").await?.status().as_u16(), 202);
    server.stop().await?;

    // Two sources: the daemon refuses to start rather than pick one.
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.http.auth_token = "a".into();
    config.http.auth_token_file = file;
    let e = TestServer::start(config).await.err().context("two token sources")?;
    assert!(format!("{e:#}").contains("more than once"), "{e:#}");
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fifty_plan_requests_202_up_to_the_queue_then_429_with_retry_after() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    config.jobs.workers = 1;
    config.jobs.queue_capacity = 8;
    config.http.retry_after_s = 7;
    let server = TestServer::start(config).await?;
    let calls = (0..50).map(|_| {
        let (http, url) = (server.http.clone(), server.url("/v1/plans"));
        async move {
            let r = http.post(url).json(&demo_request()).send().await?;
            let status = r.status().as_u16();
            let retry = r
                .headers()
                .get("retry-after")
                .and_then(|v| v.to_str().ok())
                .map(str::to_owned);
            let body: Value = r.json().await?;
            anyhow::Ok((status, retry, body))
        }
    });
    let answers = futures_util::future::try_join_all(calls).await?;
    let accepted = answers.iter().filter(|(s, _, _)| *s == 202).count();
    let refused: Vec<_> = answers.iter().filter(|(s, _, _)| *s == 429).collect();
    assert_eq!(accepted + refused.len(), 50, "{answers:?}");
    // One computing and eight waiting at least (more if a plan finished during the burst).
    assert!(accepted >= 9, "{accepted} accepted");
    assert!(!refused.is_empty(), "no 429");
    for (_, retry, body) in &refused {
        assert_eq!(retry.as_deref(), Some("7"), "{body}");
        assert_eq!(body["error"]["code"], "queue_full", "{body}");
    }
    for (status, retry, _) in &answers {
        assert!(*status == 429 || retry.is_none());
    }
    // A refused request left nothing behind.
    let (_, plans) = server.get("/v1/plans?limit=500").await?;
    assert_eq!(plans["items"].as_array().map(Vec::len), Some(accepted), "{plans}");

    // The API's description says so.
    let (_, api) = server.get("/openapi.json").await?;
    let post = &api["paths"]["/v1/plans"]["post"]["responses"];
    assert!(post["429"]["headers"]["Retry-After"].is_object(), "{post}");
    for code in ["400", "401", "403", "413"] {
        assert!(post[code].is_object(), "POST /v1/plans lacks {code}: {post}");
    }
    let upload = &api["paths"]["/v1/sites/{site}/map"]["post"]["responses"];
    assert!(upload["413"].is_object(), "{upload}");
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_sdk_waits_as_a_full_queue_asks_and_gets_in() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let mut config = test_config(dir.path());
    (
        config.jobs.workers,
        config.jobs.queue_capacity,
        config.http.retry_after_s,
    ) = (1, 1, 1);
    let server = TestServer::start(config).await?;
    let client = shift_client::Client::new(&server.base)?;
    let request: shift_proto::PlanRequest = serde_json::from_value(demo_request())?;
    let mut refused = None;
    for _ in 0..200 {
        if let Err(e) = client.create_plan(&request).await {
            refused = Some(e);
            break;
        }
    }
    let refused = refused.context("the queue never filled")?;
    assert_eq!(refused.code(), Some("queue_full"), "{refused}");
    assert_eq!(refused.retry_after(), Some(Duration::from_secs(1)));
    let late = client.create_plan_waiting(&request, Duration::from_secs(120)).await?;
    let (status, _) = server.get(&format!("/v1/plans/{}", late.plan_id)).await?;
    assert_eq!(status, 200);
    server.stop().await
}
