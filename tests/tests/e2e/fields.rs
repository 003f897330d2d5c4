//! Fields in WGS84 from outside: a backend uploads a GeoJSON field of a few hectares with a hole, plans on it
//! from a start given in lon/lat, and gets the path back as GeoJSON in lon/lat. Bad fields are refused naming
//! the field, and nothing is stored.

use std::time::Duration;

use anyhow::{Context, Result, ensure};
use serde_json::{Value, json};
use shift_tests::field::{LAT0, LON0, inside, ll, ring};
use shift_tests::{TestServer, test_config};

const LONG: Duration = Duration::from_secs(180);

/// 240 × 160 m (3.84 ha) with a 40 × 30 m pond in it.
fn field() -> Value {
    json!({"type": "Feature", "properties": {"name": "north field"}, "geometry": {"type": "Polygon", "coordinates": [
        ring(&[(0.0, 0.0), (240.0, 0.0), (240.0, 160.0), (0.0, 160.0)]),
        ring(&[(100.0, 60.0), (140.0, 60.0), (140.0, 90.0), (100.0, 90.0)]),
    ]}})
}

fn coords(v: &Value) -> Vec<[f64; 2]> {
    v.as_array()
        .map(|a| {
            a.iter()
                .filter_map(|p| Some([p.get(0)?.as_f64()?, p.get(1)?.as_f64()?]))
                .collect()
        })
        .unwrap_or_default()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_field_with_a_hole_plans_from_a_wgs84_start_and_comes_back_as_geojson() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let (code, site) = server
        .post("/v1/sites/north/field", &json!({"field": field(), "tool_width": 2.0}))
        .await?;
    ensure!(code == 201, "{code} {site}");
    let origin = coords(&json!([site["origin_wgs84"].clone()]));
    let origin = origin.first().context("origin_wgs84")?;
    ensure!((origin[0] - (LON0 + 120.0 / 75_480.0)).abs() < 1e-6, "{site}");
    ensure!((origin[1] - (LAT0 + 80.0 / 111_180.0)).abs() < 1e-6, "{site}");
    ensure!(site["crs"].as_str().is_some_and(|c| c.contains("etmerc")), "{site}");
    ensure!(site["resolution"] == 0.5, "a quarter of the tool width: {site}");

    let req = json!({"site": "north", "start_wgs84": ll(5.0, 5.0),
        "robot": {"radius": 0.9, "tool_width": 2.0, "v_max": 2.0}});
    let (code, acc) = server.post("/v1/plans", &req).await?;
    ensure!(code == 202, "{code} {acc}");
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    let status = server.wait_plan(&id, LONG, |s| s == "ready" || s == "failed").await?;
    ensure!(status["status"] == "ready", "{status}");
    let coverage = status["metrics"]["coverage_pct"].as_f64().context("coverage")?;
    ensure!(coverage >= 99.0, "coverage {coverage} %");

    // The map-frame path starts near the projected start; the GeoJSON one is the same path in lon/lat.
    let (_, doc) = server.get(&format!("/v1/plans/{id}/path")).await?;
    let w0 = &doc["waypoints"][0];
    let (x0, y0) = (
        w0["x"].as_f64().unwrap_or(f64::NAN),
        w0["y"].as_f64().unwrap_or(f64::NAN),
    );
    ensure!(
        (x0 + 115.0).hypot(y0 + 75.0) < 1.0,
        "start ({x0}, {y0}) is not 5 m in from the corner"
    );
    let (code, geo) = server.get(&format!("/v1/plans/{id}/path?crs=wgs84")).await?;
    ensure!(code == 200, "{code} {geo}");
    ensure!(
        geo["type"] == "Feature" && geo["geometry"]["type"] == "LineString",
        "{geo}"
    );
    let line = coords(&geo["geometry"]["coordinates"]);
    ensure!(
        line.len() == doc["waypoints"].as_array().map_or(0, Vec::len),
        "one position per waypoint"
    );
    ensure!(geo["properties"]["v"].as_array().map_or(0, Vec::len) == line.len());
    ensure!(geo["properties"]["t"].as_array().map_or(0, Vec::len) == line.len());
    let outer = coords(&field()["geometry"]["coordinates"][0]);
    let pond = coords(&field()["geometry"]["coordinates"][1]);
    for p in &line {
        // [lon, lat] order: longitude near 8.55, latitude near 47.37.
        ensure!(
            (p[0] - LON0).abs() < 0.01 && (p[1] - LAT0).abs() < 0.01,
            "{p:?} is not [lon, lat]"
        );
        ensure!(inside(*p, &outer), "{p:?} leaves the field");
        ensure!(!inside(*p, &pond), "{p:?} is in the pond");
    }
    let first = line.first().context("a path")?;
    let start = ll(5.0, 5.0);
    ensure!(
        ((first[0] - start[0]) * 75_480.0).hypot((first[1] - start[1]) * 111_180.0) < 1.0,
        "the path starts at start_wgs84: {first:?} vs {start:?}"
    );
    server.stop().await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_fields_and_wgs84_requests_are_refused_naming_the_field() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let bow_tie =
        json!({"type": "Polygon", "coordinates": [ring(&[(0.0, 0.0), (50.0, 50.0), (50.0, 0.0), (0.0, 50.0)])]});
    let swapped =
        json!({"type": "Polygon", "coordinates": [[[47.37, 8.55], [47.37, 98.55], [47.38, 98.56], [47.37, 8.55]]]});
    let open =
        json!({"type": "Polygon", "coordinates": [[ll(0.0, 0.0), ll(50.0, 0.0), ll(50.0, 50.0), ll(0.0, 50.0)]]});
    for (body, field) in [
        (json!({"field": bow_tie}), "field.coordinates: not a valid polygon"),
        (
            json!({"field": swapped}),
            "field.coordinates[0][1]: latitude 98.55 is outside -90..90",
        ),
        (json!({"field": open}), "field.coordinates[0]: the ring is not closed"),
        (
            json!({"field": {"type": "Point", "coordinates": [8.5, 47.3]}}),
            "field: \"Point\" is not a field",
        ),
        (json!({"field": field(), "resolution_m": -1.0}), "resolution_m"),
        (
            json!({"field": field(), "no_go": [{"type": "Polygon", "coordinates": [[[8.5, 47.3]]]}]}),
            "no_go[0]",
        ),
        (json!({"feld": field()}), "feld"),
    ] {
        let (code, err) = server.post("/v1/sites/bad/field", &body).await?;
        let msg = err["error"]["message"].as_str().unwrap_or_default();
        ensure!(code == 400 && msg.contains(field), "{field}: {code} {err}");
    }
    let (code, _) = server.get("/v1/sites/bad").await?;
    ensure!(code == 404, "nothing is stored after a refusal");

    // start_wgs84 on a site without a geo-reference, with start as well, or out of range.
    let (code, _) = server.post("/v1/sites/north/field", &json!({"field": field()})).await?;
    ensure!(code == 201);
    let robot = json!({"radius": 0.3, "tool_width": 0.6});
    for (req, field) in [
        (
            json!({"site": "demo", "start_wgs84": [8.55, 47.37], "robot": robot}),
            "start_wgs84: site \"demo\" has no geo-reference",
        ),
        (
            json!({"site": "north", "start_wgs84": ll(5.0, 5.0), "start": [0.0, 0.0], "robot": robot}),
            "not both",
        ),
        (
            json!({"site": "north", "start_wgs84": [47.37, 98.0], "robot": robot}),
            "start_wgs84",
        ),
        (
            json!({"site": "north", "start_wgs84": "here", "robot": robot}),
            "start_wgs84",
        ),
    ] {
        let (code, err) = server.post("/v1/plans", &req).await?;
        let msg = err["error"]["message"].as_str().unwrap_or_default();
        ensure!(code == 400 && msg.contains(field), "{field}: {code} {err}");
    }
    let (code, err) = server.get("/v1/plans?site=north").await?;
    ensure!(
        code == 200 && err["items"].as_array().is_some_and(Vec::is_empty),
        "no plan was stored: {err}"
    );
    server.stop().await
}
