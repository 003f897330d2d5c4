//! Missions through the SDK and `shiftctl` against a daemon started in-process: a two-robot mission on a small
//! generated site is created, followed over its event stream until planned, shown, assigned and partly driven
//! by one robot over Zenoh; the site's coverage raster is read as JSON and as a PNG; `shiftctl mission …` and
//! `shiftctl coverage` outputs are parsed back and compared with what the API serves.

mod common;

use std::collections::HashSet;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use common::{ctl, json, ok, refused};
use serde_json::Value;
use shift_client::Client;
use shift_client::proto::{
    MissionAccepted, MissionRequest, MissionRobot, MissionStatus, MissionView, OccupancyGridDoc, PlanDocument,
    PlanStatus, WaypointKindDoc,
};
use shift_tests::TestServer;
use shift_tests::fleet::{ScriptedRobot, fleet_config, poll, room_grid, wait_robot_alive};

/// The generated site: 8 m × 5 m at 0.1 m, a wall ring and a 1 m block in the middle.
const W: u64 = 80;
const H: u64 = 50;

/// The two robots and their docks (opposite corners).
fn robots() -> Vec<MissionRobot> {
    vec![
        MissionRobot::new("r1", [1.0, 1.0], 0.15, 0.3),
        MissionRobot::new("r2", [7.0, 4.0], 0.15, 0.3),
    ]
}

fn swept(grid: &OccupancyGridDoc) -> usize {
    grid.cells.iter().filter(|&&c| c == 100).count()
}

