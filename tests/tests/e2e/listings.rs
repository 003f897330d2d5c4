//! Listings over HTTP: `GET /v1/sites`, `GET /v1/plans?site=&status=&robot=&limit=&after=` (newest first,
//! cursor pages that neither repeat nor skip), the map read-back `GET /v1/sites/{site}/map`, and 400s that name
//! the bad parameter.

use std::collections::HashSet;
use std::time::Duration;

use anyhow::{Context, Result};
use serde_json::{Value, json};
use shift_tests::fleet::room_grid;
use shift_tests::{TestServer, demo_request, test_config};

const LONG: Duration = Duration::from_secs(120);

fn ids(page: &Value) -> Vec<String> {
    page["items"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|p| p["plan_id"].as_str().map(str::to_owned))
                .collect()
        })
        .unwrap_or_default()
}

/// Follows every page of `query` (without `after`) with page size `limit`.
async fn all_pages(server: &TestServer, query: &str, limit: u32) -> Result<Vec<String>> {
    let mut out = Vec::new();
    let mut after: Option<String> = None;
    for _ in 0..100 {
        let cursor = after.as_ref().map(|a| format!("&after={a}")).unwrap_or_default();
        let (code, page) = server.get(&format!("/v1/plans?limit={limit}{query}{cursor}")).await?;
        assert_eq!(code, 200, "{page}");
        let got = ids(&page);
        assert!(got.len() <= limit as usize);
        out.extend(got);
        match page["next"].as_str() {
            Some(next) => after = Some(next.to_owned()),
            None => return Ok(out),
        }
    }
    anyhow::bail!("pages never ended")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn plans_and_sites_list_newest_first_in_pages() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let grid = room_grid(40, 30, 0.1, &[(1.5, 1.0, 2.0, 2.0)]);
    let (code, body) = server.post("/v1/sites/room/map", &grid).await?;
    assert_eq!(code, 201, "{body}");

    // Sites, in name order, each as GET /v1/sites/{site} answers it.
    let (code, sites) = server.get("/v1/sites").await?;
    assert_eq!(code, 200);
    let items = sites["items"].as_array().context("items")?;
    let names: Vec<&str> = items.iter().filter_map(|s| s["site"].as_str()).collect();
    assert_eq!(names, ["demo", "room"]);
    for s in items {
        let (_, one) = server
            .get(&format!("/v1/sites/{}", s["site"].as_str().unwrap_or("")))
            .await?;
        for field in ["width", "height", "resolution", "origin", "free_cells", "updated_ms"] {
            assert_eq!(s[field], one[field], "{field}");
        }
    }
    // The map reads back as uploaded (already thresholded: 0, 100).
    let (code, map) = server.get("/v1/sites/room/map").await?;
    assert_eq!(code, 200, "{map}");
    for field in ["width", "height", "resolution", "origin", "cells"] {
        assert_eq!(map[field], grid[field], "{field}");
    }
    let (code, body) = server.get("/v1/sites/nowhere/map").await?;
    assert_eq!((code, body["error"]["code"].as_str()), (404, Some("not_found")));

    // Eight plans: six on demo, two on room; two cancelled at once.
    let room_req = json!({"site": "room", "start": [0.5, 0.5], "robot": {"radius": 0.1, "tool_width": 0.2}});
    let mut created = Vec::new();
    for i in 0..8 {
        let req = if i % 3 == 2 { room_req.clone() } else { demo_request() };
        let (code, acc) = server.post("/v1/plans", &req).await?;
        assert_eq!(code, 202, "{acc}");
        created.push(acc["plan_id"].as_str().context("id")?.to_owned());
    }
    for id in [&created[3], &created[6]] {
        server.delete(&format!("/v1/plans/{id}")).await?;
    }
    let mut status_of = std::collections::HashMap::new();
    for id in &created {
        let st = server
            .wait_plan(id, LONG, |s| matches!(s, "ready" | "failed" | "cancelled"))
            .await?;
        status_of.insert(id.clone(), st["status"].as_str().unwrap_or("").to_owned());
    }
    let ready: Vec<&String> = created.iter().filter(|id| status_of[*id] == "ready").collect();
    let assigned = ready.first().context("a ready plan")?.to_string();
    let (code, body) = server
        .post(&format!("/v1/plans/{assigned}/assign"), &json!({"robot": "r9"}))
        .await?;
    assert_eq!(code, 200, "{body}");

    // Everything, newest first, one page (default limit 50), no cursor.
    let newest_first: Vec<String> = created.iter().rev().cloned().collect();
    let (code, page) = server.get("/v1/plans").await?;
    assert_eq!(code, 200);
    assert_eq!(ids(&page), newest_first);
    assert!(page.get("next").is_none(), "{page}");
    assert_eq!(page["items"][0]["site"], "demo");
    assert!(page["items"][0]["created_ms"].is_u64());

    // Pages of 3: 3 + 3 + 2, the same plans in the same order, none twice.
    let (_, first) = server.get("/v1/plans?limit=3").await?;
    assert_eq!(ids(&first), newest_first[..3]);
    assert_eq!(first["next"].as_str(), Some(newest_first[2].as_str()));
    for limit in [1, 2, 3, 7, 8, 500] {
        assert_eq!(all_pages(&server, "", limit).await?, newest_first, "limit {limit}");
    }

    // Filters, alone and together, paged.
    let on_demo: Vec<String> = newest_first
        .iter()
        .filter(|id| created.iter().position(|c| c == *id).is_some_and(|i| i % 3 != 2))
        .cloned()
        .collect();
    assert_eq!(on_demo.len(), 6);
    assert_eq!(all_pages(&server, "&site=demo", 2).await?, on_demo);
    let cancelled: Vec<String> = newest_first
        .iter()
        .filter(|id| status_of[*id] == "cancelled")
        .cloned()
        .collect();
    assert_eq!(all_pages(&server, "&status=cancelled", 1).await?, cancelled);
    let demo_ready: Vec<String> = on_demo
        .iter()
        .filter(|id| status_of[*id] == "ready" && **id != assigned)
        .cloned()
        .collect();
    assert_eq!(all_pages(&server, "&site=demo&status=ready", 2).await?, demo_ready);
    assert_eq!(
        all_pages(&server, "&robot=r9", 5).await?,
        std::slice::from_ref(&assigned)
    );
    assert!(all_pages(&server, "&site=nowhere", 5).await?.is_empty());

    // A plan accepted between two pages shows on a fresh first page only: the cursor keeps its place.
    let (_, p1) = server.get("/v1/plans?limit=4").await?;
    let (_, acc) = server.post("/v1/plans", &demo_request()).await?;
    let newest = acc["plan_id"].as_str().context("id")?.to_owned();
    let cursor = p1["next"].as_str().context("next")?;
    let rest = all_pages(&server, &format!("&after={cursor}"), 4).await?;
    let mut walked = ids(&p1);
    walked.extend(rest);
    assert_eq!(walked, newest_first);
    assert_eq!(walked.iter().collect::<HashSet<_>>().len(), walked.len());
    let (_, fresh) = server.get("/v1/plans?limit=1").await?;
    assert_eq!(ids(&fresh), [newest]);

    // Bad parameters: 400 with the error body naming the field.
    for (query, field) in [
        ("limit=0", "limit"),
        ("limit=501", "limit"),
        ("limit=ten", "limit"),
        ("status=busy", "status"),
        ("after=p-999", "after"),
        ("order=asc", "order"),
    ] {
        let (code, body) = server.get(&format!("/v1/plans?{query}")).await?;
        assert_eq!(code, 400, "{query}: {body}");
        assert_eq!(body["error"]["code"], "invalid_request");
        let message = body["error"]["message"].as_str().unwrap_or("");
        assert!(message.starts_with(field), "{query}: {message}");
    }

    // All of it is in the API description.
    let (_, api) = server.get("/openapi.json").await?;
    assert!(api["paths"]["/v1/sites"]["get"].is_object());
    assert!(api["paths"]["/v1/sites/{site}/map"]["get"].is_object());
    let params = api["paths"]["/v1/plans"]["get"]["parameters"]
        .as_array()
        .context("plan list parameters")?;
    let names: HashSet<&str> = params.iter().filter_map(|p| p["name"].as_str()).collect();
    assert_eq!(names, HashSet::from(["site", "status", "robot", "limit", "after"]));
    server.stop().await
}
