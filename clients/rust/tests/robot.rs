//! The robot side over Zenoh on loopback: a robot follows its plan with `RobotLink` + `FollowedPlan`, an
//! obstacle on its lane makes the daemon send a correction, the robot applies it by version and ends at the
//! document the API serves; `shiftctl tail corrections` prints the same correction.

use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Stdio};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use shift_client::Client;
use shift_client::proto::keys::KeySpace;
use shift_client::proto::{
    CorrectionDoc, OccupancyGridDoc, PlanRequest, PlanStatus, PlanStatusResponse, RobotSpec, WatchHealth,
};
use shift_client::robot::{Applied, FollowedPlan, RobotLink, RobotMessage};
use shift_tests::TestServer;
use shift_tests::fleet::{ScriptedRobot, fleet_config, room_grid};
use shift_tests::path::{along, longest_straight};

const LONG: Duration = Duration::from_secs(120);

/// The next plan or correction; the plan statuses that come before it are kept in `statuses`.
async fn next_not_status(link: &RobotLink, statuses: &mut Vec<PlanStatusResponse>) -> Result<RobotMessage> {
    loop {
        match tokio::time::timeout(LONG, link.recv()).await?? {
            RobotMessage::Status(s) => statuses.push(*s),
            other => return Ok(other),
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_follows_its_plan_and_a_correction_and_tail_prints_it() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let (config, endpoint) = fleet_config(dir.path())?;
    let server = TestServer::start(config).await?;
    let client = Client::new(&server.base)?;

    // An open 8 m × 4 m room, uploaded as a JSON grid and read back unchanged.
    let grid: OccupancyGridDoc = serde_json::from_value(room_grid(160, 80, 0.05, &[]))?;
    let summary = client.upload_grid("room", &grid).await?;
    assert_eq!((summary.width, summary.height), (160, 80));
    assert_eq!(client.site_map("room").await?, grid);

    let scripted = ScriptedRobot::join(&endpoint, "r1").await?;
    let link = RobotLink::connect(&endpoint, KeySpace::default(), "r1").await?;
    assert_eq!(
        link.fetch_plan(Duration::from_millis(500)).await?,
        None,
        "nothing assigned yet"
    );

    // shiftctl follows r1's corrections.
    let mut tail = KillOnDrop(
        Command::new(env!("CARGO_BIN_EXE_shiftctl"))
            .args([
                "--json",
                "tail",
                "corrections",
                "r1",
                "--zenoh",
                &endpoint,
                "--count",
                "1",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?,
    );
    let mut tail_err = BufReader::new(tail.0.stderr.take().context("stderr")?);
    let first = tokio::task::spawn_blocking(move || {
        let mut line = String::new();
        tail_err.read_line(&mut line).map(|_| (line, tail_err))
    })
    .await??;
    assert!(
        first.0.starts_with("following shift/default/robots/r1/corrections"),
        "{}",
        first.0
    );

    let accepted = client
        .create_plan(&PlanRequest {
            site: "room".into(),
            start: [0.5, 0.5],
            robot: RobotSpec {
                radius: 0.15,
                footprint: None,
                tool_width: 0.3,
                v_min: 0.1,
                v_max: 1.0,
                a_max: 0.5,
            },
            attribute: None,
            region: None,
            options: None,
            objective: None,
            snap_start_m: None,
        })
        .await?;
    let id = accepted.plan_id;
    let status = client.wait_plan(&id, Duration::from_millis(50), LONG).await?;
    assert_eq!(status.status, PlanStatus::Ready);
    assert_eq!(client.assign(&id, "r1").await?.robot.as_deref(), Some("r1"));

    // The plan arrives on r1's plan key.
    let mut followed = FollowedPlan::default();
    let mut statuses = Vec::new();
    let message = next_not_status(&link, &mut statuses).await?;
    let RobotMessage::Plan(doc) = &message else {
        bail!("expected the plan first, got {message:?}");
    };
    assert_eq!(doc, &client.path(&id).await?);
    assert_eq!(
        link.follow(&mut followed, message).await?,
        Applied::Plan {
            plan_id: id.clone(),
            version: 1
        }
    );

    // Drive to the longest lane, then a post 2 m ahead on it.
    let w = followed.doc().context("plan")?.waypoints.clone();
    let seg = longest_straight(&w);
    for k in (0..seg.0).step_by(4) {
        scripted.odom("r1", w[k].x, w[k].y, 0.0).await?;
    }
    for k in 0..5 {
        let pose = along(&w, seg, 0.2 * k as f64);
        scripted.odom("r1", pose.0, pose.1, pose.2).await?;
        tokio::time::sleep(Duration::from_millis(30)).await;
    }
    let (ox, oy, _) = along(&w, seg, 2.8);
    let post: Vec<[f32; 3]> = (0..75)
        .map(|n| {
            let (i, j, k) = (n % 5, (n / 5) % 5, n / 25);
            [
                (ox - 0.1 + 0.05 * i as f64) as f32,
                (oy - 0.1 + 0.05 * j as f64) as f32,
                0.1 + 0.2 * k as f32,
            ]
        })
        .collect();
    scripted.cloud("r1", &post).await?;

    // The correction applies by version.
    let message = next_not_status(&link, &mut statuses).await?;
    let RobotMessage::Correction(correction) = message.clone() else {
        bail!("expected a correction, got {message:?}");
    };
    assert_eq!((correction.base_version, correction.version), (1, 2));
    assert_eq!(
        link.follow(&mut followed, message).await?,
        Applied::Correction { version: 2 }
    );
    let patched = followed.doc().context("plan")?;
    assert!(
        patched.waypoints.len() != w.len() || patched.waypoints != w,
        "the path changed"
    );

    // A stale copy changes nothing; catching up with later corrections (the daemon may look again) ends at
    // what the API serves.
    assert_eq!(followed.on_correction(correction.clone()), Ok(Applied::Stale));
    let served = loop {
        let served = client.path(&id).await?;
        if followed.version() == Some(served.version) {
            break served;
        }
        let message = tokio::time::timeout(LONG, link.recv()).await??;
        if let RobotMessage::Status(s) = &message {
            statuses.push((**s).clone());
        }
        link.follow(&mut followed, message).await?;
    };
    assert_eq!(followed.doc(), Some(&served));
    // The status of version 2 follows its correction.
    while !statuses.iter().any(|s| s.version >= 2) {
        if let RobotMessage::Status(s) = tokio::time::timeout(LONG, link.recv()).await?? {
            statuses.push(*s);
        }
    }
    // The plan's statuses reached its robot: assigned and watched, then at version 2.
    assert!(
        statuses
            .iter()
            .any(|s| s.plan_id == id && s.watch == Some(WatchHealth::Watching)),
        "{statuses:?}"
    );
    assert!(
        statuses.iter().all(|s| s.robot.as_deref() == Some("r1")),
        "only r1's plans"
    );
    // A robot that joins now asks for the status it missed: the plan's current one.
    let asked = link
        .fetch_status(&id, Duration::from_secs(2))
        .await?
        .context("the status queryable answers")?;
    assert_eq!(
        (asked.plan_id.as_str(), asked.robot.as_deref()),
        (id.as_str(), Some("r1"))
    );
    assert_eq!(asked.version, followed.version().context("a version")?);
    let mut joined = FollowedPlan::new(served.clone());
    assert_eq!(
        joined.on_status(&asked),
        Applied::Watch {
            health: asked.watch.context("watched")?
        }
    );

    // shiftctl printed the first correction, exactly.
    let mut stdout = tail.0.stdout.take().context("stdout")?;
    let printed = tokio::task::spawn_blocking(move || {
        let mut out = String::new();
        stdout.read_to_string(&mut out).map(|_| out)
    })
    .await??;
    let exit = tokio::task::spawn_blocking(move || {
        let mut t = tail;
        t.0.wait()
    })
    .await??;
    assert!(exit.success(), "tail exited {exit:?}");
    let printed: CorrectionDoc = serde_json::from_str(printed.trim()).context("tail output")?;
    assert_eq!(printed, correction);
    server.stop().await
}

/// A child process killed when the test ends early.
struct KillOnDrop(std::process::Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}
