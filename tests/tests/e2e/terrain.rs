//! Terrain sites from outside (issue 23): a backend uploads a LiDAR tile (LAZ, in feet) as a ground robot's site,
//! plans on it and gets waypoints with the ground's z; broken clouds and bad parameters are refused naming what
//! is wrong, the site keeps its map, and a restart brings the same site back from the store. A robot that joins
//! late on a georeferenced terrain site (UTM coordinates, ground 60 m above the datum) and sees a post with its
//! own sensor gets a correction that clears the post and carries the ground's height.

use std::path::Path;
use std::time::Duration;

use anyhow::{Context, Result, anyhow, ensure};
use serde_json::{Value, json};
use shift_proto::ros::Time;
use shift_proto::{CorrectionReason, PlanDocument};
use shift_tests::bench::Rng;
use shift_tests::fleet::{ScriptedRobot, fleet_config};
use shift_tests::path::{index_at, length, seg_dist, straight_from};
use shift_tests::{TestServer, test_config};

const LONG: Duration = Duration::from_secs(180);

fn autzen() -> Result<Vec<u8>> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/terrain/autzen_trim.laz");
    std::fs::read(&p).with_context(|| format!("{} (the shared terrain samples sit beside the repository)", p.display()))
}

async fn upload(server: &TestServer, site: &str, query: &str, body: Vec<u8>) -> Result<(u16, Value)> {
    let r = server
        .http
        .post(server.url(&format!("/v1/sites/{site}/terrain{query}")))
        .header("content-type", "application/octet-stream")
        .body(body)
        .send()
        .await?;
    let status = r.status().as_u16();
    Ok((status, r.json().await.unwrap_or(Value::Null)))
}

