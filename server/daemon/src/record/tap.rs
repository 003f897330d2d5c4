//! Taps on the fleet's Zenoh session: subscribers of their own on the ingest keys and the liveliness tokens,
//! so what robots send is recorded exactly as it arrived (malformed payloads too: they matter in an incident)
//! without touching the fleet bridge. Topic = the key the sample came in on.

use std::sync::Arc;

use crate::err;
use crate::error::Result;
use shift_proto::keys::{KeySpace, Ros2Mapping, Stream};
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;
use zenoh::sample::SampleKind;

use super::Recorder;
use super::channels::Kind;

/// The key expressions recorded, with the stream each carries: those the fleet bridge ingests under the
/// fleet's key mapping (native, zenoh-bridge-ros2dds or rmw_zenoh).
pub fn ingest_keys(keys: &KeySpace, mapping: &Ros2Mapping) -> Vec<(String, Stream)> {
    mapping.subscriptions(keys)
}

/// Declares the taps; each runs until `stop` or the session closes.
pub async fn start(
    session: &zenoh::Session,
    keys: &Arc<KeySpace>,
    mapping: &Ros2Mapping,
    recorder: Recorder,
    stop: CancellationToken,
) -> Result<Vec<JoinHandle<()>>> {
    let z = |e: zenoh::Error| err!("zenoh (recorder tap): {e}");
    let mut tasks = Vec::new();
    for (key_expr, stream) in ingest_keys(keys, mapping) {
        let sub = session.declare_subscriber(key_expr).await.map_err(z)?;
        let (r, s) = (recorder.clone(), stop.clone());
        tasks.push(tokio::spawn(async move {
            loop {
                let sample = tokio::select! {
                    () = s.cancelled() => break,
                    x = sub.recv_async() => match x { Ok(x) => x, Err(_) => break },
                };
                let bytes = sample.payload().to_bytes().into_owned();
                let encoding = sample.encoding().to_string();
                if let Some(kind) = Kind::of_payload(stream, &bytes, &encoding) {
                    r.ingest(kind, sample.key_expr().as_str(), bytes);
                }
            }
        }));
    }
    let sub = session
        .liveliness()
        .declare_subscriber(keys.all_alive())
        .history(true)
        .await
        .map_err(z)?;
    let (r, s) = (recorder, stop);
    tasks.push(tokio::spawn(async move {
        loop {
            let sample = tokio::select! {
                () = s.cancelled() => break,
                x = sub.recv_async() => match x { Ok(x) => x, Err(_) => break },
            };
            r.liveliness(sample.key_expr().as_str(), sample.kind() == SampleKind::Put);
        }
    }));
    Ok(tasks)
}
