//! `tail corrections ROBOT`: subscribes to the robot's corrections key on Zenoh (a peer connected to one
//! endpoint, no scouting) and prints each correction as it arrives.

use shift_client::ClientError;
use shift_client::proto::CorrectionDoc;
use shift_client::proto::keys::KeySpace;
use shift_client::robot::peer_config;

use crate::cli::TailStream;
use crate::input::bad;

/// Runs the command until `--count` corrections arrived (or forever).
pub async fn run(stream: TailStream, json: bool) -> anyhow::Result<()> {
    let TailStream::Corrections {
        robot,
        zenoh,
        prefix,
        fleet,
        count,
    } = stream;
    let keys = KeySpace::new(prefix, fleet).map_err(|e| bad(e.to_string()))?;
    let key = keys.corrections(&robot).map_err(|e| bad(e.to_string()))?;
    let config = peer_config(&zenoh)?;
    let session = zenoh::open(config)
        .await
        .map_err(|e| ClientError::Zenoh(format!("connecting to {zenoh}: {e}")))?;
    let sub = session
        .declare_subscriber(key.as_str())
        .await
        .map_err(|e| ClientError::Zenoh(e.to_string()))?;
    // On stderr, so scripts know the subscription is up (stdout carries only corrections).
    eprintln!("following {key} via {zenoh}");
    let mut seen = 0u64;
    while count.is_none_or(|n| seen < n) {
        let sample = sub.recv_async().await.map_err(|e| ClientError::Zenoh(e.to_string()))?;
        let bytes = sample.payload().to_bytes();
        let c: CorrectionDoc = match serde_json::from_slice(&bytes) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("shiftctl: a payload on {key} is not a correction: {e}");
                continue;
            }
        };
        seen += 1;
        if json {
            println!("{}", serde_json::to_string(&c)?);
        } else {
            println!("{}", line(&c));
        }
    }
    session.close().await.map_err(|e| ClientError::Zenoh(e.to_string()))?;
    Ok(())
}

/// One human line per correction.
fn line(c: &CorrectionDoc) -> String {
    let mut s = format!(
        "{} v{} -> v{} {} [{}..{}) {} waypoints, +{:.2} s, {} us",
        c.plan_id,
        c.base_version,
        c.version,
        c.reason.as_str(),
        c.from,
        c.to,
        c.waypoints.len(),
        c.dt_after_s,
        c.compute_us
    );
    if !c.skipped.is_empty() {
        s.push_str(&format!(", {} points skipped", c.skipped.len()));
    }
    s
}