/// A free cell of the site's grid with every cell within `clear_m` free too: (x, y) of its centre.
async fn clear_spot(server: &TestServer, site: &str, clear_m: f64) -> Result<[f64; 2]> {
    let (code, grid) = server.get(&format!("/v1/sites/{site}/map")).await?;
    ensure!(code == 200, "{code} {grid}");
    let w = grid["width"].as_u64().context("width")? as i64;
    let h = grid["height"].as_u64().context("height")? as i64;
    let res = grid["resolution"].as_f64().context("resolution")?;
    let origin = [
        grid["origin"][0].as_f64().context("ox")?,
        grid["origin"][1].as_f64().context("oy")?,
    ];
    let data: Vec<i64> = grid["cells"]
        .as_array()
        .context("cells")?
        .iter()
        .filter_map(Value::as_i64)
        .collect();
    ensure!(data.len() as i64 == w * h, "grid data");
    let r = (clear_m / res).ceil() as i64;
    let free = |c: i64, row: i64| c >= 0 && row >= 0 && c < w && row < h && data[(row * w + c) as usize] == 0;
    // From the centre outwards, so the spot is in the tile's bulk.
    let mut cells: Vec<(i64, i64)> = (0..h).flat_map(|row| (0..w).map(move |c| (c, row))).collect();
    cells.sort_by_key(|&(c, row)| (c - w / 2).pow(2) + (row - h / 2).pow(2));
    let (c, row) = cells
        .into_iter()
        .find(|&(c, row)| (-r..=r).all(|dy| (-r..=r).all(|dx| free(c + dx, row + dy))))
        .context("no clear spot on the terrain site")?;
    Ok([origin[0] + (c as f64 + 0.5) * res, origin[1] + (row as f64 + 0.5) * res])
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lidar_tile_becomes_a_ground_site_whose_plans_carry_the_ground_height() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let server = TestServer::start(test_config(dir.path())).await?;
    let laz = autzen()?;
    let (code, site) = upload(&server, "autzen", "?grid_m=1&max_slope_deg=12", laz.clone()).await?;
    ensure!(code == 201, "{code} {site}");
    ensure!(site["resolution"] == 1.0, "{site}");
    let warnings = site["warnings"].to_string();
    ensure!(
        warnings.contains("foot") && warnings.contains("0.3048"),
        "the conversion is said: {warnings}"
    );
    let free = site["free_cells"].as_u64().context("free_cells")?;
    let cells = site["width"].as_u64().context("width")? * site["height"].as_u64().context("height")?;
    ensure!(
        free > cells / 4 && free < cells,
        "some ground is drivable, some is not: {free} of {cells}"
    );

    let start = clear_spot(&server, "autzen", 1.0).await?;
    let req = json!({"site": "autzen", "start": start, "robot": {"radius": 0.5, "tool_width": 1.0}});
    let (code, acc) = server.post("/v1/plans", &req).await?;
    ensure!(code == 202, "{code} {acc}");
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    let status = server.wait_plan(&id, LONG, |s| s == "ready" || s == "failed").await?;
    ensure!(status["status"] == "ready", "{status}");
    ensure!(status["metrics"]["collisions"] == 0, "{status}");
    let (_, doc) = server.get(&format!("/v1/plans/{id}/path")).await?;
    let z: Vec<f64> = doc["waypoints"]
        .as_array()
        .context("waypoints")?
        .iter()
        .filter_map(|w| w["z"].as_f64())
        .collect();
    let (lo, hi) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    // Autzen's ground lies about 120–140 m above the datum (in metres now, not feet).
    ensure!(
        lo > 100.0 && hi < 170.0 && hi - lo > 0.5,
        "z in metres along the ground: {lo}..{hi}"
    );

    // Broken clouds and bad parameters: 400 naming the problem, and the site keeps its map.
    let before = server.get("/v1/sites/autzen").await?.1;
    for (query, body, want) in [
        ("", laz[..laz.len() / 2].to_vec(), "truncated"),
        ("", b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec(), "no points"),
        ("", b"ply\nformat ascii 1.0\nelement vertex 9\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n".to_vec(), "9"),
        ("?grid_m=0", laz.clone(), "grid_m"),
        ("?slope=3", laz.clone(), "slope: unknown parameter"),
        ("?units=yards", laz.clone(), "units"),
    ] {
        let (code, body) = upload(&server, "autzen", query, body).await?;
        let msg = body["error"]["message"].as_str().unwrap_or_default().to_owned();
        ensure!(code == 400, "{query}: {code} {body}");
        ensure!(msg.to_lowercase().contains(want), "{query}: {msg:?} should say {want:?}");
    }
    let after = server.get("/v1/sites/autzen").await?.1;
    ensure!(after == before, "a refused upload changed the site: {before} → {after}");
    let (code, _) = server.get("/v1/sites/never").await?;
    ensure!(code == 404);
    let (code, body) = upload(&server, "never", "", Vec::new()).await?;
    ensure!(
        code == 400 && server.get("/v1/sites/never").await?.0 == 404,
        "{code} {body}"
    );

    // The store keeps the elevation map: after a restart the site is the same.
    let config = test_config(dir.path());
    server.stop().await?;
    let server = TestServer::start(config).await?;
    let again = server.get("/v1/sites/autzen").await?.1;
    ensure!(
        again["free_cells"] == before["free_cells"] && again["warnings"] == before["warnings"],
        "{again}"
    );
    server.stop().await
}

