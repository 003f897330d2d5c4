//! `shiftctl` with fields in WGS84, as the real binary against a daemon on 127.0.0.1: a GeoJSON field uploaded
//! from a file, a plan from a start in lon/lat, the path exported as GeoJSON in lon/lat.

mod common;

use std::time::Duration;

use anyhow::{Context, Result, ensure};
use common::ctl;
use serde_json::{Value, json};
use shift_client::Client;
use shift_tests::field::{LAT0, LON0, inside, ll, ring};
use shift_tests::{TestServer, test_config};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_field_from_a_file_plans_from_lon_lat_and_exports_geojson_in_lon_lat() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let base = server.base.clone();
    let outer = ring(&[(0.0, 0.0), (120.0, 0.0), (120.0, 80.0), (0.0, 80.0)]);
    let shed = ring(&[(50.0, 30.0), (70.0, 30.0), (70.0, 50.0), (50.0, 50.0)]);
    let field = dir.path().join("field.geojson");
    std::fs::write(&field, json!({"type": "Polygon", "coordinates": [outer]}).to_string())?;
    let no_go = dir.path().join("shed.geojson");
    std::fs::write(&no_go, json!({"type": "Polygon", "coordinates": [shed]}).to_string())?;
    let (code, out, err) = ctl(
        &base,
        &[
            "--json",
            "site",
            "field",
            "west",
            "--geojson",
            &field.to_string_lossy(),
            "--no-go",
            &no_go.to_string_lossy(),
            "--tool-width",
            "2",
        ],
    )
    .await?;
    ensure!(code == 0, "site field: {err}");
    let site: Value = serde_json::from_str(&out)?;
    ensure!(
        site["crs"].as_str().is_some_and(|c| c.contains("etmerc")) && site["origin_wgs84"].is_array(),
        "{site}"
    );

    let [lon, lat] = ll(4.0, 4.0);
    let start = format!("{lon},{lat}");
    let (code, out, err) = ctl(
        &base,
        &[
            "--json",
            "plan",
            "--site",
            "west",
            "--start-wgs84",
            &start,
            "--robot-radius",
            "0.9",
            "--tool-width",
            "2",
            "--v-max",
            "2",
        ],
    )
    .await?;
    ensure!(code == 0, "plan: {err}");
    let id = serde_json::from_str::<Value>(&out)?["plan_id"]
        .as_str()
        .context("plan id")?
        .to_owned();
    let client = Client::new(&base)?;
    let done = client
        .wait_plan(&id, Duration::from_millis(100), Duration::from_secs(180))
        .await?;
    ensure!(
        done.metrics.as_ref().is_some_and(|m| m.coverage_pct >= 99.0),
        "{done:?}"
    );

    let geo = dir.path().join("path.geojson");
    let (code, _, err) = ctl(
        &base,
        &[
            "export",
            &id,
            "--format",
            "geojson",
            "--crs",
            "wgs84",
            "--out",
            &geo.to_string_lossy(),
        ],
    )
    .await?;
    ensure!(code == 0, "export: {err}");
    let feature: Value = serde_json::from_str(&std::fs::read_to_string(&geo)?)?;
    let line: Vec<[f64; 2]> = feature["geometry"]["coordinates"]
        .as_array()
        .context("coordinates")?
        .iter()
        .filter_map(|p| Some([p.get(0)?.as_f64()?, p.get(1)?.as_f64()?]))
        .collect();
    let as_ll = |r: &Value| -> Vec<[f64; 2]> { serde_json::from_value(r.clone()).unwrap_or_default() };
    let (outer, shed) = (as_ll(&outer), as_ll(&shed));
    ensure!(line.len() > 10);
    for p in &line {
        ensure!(
            (p[0] - LON0).abs() < 0.01 && (p[1] - LAT0).abs() < 0.01,
            "{p:?} is not [lon, lat]"
        );
        ensure!(
            inside(*p, &outer) && !inside(*p, &shed),
            "{p:?} leaves the field or enters the shed"
        );
    }

    // Both starts, or a wgs84 export of a CSV: bad input, exit 2.
    let (code, _, _) = ctl(
        &base,
        &["plan", "--site", "west", "--start", "1,1", "--start-wgs84", &start],
    )
    .await?;
    ensure!(code == 2, "both starts: exit {code}");
    let (code, _, err) = ctl(&base, &["export", &id, "--format", "csv", "--crs", "wgs84"]).await?;
    ensure!(code == 2 && err.contains("--crs"), "{code} {err}");
    server.stop().await
}
