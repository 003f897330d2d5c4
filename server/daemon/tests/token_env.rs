//! The bearer token from the environment (`SHIFT_AUTH_TOKEN`) of a real `shiftd serve` process, and never in
//! its logs. It lives in the daemon's package because it needs the binary (`CARGO_BIN_EXE_shiftd`): a test
//! cannot set an environment variable in its own process (`set_var` is unsafe, and unsafe code is forbidden).

use std::process::{Child, Command, Stdio};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use serde_json::json;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

const TOKEN: &str = "env-token-7c1f";

/// One request with `Connection: close` → status.
async fn post(port: u16, auth: Option<&str>) -> Result<u16> {
    let mut s = tokio::net::TcpStream::connect(("127.0.0.1", port)).await?;
    let body = json!({"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}}).to_string();
    let auth = auth.map(|a| format!("Authorization: {a}\r\n")).unwrap_or_default();
    let req = format!(
        "POST /v1/plans HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\nContent-Type: application/json\r\n\
         {auth}Content-Length: {}\r\n\r\n{body}",
        body.len()
    );
    s.write_all(req.as_bytes()).await?;
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).await?;
    let text = String::from_utf8_lossy(&raw);
    Ok(text.split(' ').nth(1).context("status")?.parse()?)
}

async fn ready(port: u16) -> bool {
    let Ok(mut s) = tokio::net::TcpStream::connect(("127.0.0.1", port)).await else {
        return false;
    };
    let req = "GET /readyz HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
    if s.write_all(req.as_bytes()).await.is_err() {
        return false;
    }
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).await.is_ok() && raw.starts_with(b"HTTP/1.1 200")
}

struct Daemon(Child);

impl Drop for Daemon {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_token_from_the_environment_guards_mutations_and_is_never_logged() -> Result<()> {
    let dir = tempfile::tempdir()?;
    let port = std::net::TcpListener::bind("127.0.0.1:0")?.local_addr()?.port();
    let config = dir.path().join("shiftd.toml");
    std::fs::write(
        &config,
        "[zenoh]\nenabled = false\n[jobs]\nworkers = 1\nshutdown_grace_s = 0\n",
    )?;
    let log = dir.path().join("shiftd.log");
    let child = Command::new(env!("CARGO_BIN_EXE_shiftd"))
        .args(["serve", "--bind", &format!("127.0.0.1:{port}")])
        .arg("--data-dir")
        .arg(dir.path().join("data"))
        .arg("--config")
        .arg(&config)
        .env("SHIFT_AUTH_TOKEN", TOKEN)
        .env("RUST_LOG", "debug")
        .stdout(Stdio::from(std::fs::File::create(dir.path().join("stdout.log"))?))
        .stderr(Stdio::from(std::fs::File::create(&log)?))
        .spawn()?;
    let mut daemon = Daemon(child);
    let mut up = false;
    for _ in 0..2400 {
        if let Some(status) = daemon.0.try_wait()? {
            bail!("shiftd exited while starting: {status}");
        }
        if ready(port).await {
            up = true;
            break;
        }
        tokio::time::sleep(Duration::from_millis(25)).await;
    }
    assert!(up, "shiftd did not become ready");

    assert_eq!(post(port, None).await?, 401);
    assert_eq!(post(port, Some("Bearer env-token-7c1F")).await?, 403, "same length");
    assert_eq!(post(port, Some("Bearer env")).await?, 403, "shorter");
    assert_eq!(post(port, Some(&format!("Bearer {TOKEN}"))).await?, 202);
    drop(daemon);

    let logged = std::fs::read_to_string(&log)? + &std::fs::read_to_string(dir.path().join("stdout.log"))?;
    assert!(logged.contains("shiftd serving"), "the log was written: {logged}");
    assert!(logged.contains("Env"), "the log names the token's source: {logged}");
    assert!(!logged.contains(TOKEN), "the token was logged");
    Ok(())
}