/// A binary PLY of a 16 m × 10 m tile in UTM metres: ground 60 m above the datum, rising 5 cm per metre east
/// and 2 cm per metre north, with ±5 mm of noise. Returns the file and the ground's height function.
fn utm_tile(ox: f64, oy: f64) -> (Vec<u8>, impl Fn(f64, f64) -> f64) {
    let ground = move |x: f64, y: f64| 60.0 + 0.05 * (x - ox) + 0.02 * (y - oy);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut unit = move || rng.next_f64();
    let n = 40_000;
    let mut ply = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty double x\nproperty double y\n\
         property double z\nend_header\n"
    )
    .into_bytes();
    for _ in 0..n {
        let (x, y) = (ox + 16.0 * unit(), oy + 10.0 * unit());
        let z = ground(x, y) + 0.01 * (unit() - 0.5);
        for v in [x, y, z] {
            ply.extend_from_slice(&v.to_le_bytes());
        }
    }
    (ply, ground)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_joining_late_on_a_utm_terrain_site_is_corrected_round_a_post_at_the_grounds_height() -> Result<()> {
    const RADIUS: f64 = 0.15;
    let dir = tempfile::tempdir()?;
    let (config, endpoint) = fleet_config(dir.path())?;
    let server = TestServer::start(config).await?;
    let (ox, oy) = (512_300.0, 5_123_400.0);
    let (ply, ground) = utm_tile(ox, oy);
    let (code, site) = upload(&server, "slope", "?grid_m=0.1", ply).await?;
    ensure!(code == 201, "{code} {site}");
    let robot = ScriptedRobot::join(&endpoint, "r1").await?;
    let req = json!({"site": "slope", "start": [ox + 0.5, oy + 0.5], "robot": {"radius": RADIUS, "tool_width": 0.3}});
    let (code, acc) = server.post("/v1/plans", &req).await?;
    ensure!(code == 202, "{code} {acc}");
    let id = acc["plan_id"].as_str().context("plan id")?.to_owned();
    let status = server.wait_plan(&id, LONG, |s| s == "ready" || s == "failed").await?;
    ensure!(status["status"] == "ready", "{status}");
    let (code, st) = server
        .post(&format!("/v1/plans/{id}/assign"), &json!({"robot": "r1"}))
        .await?;
    ensure!(code == 200, "assign: {code} {st}");
    let (_, served) = server.get(&format!("/v1/plans/{id}/path")).await?;
    let doc: PlanDocument = serde_json::from_value(served)?;
    let w = &doc.waypoints;
    for p in w {
        ensure!(
            (p.z - ground(p.x, p.y)).abs() < 0.02,
            "plan z {} over ground {}",
            p.z,
            ground(p.x, p.y)
        );
    }

    // First seen at 60 % of its plan, on a straight stretch; odometry at 20 Hz on its own clock.
    let seg = straight_from(w, index_at(w, 0.6 * length(w)), 2.5).context("a straight stretch after 60 %")?;
    let (a, b) = (&w[seg.0], &w[seg.1]);
    let yaw = (b.y - a.y).atan2(b.x - a.x);
    let (c, s) = (yaw.cos(), yaw.sin());
    let mut stamp = 100.0;
    for _ in 0..3 {
        robot.odom_stamped("r1", a.x, a.y, yaw, stamp).await?;
        stamp += 0.05;
        tokio::time::sleep(Duration::from_millis(30)).await;
    }
    let stamp = stamp - 0.05;
    // Its depth camera sees a 0.2 m post 1.5 m ahead, 0.1–0.5 m over the ground: a cloud in its own frame.
    let mut local = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            for k in 0..3 {
                local.push([1.4 + 0.05 * i as f32, -0.1 + 0.05 * j as f32, 0.1 + 0.2 * k as f32]);
            }
        }
    }
    let post: Vec<(f64, f64)> = local
        .iter()
        .map(|p| {
            let (u, v) = (f64::from(p[0]), f64::from(p[1]));
            (a.x + c * u - s * v, a.y + s * u + c * v)
        })
        .collect();
    let secs = stamp.floor();
    let time = Time {
        sec: secs as i32,
        nanosec: ((stamp - secs) * 1e9).round() as u32,
    };
    robot.cloud_in("r1", "base_link", time, &local).await?;

    let corr = robot.next_correction(LONG).await?;
    ensure!(corr.base_version == 1 && corr.plan_id == id, "{corr:?}");
    ensure!(
        corr.reason != CorrectionReason::Skipped,
        "room to pass on an open slope: {corr:?}"
    );
    ensure!(corr.from >= seg.0, "the patch is ahead of the robot: {corr:?}");
    let new = corr.apply(&doc).map_err(|e| anyhow!("{e}"))?;
    // The patch and its joins clear the post by the radius, measured in f64 (f32 would be 0.5 m coarse here).
    let lo = corr.from.saturating_sub(1);
    let hi = (corr.from + corr.waypoints.len() + 1).min(new.waypoints.len() - 1);
    let nw = &new.waypoints;
    let clear = (lo..hi)
        .flat_map(|i| {
            post.iter()
                .map(move |&p| seg_dist(p, (nw[i].x, nw[i].y), (nw[i + 1].x, nw[i + 1].y)))
        })
        .fold(f64::INFINITY, f64::min);
    ensure!(clear >= RADIUS - 0.03, "the patch comes {clear:.3} m from the post");
    // Every waypoint of the patch is on the ground: z is the slope's height under it, not 0.
    for p in &corr.waypoints {
        let g = ground(p.x, p.y);
        ensure!(
            (p.z - g).abs() < 0.02,
            "correction z {} over ground {g} at ({}, {})",
            p.z,
            p.x,
            p.y
        );
    }
    robot.session.close().await.map_err(|e| anyhow!("{e}"))?;
    server.stop().await
}
