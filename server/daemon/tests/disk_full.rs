//! A disk that fills up under a running daemon (issue 22). The test cannot assume root, so the disk is the
//! process's file-size limit (RLIMIT_FSIZE, set from outside with util-linux's `prlimit --pid`): a write past
//! it fails with EFBIG exactly as on a full file system (shiftd catches SIGXFSZ, so it is not killed).
//!
//! While full: map uploads, plan requests and cancels are refused with 507 naming the store, nothing of them is
//! stored or served, every read is still served and `/readyz` says why writes are refused; a plan job that
//! finishes meanwhile is not served as ready before its result is stored. When the space comes back, writes
//! work again without a restart, what waited is committed, and after a kill -9 the store opens holding exactly
//! what was acknowledged.

mod common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail, ensure};
use serde_json::{Value, json};

use common::{Daemon, free_port, http, pillar_grid as grid};

const CONFIG: &str = "[jobs]\nworkers = 1\nshutdown_grace_s = 0\n";

/// Sets the daemon's file-size limit (soft; the hard limit stays unlimited).
fn limit_file_size(pid: u32, bytes: Option<u64>) -> Result<()> {
    let soft = bytes.map_or("unlimited".to_owned(), |b| b.to_string());
    let out = Command::new("prlimit")
        .arg("--pid")
        .arg(pid.to_string())
        .arg(format!("--fsize={soft}:unlimited"))
        .output()
        .context("running prlimit (util-linux)")?;
    ensure!(
        out.status.success(),
        "prlimit: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Ok(())
}

async fn upload(port: u16, site: &str, side: usize, seed: usize) -> Result<(u16, Value)> {
    http(port, "POST", &format!("/v1/sites/{site}/map"), Some(&grid(side, seed))).await
}

async fn wait_status(d: &Daemon, plan: &str, want: &str, within: Duration) -> Result<Value> {
    let until = Instant::now() + within;
    loop {
        let (code, body) = d.get(&format!("/v1/plans/{plan}")).await?;
        ensure!(code == 200, "GET plan {plan}: {code} {body}");
        if body["status"] == want {
            return Ok(body);
        }
        if Instant::now() > until {
            bail!("plan {plan} is {} after {within:?}, not {want}", body["status"]);
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

fn site_names(body: &Value) -> Vec<String> {
    let list = &body["items"];
    list.as_array()
        .map(|a| a.iter().filter_map(|s| s["site"].as_str().map(str::to_owned)).collect())
        .unwrap_or_default()
}

fn plan_request(site: &str) -> Value {
    json!({"site": site, "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}})
}

fn store_len(dir: &Path) -> Result<u64> {
    Ok(std::fs::metadata(dir.join("data").join("shift.redb"))?.len())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_disk_refuses_writes_with_507_keeps_reads_and_loses_nothing_acknowledged() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let port = free_port()?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let d = Daemon::start(dir.path(), port, &endpoint, CONFIG).await?;

    // Before: a site and a computed plan.
    assert_eq!(upload(port, "before", 200, 1).await?.0, 201);
    let (code, body) = d.post("/v1/plans", &plan_request("before")).await?;
    ensure!(code == 202, "{code} {body}");
    let ready_plan = body["plan_id"].as_str().context("plan_id")?.to_owned();
    let ready_body = wait_status(&d, &ready_plan, "ready", Duration::from_secs(60)).await?;
    // A bigger plan that may still be computing when the disk fills.
    assert_eq!(upload(port, "wide", 400, 2).await?.0, 201);
    let (code, body) = d.post("/v1/plans", &plan_request("wide")).await?;
    ensure!(code == 202, "{code} {body}");
    let late_plan = body["plan_id"].as_str().context("plan_id")?.to_owned();

    // The disk fills: the file may not grow any more.
    limit_file_size(d.pid(), Some(store_len(dir.path())?))?;
    let mut acknowledged = vec!["before".to_owned(), "wide".to_owned()];
    let mut refused = None;
    for k in 0..60 {
        let name = format!("fill-{k}");
        let (code, body) = upload(port, &name, 300, 10 + k).await?;
        match code {
            201 | 200 => acknowledged.push(name),
            507 => {
                assert_eq!(body["error"]["code"], "store_full", "{body}");
                let msg = body["error"]["message"].as_str().unwrap_or_default();
                assert!(msg.contains("no space left"), "the message says why: {msg}");
                refused = Some(name);
                break;
            }
            other => bail!("upload {name}: unexpected {other} {body}"),
        }
    }
    let refused = refused.context("60 uploads never filled the store")?;
    let (_, late) = d.get(&format!("/v1/plans/{late_plan}")).await?;
    let late_computing_when_full = late["status"] != "ready";

    // While full: every write is refused, every read is served.
    let (code, body) = d.post("/v1/plans", &plan_request("before")).await?;
    assert_eq!(
        (code, body["error"]["code"].as_str()),
        (507, Some("store_full")),
        "{body}"
    );
    let (code, body) = http(port, "DELETE", &format!("/v1/plans/{late_plan}"), None).await?;
    assert_eq!(code, 507, "cancel while full: {body}");
    let (code, body) = d.get("/readyz").await?;
    assert_eq!((code, body["store"].as_str()), (200, Some("full")), "{body}");
    let (code, body) = d.get("/v1/sites").await?;
    assert_eq!(code, 200);
    let listed = site_names(&body);
    assert!(
        !listed.contains(&refused),
        "the refused upload is not served: {listed:?}"
    );
    for name in &acknowledged {
        assert!(listed.contains(name), "{name} was acknowledged: {listed:?}");
    }
    let (code, body) = d.get(&format!("/v1/plans/{ready_plan}")).await?;
    assert_eq!((code, &body["status"]), (200, &ready_body["status"]));
    assert_eq!(d.get(&format!("/v1/plans/{ready_plan}/path")).await?.0, 200);
    let (code, _) = d.get(&format!("/v1/sites/{refused}")).await?;
    assert_eq!(code, 404, "nothing half-written is served");
    // A plan job that finishes while the disk is full is not served as ready before its result is stored.
    if late_computing_when_full {
        tokio::time::sleep(Duration::from_secs(3)).await;
        let (_, late) = d.get(&format!("/v1/plans/{late_plan}")).await?;
        assert_ne!(
            late["status"], "ready",
            "a result that is not stored is not served: {late}"
        );
        let metrics = common::text(port, "/metrics").await?;
        let deferred = metrics
            .lines()
            .find_map(|l| l.strip_prefix("shift_store_deferred "))
            .and_then(|v| v.trim().parse::<f64>().ok());
        eprintln!(
            "{} uploads fitted before the disk was full; {late_plan} status {} while full, facts waiting: {deferred:?}",
            acknowledged.len() - 2,
            late["status"]
        );
    } else {
        eprintln!("note: {late_plan} was computed before the disk filled; the deferred-result check did not run");
    }

    // The space comes back: writes work again without a restart (the store is probed at most once a second).
    limit_file_size(d.pid(), None)?;
    tokio::time::sleep(Duration::from_millis(1100)).await;
    let (code, body) = upload(port, &refused, 300, 99).await?;
    assert_eq!(code, 201, "after the space came back: {body}");
    acknowledged.push(refused.clone());
    let (code, body) = d.get("/readyz").await?;
    assert_eq!((code, body["store"].as_str()), (200, Some("open")), "{body}");
    wait_status(&d, &late_plan, "ready", Duration::from_secs(120)).await?;
    let (code, body) = d.post("/v1/plans", &plan_request("before")).await?;
    ensure!(code == 202, "a plan after the space came back: {code} {body}");
    let after_plan = body["plan_id"].as_str().context("plan_id")?.to_owned();
    wait_status(&d, &after_plan, "ready", Duration::from_secs(60)).await?;

    // kill -9 and start again on the same data: exactly what was acknowledged is there.
    d.kill9()?;
    let d = Daemon::start(dir.path(), port, &endpoint, CONFIG).await?;
    let (_, body) = d.get("/v1/sites").await?;
    let mut listed = site_names(&body);
    listed.retain(|s| s != "demo");
    listed.sort();
    acknowledged.sort();
    assert_eq!(listed, acknowledged);
    for plan in [&ready_plan, &late_plan, &after_plan] {
        let (code, body) = d.get(&format!("/v1/plans/{plan}")).await?;
        assert_eq!((code, body["status"].as_str()), (200, Some("ready")), "{plan}: {body}");
    }
    Ok(())
}
