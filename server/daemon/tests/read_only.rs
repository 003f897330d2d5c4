//! A data dir that turns read-only under a running daemon (issue 22), as a real disk does: ext4 mounted with
//! `errors=remount-ro` remounts itself read-only when it meets an error, and from then on every write fails —
//! through files already open (EIO) and new ones (EROFS). The test makes such a file system in a file, mounts
//! it over a loop device in a mount namespace of the daemon's own (`unshare`, so nothing outside sees it), and
//! triggers the error with ext4's `trigger_fs_error` switch.
//!
//! While read-only: writes are refused with 503 and a message naming the store, nothing of them is stored or
//! served, every read is still served and `/readyz` says why writes are refused. After kill -9 and `e2fsck`,
//! the store opens holding exactly what was acknowledged.
//!
//! It needs root (or a user namespace allowed to mount) and a loop device; where the machine gives neither, it
//! says so and checks nothing (CI runs as root with loop devices).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail, ensure};
use serde_json::{Value, json};

use common::{Daemon, free_port, http, pillar_grid as grid};

const CONFIG: &str = "[jobs]\nworkers = 1\nshutdown_grace_s = 0\n";

/// Mounts `$0` (the image) on `$1` in a private mount namespace, then runs the rest.
const MOUNT_THEN_EXEC: &str = "mount -o loop,errors=remount-ro \"$0\" \"$1\" && shift && exec \"$@\"";

fn run(program: &str, args: &[&str]) -> Result<std::process::Output> {
    Command::new(program)
        .args(args)
        .output()
        .with_context(|| format!("running {program}"))
}

fn path_str(p: &Path) -> Result<&str> {
    p.to_str().context("a UTF-8 temp path")
}

/// An ext4 image of `mb` MiB (sparse).
fn make_image(img: &Path, mb: u64) -> Result<()> {
    std::fs::File::create(img)?.set_len(mb << 20)?;
    let out = run("mkfs.ext4", &["-q", "-F", path_str(img)?])?;
    ensure!(
        out.status.success(),
        "mkfs.ext4: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    Ok(())
}

/// `unshare` running `script` (`sh -c`, with `$0` the image and `$1` the mount point) in a private mount
/// namespace, as arguments.
fn in_namespace(script: &str, img: &Path, mnt: &Path) -> Result<Vec<String>> {
    let head = ["--mount", "--propagation", "private", "--", "sh", "-c", script];
    let mut args: Vec<String> = head.map(str::to_owned).to_vec();
    args.push(path_str(img)?.to_owned());
    args.push(path_str(mnt)?.to_owned());
    Ok(args)
}

/// Whether this machine lets the test mount a loop device in a namespace of its own.
fn can_mount(img: &Path, mnt: &Path) -> bool {
    let Ok(args) = in_namespace("mount -o loop \"$0\" \"$1\" && umount \"$1\"", img, mnt) else {
        return false;
    };
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    run("unshare", &args).map(|o| o.status.success()).unwrap_or(false)
}

/// The wrapper that starts shiftd on the image mounted at `mnt`.
fn mounted(img: &Path, mnt: &Path) -> Result<Vec<String>> {
    let mut wrapper = vec!["unshare".to_owned()];
    wrapper.extend(in_namespace(MOUNT_THEN_EXEC, img, mnt)?);
    Ok(wrapper)
}

/// The loop devices backing `img` (`/dev/loopN` → `loopN`).
fn loop_devices(img: &Path) -> Result<Vec<String>> {
    let out = run("losetup", &["-j", path_str(img)?])?;
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split(':').next())
        .filter_map(|dev| dev.rsplit('/').next().map(str::to_owned))
        .collect())
}

/// ext4's own error path: with `errors=remount-ro` the file system turns read-only at once.
fn trigger_fs_error(img: &Path) -> Result<()> {
    let devices = loop_devices(img)?;
    let dev = devices.first().context("the image's loop device")?;
    let switch = PathBuf::from(format!("/sys/fs/ext4/{dev}/trigger_fs_error"));
    std::fs::write(&switch, "1").with_context(|| format!("writing {}", switch.display()))
}

