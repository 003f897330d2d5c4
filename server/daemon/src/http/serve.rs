//! The HTTP/1 server loop (in place of `axum::serve`, which sets none of these): hyper's header read timeout,
//! a cap on open connections (a semaphore, mini-redis style: at the cap, new connections wait in the listen
//! backlog), a write-stall timeout per connection ([`StallGuard`]) and graceful shutdown.

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::net::TcpListener;
use tokio::sync::Semaphore;
use tokio_util::sync::CancellationToken;

use super::stall::StallGuard;

/// How connections are held to account.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConnLimits {
    /// A request head not complete this long after the connection opened (or after the previous response)
    /// closes the connection.
    pub header_read_timeout: Duration,
    /// Open connections at most.
    pub max_connections: usize,
    /// A response write that moves no byte for this long closes the connection.
    pub write_stall: Duration,
    /// After shutdown, how long open connections get to finish their responses.
    pub drain: Duration,
}

/// Serves `app` on `listener` until `shutdown` is cancelled; then stops accepting, lets every open connection
/// finish its current response (at most `limits.drain`) and returns.
pub async fn serve(listener: TcpListener, app: Router, limits: ConnLimits, shutdown: CancellationToken) {
    // `max_connections` is checked to fit a u32 by `HttpConfig::validate`.
    let slots = u32::try_from(limits.max_connections).unwrap_or(u32::MAX >> 3);
    let permits = Arc::new(Semaphore::new(slots as usize));
    loop {
        let permit = tokio::select! {
            _ = shutdown.cancelled() => break,
            p = permits.clone().acquire_owned() => match p {
                Ok(p) => p,
                Err(_) => break,
            },
        };
        let stream = tokio::select! {
            _ = shutdown.cancelled() => break,
            accepted = listener.accept() => match accepted {
                Ok((stream, _)) => stream,
                Err(e) => {
                    // Out of file descriptors, say: back off instead of spinning.
                    tracing::warn!("accepting a connection: {e}");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
        };
        let _ = stream.set_nodelay(true);
        let io = TokioIo::new(StallGuard::new(stream, limits.write_stall));
        let service = TowerToHyperService::new(app.clone());
        let stop = shutdown.clone();
        tokio::spawn(async move {
            let _slot = permit;
            let mut builder = http1::Builder::new();
            builder
                .timer(TokioTimer::new())
                .header_read_timeout(limits.header_read_timeout);
            let conn = builder.serve_connection(io, service);
            tokio::pin!(conn);
            let result = tokio::select! {
                r = conn.as_mut() => r,
                _ = stop.cancelled() => {
                    conn.as_mut().graceful_shutdown();
                    conn.await
                }
            };
            if let Err(e) = result {
                tracing::debug!("connection closed: {e}");
            }
        });
    }
    drop(listener);
    // Every slot back = every connection closed.
    let all = permits.acquire_many(slots);
    if tokio::time::timeout(limits.drain, all).await.is_err() {
        tracing::warn!("connections still open after the drain time; leaving them");
    }
}
