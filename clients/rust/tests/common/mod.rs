//! Running the `shiftctl` binary from the client's integration tests, as a script or an operator would.
// Each test binary uses the helpers it needs; the others are unused there.
#![allow(dead_code)]

use std::process::Output;

use anyhow::{Context, Result, ensure};
use serde_json::Value;

/// Runs shiftctl with `args` against `base` (no token from the environment); (exit code, stdout, stderr).
pub async fn ctl(base: &str, args: &[&str]) -> Result<(i32, String, String)> {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_shiftctl"));
    cmd.args(args).env("SHIFT_HTTP", base).env_remove("SHIFT_TOKEN");
    let out: Output = tokio::task::spawn_blocking(move || cmd.output()).await??;
    let code = out.status.code().context("shiftctl was killed")?;
    Ok((
        code,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    ))
}

/// Runs shiftctl and expects exit 0; its stdout.
pub async fn ok(base: &str, args: &[&str]) -> Result<String> {
    let (code, out, err) = ctl(base, args).await?;
    ensure!(code == 0, "shiftctl {args:?} exited {code}: {err}");
    Ok(out)
}

/// Runs shiftctl with `--json` and parses its stdout.
pub async fn json<T: serde::de::DeserializeOwned>(base: &str, args: &[&str]) -> Result<T> {
    let mut all = vec!["--json"];
    all.extend_from_slice(args);
    let out = ok(base, &all).await?;
    serde_json::from_str(&out).with_context(|| format!("shiftctl {args:?} printed {out}"))
}

/// Runs shiftctl with `--json`, expects exit 1 and the API error it prints on stderr: (status, code).
pub async fn refused(base: &str, args: &[&str]) -> Result<(u64, String)> {
    let mut all = vec!["--json"];
    all.extend_from_slice(args);
    let (code, _, err) = ctl(base, &all).await?;
    ensure!(code == 1, "shiftctl {args:?} exited {code}: {err}");
    let body: Value = serde_json::from_str(err.trim()).with_context(|| format!("stderr {err}"))?;
    Ok((
        body["status"].as_u64().context("status")?,
        body["error"]["code"].as_str().context("code")?.to_owned(),
    ))
}