/// Drives the first `metres` of `doc`'s path (or more, to the end of a segment) by odometry every 0.1 m.
async fn drive(robot: &ScriptedRobot, name: &str, doc: &PlanDocument, metres: f64) -> Result<()> {
    let mut driven = 0.0;
    for pair in doc.waypoints.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let len = (b.x - a.x).hypot(b.y - a.y);
        let yaw = (b.y - a.y).atan2(b.x - a.x);
        let n = (len / 0.1).ceil().max(1.0) as usize;
        for k in 0..n {
            let f = k as f64 / n as f64;
            robot
                .odom(name, a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, yaw)
                .await?;
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        driven += len;
        if driven >= metres {
            return Ok(());
        }
    }
    Ok(())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_two_robot_mission_through_the_sdk_and_shiftctl() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (config, endpoint) = fleet_config(dir.path())?;
    let server = TestServer::start(config).await?;
    let b = server.base.as_str();
    let client = Client::new(b)?;

    let grid: OccupancyGridDoc =
        serde_json::from_value(room_grid(W as usize, H as usize, 0.1, &[(3.5, 2.0, 4.5, 3.0)]))?;
    let site = client.upload_grid("yard", &grid).await?;
    assert_eq!((site.width, site.height), (W, H));

    // Refused by the daemon before anything is stored, naming the field.
    let mut twice = robots();
    twice[1].id = "r1".into();
    let request = |robots| MissionRequest {
        site: "yard".into(),
        robots,
        attribute: None,
        options: None,
        objective: None,
    };
    let e = client
        .create_mission(&request(twice))
        .await
        .err()
        .context("a duplicate id")?;
    assert_eq!(e.status().map(|s| s.as_u16()), Some(400), "{e}");
    assert!(e.to_string().contains("robots[1].id"), "{e}");
    let e = client.mission("m-999").await.err().context("unknown mission")?;
    assert_eq!(
        (e.status().map(|s| s.as_u16()), e.code()),
        (Some(404), Some("not_found"))
    );
    let e = client
        .mission_events("m-999")
        .await
        .err()
        .context("unknown mission's events")?;
    assert_eq!(e.status().map(|s| s.as_u16()), Some(404));

    // Created, followed over its events until planned.
    let accepted = client.create_mission(&request(robots())).await?;
    assert_eq!(accepted.status, MissionStatus::Queued);
    let id = accepted.mission_id.clone();
    let mut views = client.mission_events(&id).await?;
    let mut seen = Vec::new();
    let ready = tokio::time::timeout(Duration::from_secs(120), async {
        while let Some(view) = views.next_view().await? {
            seen.push(view.status);
            match view.status {
                MissionStatus::Ready => return Ok(view),
                MissionStatus::Queued | MissionStatus::Planning => {}
                s => bail!("mission {s:?}: {view:?}"),
            }
        }
        bail!("the stream ended before the mission was planned: {seen:?}")
    })
    .await
    .context("no ready mission in 2 minutes")??;
    drop(views);
    assert!(
        matches!(
            seen[0],
            MissionStatus::Queued | MissionStatus::Planning | MissionStatus::Ready
        ),
        "{seen:?}"
    );
    assert_eq!(ready.mission_id, id);
    assert_eq!(
        ready.plans.iter().map(|p| p.robot.as_str()).collect::<Vec<_>>(),
        ["r1", "r2"]
    );
    assert!(
        ready.coverage.planned_pct.is_some_and(|p| p >= 95.0),
        "{:?}",
        ready.coverage
    );
    assert!(ready.eta_s.is_some_and(|t| t > 0.0), "{ready:?}");
    let free_m2 = site.free_cells as f64 * 0.01;
    let area: f64 = ready.plans.iter().filter_map(|p| p.area_m2).sum();
    assert!(area > 0.7 * free_m2 && area <= free_m2 * 1.01, "{area} of {free_m2} m²");
    for p in &ready.plans {
        // Each part is an ordinary plan naming its mission.
        let plan = client.plan(&p.plan_id).await?;
        assert_eq!((plan.status, plan.version), (PlanStatus::Ready, 1));
        assert_eq!(plan.mission.as_deref(), Some(id.as_str()));
        assert_eq!(p.planned_duration_s, plan.metrics.as_ref().map(|m| m.duration_s));
    }

    // Shown the same by the SDK and shiftctl (JSON and the human table).
    let shown = client.mission(&id).await?;
    assert_eq!((shown.status, &shown.plans), (MissionStatus::Ready, &ready.plans));
    let by_ctl: MissionView = json(b, &["mission", "show", &id]).await?;
    assert_eq!(
        (&by_ctl.mission_id, by_ctl.status, &by_ctl.plans),
        (&id, shown.status, &shown.plans)
    );
    assert_eq!(by_ctl.coverage.planned_pct, shown.coverage.planned_pct);
    let human = ok(b, &["mission", "show", &id]).await?;
    assert!(human.contains("ROBOT") && human.contains("ready"), "{human}");
    for p in &shown.plans {
        let row = human
            .lines()
            .find(|l| l.starts_with(p.robot.as_str()))
            .with_context(|| format!("no row for {}: {human}", p.robot))?;
        assert!(row.contains(&p.plan_id) && row.contains("ready"), "{row}");
    }

    // The robots join; the mission is assigned; r1 drives 15 m of its part (a transit to its first lane, then
    // lanes).
    let mut joined = Vec::new();
    for r in robots() {
        joined.push(ScriptedRobot::join(&endpoint, &r.id).await?);
        wait_robot_alive(&server, &r.id).await?;
    }
    let active = client.assign_mission(&id).await?;
    assert_eq!(active.status, MissionStatus::Active);
    for p in &active.plans {
        let plan = client.plan(&p.plan_id).await?;
        assert_eq!(
            (plan.status, plan.robot.as_deref()),
            (PlanStatus::Active, Some(p.robot.as_str()))
        );
    }
    let doc = client.path(&active.plans[0].plan_id).await?;
    drive(&joined[0], "r1", &doc, 15.0).await?;
    let measured = poll(
        async || {
            let m = client.mission(&id).await?;
            Ok((m.coverage.measured_pct > 0.0 && m.plans[0].driven_fraction > 0.0).then_some(m))
        },
        "r1's sweep to be measured",
    )
    .await?;
    assert!(measured.coverage.measured_pct < 50.0, "{:?}", measured.coverage);
    assert_eq!(measured.plans[1].driven_fraction, 0.0);

    // The site's raster: the map's dims, the free cells swept or not, r1's sweep near its dock.
    let coverage = poll(
        async || {
            let g = client.site_coverage("yard").await?;
            Ok((swept(&g) > 0).then_some(g))
        },
        "swept cells on the raster",
    )
    .await?;
    assert_eq!(
        (coverage.width, coverage.height, coverage.resolution, coverage.origin),
        (W, H, 0.1, [0.0, 0.0])
    );
    assert_eq!(coverage.cells.len() as u64, W * H);
    assert!(coverage.cells.iter().all(|c| [-1, 0, 100].contains(c)));
    let free_or_swept = coverage.cells.iter().filter(|&&c| c >= 0).count() as u64;
    assert!(
        free_or_swept >= site.free_cells && free_or_swept <= site.free_cells + 2 * (W + H),
        "{free_or_swept} cells vs {} free",
        site.free_cells
    );
    assert_eq!(coverage.cell(0, 0), Some(-1), "the wall ring is not free");
    // The first cover waypoint of r1's path (driving to it is transit, its tool off) was swept.
    let first_cover = doc
        .waypoints
        .iter()
        .find(|w| w.kind == WaypointKindDoc::Cover)
        .context("a cover waypoint")?;
    let (cover_col, cover_row) = ((first_cover.x / 0.1) as u32, (first_cover.y / 0.1) as u32);
    assert_eq!(
        coverage.cell(u64::from(cover_col), u64::from(cover_row)),
        Some(100),
        "{first_cover:?}"
    );
    assert_eq!(coverage.cell(70, 40), Some(0), "r2's dock at (7, 4) is not");
    let swept_json = swept(&coverage);

    let by_ctl: OccupancyGridDoc = json(b, &["coverage", "yard"]).await?;
    assert_eq!((by_ctl.width, by_ctl.height), (W, H));
    assert!(swept(&by_ctl) >= swept_json);
    let human = ok(b, &["coverage", "yard"]).await?;
    assert!(
        human.contains(&format!("{W} × {H} cells")) && human.contains("swept share"),
        "{human}"
    );

    // The PNG: one pixel per cell, the map's top row first; swept cells green, walls dark, the rest light.
    let png = client.site_coverage_png("yard").await?;
    let img = image::load_from_memory_with_format(&png, image::ImageFormat::Png)?.to_rgb8();
    assert_eq!(img.dimensions(), (W as u32, H as u32));
    let px = |col: u32, row_from_bottom: u32| img.get_pixel(col, H as u32 - 1 - row_from_bottom).0;
    assert_eq!(px(0, 0), [20, 20, 20]);
    assert_eq!(px(cover_col, cover_row), [46, 160, 67]);
    assert_eq!(px(70, 40), [250, 250, 250]);
    let green = img.pixels().filter(|p| p.0 == [46, 160, 67]).count();
    assert!(green >= swept_json, "{green} green pixels for {swept_json} swept cells");
    let file = dir.path().join("coverage.png");
    let file_s = file.to_str().context("path")?;
    let out: Value = json(b, &["coverage", "yard", "--png", file_s]).await?;
    let written = image::open(&file)?.to_rgb8();
    assert_eq!(written.dimensions(), (W as u32, H as u32));
    assert_eq!((out["width"].as_u64(), out["height"].as_u64()), (Some(W), Some(H)));
    assert!(
        ok(b, &["coverage", "yard", "--png", file_s])
            .await?
            .starts_with("wrote ")
    );

    // A second mission by shiftctl, cancelled by shiftctl with its plans; then it cannot be replanned.
    let second: MissionAccepted = json(
        b,
        &[
            "mission",
            "create",
            "--site",
            "yard",
            "--robot",
            "s1:1,4:0.15:0.3",
            "--robot",
            "s2:7,1:0.15:0.3",
            "--seed",
            "7",
        ],
    )
    .await?;
    assert_eq!(second.status, MissionStatus::Queued);
    let cancelled: MissionView = json(b, &["mission", "cancel", &second.mission_id]).await?;
    assert_eq!(
        (cancelled.mission_id.as_str(), cancelled.status),
        (second.mission_id.as_str(), MissionStatus::Cancelled)
    );
    assert_eq!(cancelled.plans.len(), 2);
    for p in &cancelled.plans {
        assert_eq!(p.status, PlanStatus::Cancelled, "{p:?}");
    }
    assert_eq!(
        client.mission(&second.mission_id).await?.status,
        MissionStatus::Cancelled
    );
    assert_eq!(
        refused(b, &["mission", "cancel", &second.mission_id]).await?,
        (409, "invalid_state".into())
    );
    assert_eq!(refused(b, &["mission", "replan", &second.mission_id]).await?.0, 409);
    assert_eq!(
        refused(b, &["mission", "show", "m-999"]).await?,
        (404, "not_found".into())
    );
    assert_eq!(refused(b, &["coverage", "nowhere"]).await?.0, 404);

    // `mission create --watch`: the bar (not a terminal here: hidden), then the table of the planned mission.
    let watched = ok(
        b,
        &[
            "mission",
            "create",
            "--site",
            "yard",
            "--robot",
            "w1:1,4:0.15:0.3",
            "--robot",
            "w2:7,1:0.15:0.3",
            "--watch",
        ],
    )
    .await?;
    let watched_id = watched
        .lines()
        .find_map(|l| l.strip_prefix("mission "))
        .map(|rest| rest.trim().to_owned())
        .with_context(|| format!("no mission line: {watched}"))?;
    let view = client.mission(&watched_id).await?;
    assert_eq!(view.status, MissionStatus::Ready, "{watched}");
    for p in &view.plans {
        assert!(watched.contains(&p.plan_id), "{watched}");
    }

    // Bad input: 2, before anything is sent.
    for args in [
        &["mission", "create", "--site", "yard", "--robot", "r1:1,1:0.15"][..],
        &[
            "mission",
            "create",
            "--site",
            "yard",
            "--robot",
            "r1:1,1:0.15:0.3",
            "--robot",
            "r1:2,2:0.15:0.3",
        ],
        &["mission", "create", "--site", "yard", "--robot", "r1:1,1:-0.15:0.3"],
        &["mission", "create", "--site", "yard", "--robot", "r1:x,1:0.15:0.3"],
        &["mission", "create", "--site", "yard"],
        &[
            "mission",
            "create",
            "--site",
            "yard",
            "--robot",
            "r1:1,1:0.15:0.3",
            "--objective",
            "fastest",
        ],
        &["mission", "show"],
    ] {
        let (code, _, err) = ctl(b, args).await?;
        assert_eq!(code, 2, "{args:?}: {err}");
    }
    let missions: HashSet<&str> = [id.as_str(), second.mission_id.as_str(), watched_id.as_str()].into();
    assert_eq!(missions.len(), 3);

    // The active mission's remainder is replanned on request (202, its view).
    let replanned = client.replan_mission(&id).await?;
    assert_eq!(replanned.mission_id, id);
    assert_ne!(replanned.status, MissionStatus::Failed, "{replanned:?}");

    // A robot joins by shiftctl: a bad spec exits 2, a dock on the map's edge is refused naming the field, a
    // good one gets a plan of the mission.
    let (code, _, err) = ctl(b, &["mission", "join", &id, "--robot", "r3:1,1:0.15"]).await?;
    assert_eq!(code, 2, "{err}");
    assert_eq!(
        refused(b, &["mission", "join", &id, "--robot", "r3:-5,1:0.15:0.3"]).await?,
        (400, "invalid_request".into())
    );
    let grown: MissionView = json(b, &["mission", "join", &id, "--robot", "r3:1.5,1.2:0.15:0.3"]).await?;
    assert_eq!(grown.plans.len(), 3, "{grown:?}");
    assert_eq!(grown.plans[2].robot, "r3");

    drop(joined);
    server.stop().await
}