/// After the daemon is gone its namespace, mount and loop device go too; then the image is checked and repaired.
fn fsck_when_released(img: &Path) -> Result<()> {
    let until = Instant::now() + Duration::from_secs(20);
    while !loop_devices(img)?.is_empty() {
        ensure!(
            Instant::now() < until,
            "the loop device of {} was not released",
            img.display()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let out = run("e2fsck", &["-f", "-y", path_str(img)?])?;
    // 0: clean, 1: errors corrected (the error the test triggered is recorded in the superblock).
    ensure!(
        matches!(out.status.code(), Some(0 | 1)),
        "e2fsck: {:?} {}",
        out.status,
        String::from_utf8_lossy(&out.stdout)
    );
    Ok(())
}

fn plan_request(site: &str) -> Value {
    json!({"site": site, "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}})
}

fn site_names(body: &Value) -> Vec<String> {
    let mut names: Vec<String> = body["items"]
        .as_array()
        .map(|a| a.iter().filter_map(|s| s["site"].as_str().map(str::to_owned)).collect())
        .unwrap_or_default();
    names.retain(|s| s != "demo");
    names.sort();
    names
}

async fn wait_ready(d: &Daemon, plan: &str) -> Result<Value> {
    let until = Instant::now() + Duration::from_secs(60);
    loop {
        let (code, body) = d.get(&format!("/v1/plans/{plan}")).await?;
        ensure!(code == 200, "GET plan {plan}: {code} {body}");
        if body["status"] == "ready" {
            return Ok(body);
        }
        ensure!(
            Instant::now() < until,
            "plan {plan} is {} after a minute",
            body["status"]
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// A 503 naming the store (`store_read_only`, or `store_unavailable` for the first write, which meets EIO).
fn assert_store_refused(what: &str, code: u16, body: &Value) {
    let name = body["error"]["code"].as_str().unwrap_or_default();
    assert!(
        code == 503 && matches!(name, "store_read_only" | "store_unavailable"),
        "{what} while read-only: {code} {body}"
    );
    let message = body["error"]["message"].as_str().unwrap_or_default();
    assert!(
        message.contains("store"),
        "{what}: the message names the store: {message}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_data_dir_turning_read_only_refuses_writes_with_503_keeps_reads_and_loses_nothing_acknowledged() -> Result<()>
{
    let dir = tempfile::tempdir()?;
    let (img, mnt) = (dir.path().join("disk.img"), dir.path().join("mnt"));
    std::fs::create_dir_all(&mnt)?;
    make_image(&img, 256)?;
    if !can_mount(&img, &mnt) {
        eprintln!("skipped: this machine does not let the test mount a loop device in its own namespace");
        return Ok(());
    }
    let data = mnt.join("data");
    let port = free_port()?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let d = Daemon::start_wrapped(dir.path(), &data, port, &endpoint, CONFIG, &mounted(&img, &mnt)?).await?;

    // Before: two sites and a computed plan.
    let mut acknowledged = Vec::new();
    for (k, site) in ["before", "second"].into_iter().enumerate() {
        let (code, body) = http(port, "POST", &format!("/v1/sites/{site}/map"), Some(&grid(200, k))).await?;
        ensure!(code == 201, "upload {site}: {code} {body}");
        acknowledged.push(site.to_owned());
    }
    let (code, body) = d.post("/v1/plans", &plan_request("before")).await?;
    ensure!(code == 202, "{code} {body}");
    let plan = body["plan_id"].as_str().context("plan_id")?.to_owned();
    let ready = wait_ready(&d, &plan).await?;

    trigger_fs_error(&img)?;

    // Every write is refused with 503 naming the store; nothing of it is served.
    let (code, body) = http(port, "POST", "/v1/sites/refused/map", Some(&grid(200, 7))).await?;
    assert_store_refused("an upload", code, &body);
    let (code, body) = d.post("/v1/plans", &plan_request("before")).await?;
    assert_store_refused("a plan request", code, &body);
    // The store is probed again within a second: reopening a read-only file system says so.
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let (code, body) = http(port, "POST", "/v1/sites/refused/map", Some(&grid(200, 8))).await?;
    assert_eq!(
        (code, body["error"]["code"].as_str()),
        (503, Some("store_read_only")),
        "after the probe: {body}"
    );
    let (code, body) = http(port, "DELETE", &format!("/v1/plans/{plan}"), None).await?;
    assert_store_refused("a cancel", code, &body);
    let (code, body) = d.get("/readyz").await?;
    assert_eq!((code, body["store"].as_str()), (200, Some("read_only")), "{body}");

    // Every read is served.
    let (code, body) = d.get("/v1/sites").await?;
    assert_eq!(code, 200);
    assert_eq!(site_names(&body), acknowledged);
    assert_eq!(d.get("/v1/sites/refused").await?.0, 404, "nothing refused is served");
    let (code, body) = d.get(&format!("/v1/plans/{plan}")).await?;
    assert_eq!((code, &body["status"]), (200, &ready["status"]), "{body}");
    assert_eq!(d.get(&format!("/v1/plans/{plan}/path")).await?.0, 200);
    let (code, body) = d.get("/v1/plans").await?;
    assert_eq!(code, 200, "{body}");
    assert_eq!(
        body["items"].as_array().map(Vec::len),
        Some(1),
        "one plan was accepted: {body}"
    );

    // kill -9, repair the file system, start again: exactly what was acknowledged is there.
    d.kill9()?;
    fsck_when_released(&img)?;
    let d = Daemon::start_wrapped(dir.path(), &data, port, &endpoint, CONFIG, &mounted(&img, &mnt)?).await?;
    let (_, body) = d.get("/v1/sites").await?;
    assert_eq!(site_names(&body), acknowledged);
    let (code, body) = d.get(&format!("/v1/plans/{plan}")).await?;
    assert_eq!((code, body["status"].as_str()), (200, Some("ready")), "{body}");
    let (_, body) = d.get("/v1/plans").await?;
    assert_eq!(body["items"].as_array().map(Vec::len), Some(1), "{body}");
    // And it writes again.
    let (code, body) = http(port, "POST", "/v1/sites/after/map", Some(&grid(200, 9))).await?;
    ensure!(code == 201, "upload after repair: {code} {body}");
    d.kill9()?;
    if let Err(e) = fsck_when_released(&img) {
        bail!("the image after the test: {e:#}");
    }
    Ok(())
}
