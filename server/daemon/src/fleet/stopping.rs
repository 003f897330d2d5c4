//! Ending the fleet's receive loops on shutdown.

use tokio_util::sync::CancellationToken;

/// The next item of a zenoh receiver, or `None` once `stop` is cancelled or the receiver closed.
pub async fn next_or_stop<T, E>(
    stop: &CancellationToken,
    recv: impl std::future::Future<Output = Result<T, E>>,
) -> Option<T> {
    tokio::select! {
        () = stop.cancelled() => None,
        r = recv => r.ok(),
    }
}
