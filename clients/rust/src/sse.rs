//! `GET /v1/plans/{id}/events` and `GET /v1/missions/{id}/events` as typed streams: a small `text/event-stream`
//! parser (the WHATWG rules this API needs: `event:`, `data:` lines joined by newlines, `id:`, comments, any of
//! `\n`, `\r\n`, `\r` as line ends) over reqwest's byte stream, each event decoded into a [`PlanEvent`] or a
//! [`MissionView`].

use std::collections::VecDeque;
use std::pin::Pin;
use std::task::{Context, Poll};

use futures_util::stream::{BoxStream, Stream, StreamExt};
use reqwest::Method;
use serde::de::DeserializeOwned;
use shift_proto::{MissionView, PlanEvent};

use crate::client::{Client, segment};
use crate::error::{ClientError, Result};

/// One server-sent event as framed on the wire.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SseFrame {
    /// The `event:` name (`message` when none was given).
    pub event: String,
    /// The `data:` lines, joined by `\n`.
    pub data: String,
    /// The last `id:` seen on the stream, if any.
    pub id: Option<String>,
}

/// Incremental `text/event-stream` parser: feed it bytes as they arrive, take out whole events.
///
/// ```
/// use shift_client::sse::SseParser;
/// let mut p = SseParser::default();
/// p.feed(b": keep-alive\nevent: progress\ndata: {\"a\":");
/// assert!(p.next_frame().is_none());
/// p.feed(b"1}\n\n");
/// let frame = p.next_frame().expect("a whole event");
/// assert_eq!((frame.event.as_str(), frame.data.as_str()), ("progress", "{\"a\":1}"));
/// ```
#[derive(Debug, Default)]
pub struct SseParser {
    buf: Vec<u8>,
    /// A `\r` ended the last line: a `\n` right after it belongs to the same line end.
    after_cr: bool,
    event: Option<String>,
    data: Option<String>,
    last_id: Option<String>,
    ready: VecDeque<SseFrame>,
}

impl SseParser {
    /// Adds received bytes.
    pub fn feed(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.after_cr {
                self.after_cr = false;
                if b == b'\n' {
                    continue;
                }
            }
            match b {
                b'\n' => self.line(),
                b'\r' => {
                    self.after_cr = true;
                    self.line();
                }
                _ => self.buf.push(b),
            }
        }
    }

    /// The next whole event, if one is complete.
    pub fn next_frame(&mut self) -> Option<SseFrame> {
        self.ready.pop_front()
    }

    fn line(&mut self) {
        let line = String::from_utf8_lossy(&self.buf).into_owned();
        self.buf.clear();
        if line.is_empty() {
            // Dispatch; an event without data is dropped (as browsers do).
            let event = self.event.take();
            if let Some(data) = self.data.take() {
                self.ready.push_back(SseFrame {
                    event: event.unwrap_or_else(|| "message".into()),
                    data,
                    id: self.last_id.clone(),
                });
            }
            return;
        }
        if line.starts_with(':') {
            return;
        }
        let (field, value) = match line.split_once(':') {
            Some((f, v)) => (f, v.strip_prefix(' ').unwrap_or(v)),
            None => (line.as_str(), ""),
        };
        match field {
            "event" => self.event = Some(value.to_owned()),
            "data" => match &mut self.data {
                Some(d) => {
                    d.push('\n');
                    d.push_str(value);
                }
                None => self.data = Some(value.to_owned()),
            },
            "id" if !value.contains('\0') => self.last_id = Some(value.to_owned()),
            _ => {}
        }
    }
}

/// A plan's events, as a [`Stream`] of [`PlanEvent`]s: first its current status, then progress,
/// region-ready, correction and status events; it ends after a terminal status (done, failed, cancelled), or
/// when the daemon shuts down.
pub struct PlanEvents {
    inner: BoxStream<'static, Result<PlanEvent>>,
}

impl PlanEvents {
    /// The next event; `None` at the end of the stream.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let mut events = client.events("p-1").await?;
    /// while let Some(event) = events.next_event().await? {
    ///     println!("{}", event.name());
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn next_event(&mut self) -> Result<Option<PlanEvent>> {
        self.inner.next().await.transpose()
    }
}

impl Stream for PlanEvents {
    type Item = Result<PlanEvent>;

    fn poll_next(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Self::Item>> {
        self.inner.as_mut().poll_next(cx)
    }
}

impl std::fmt::Debug for PlanEvents {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PlanEvents")
    }
}

/// A mission's events (`GET /v1/missions/{id}/events`), as a [`Stream`] of [`MissionView`]s: first its current
/// view, then one on every change (about once a second at most while only progress and measured coverage
/// move); it ends after `done`, `failed` or `cancelled`, or when the daemon shuts down. Events of other names
/// (a newer daemon's) are skipped.
pub struct MissionEvents {
    inner: BoxStream<'static, Result<MissionView>>,
}

impl MissionEvents {
    /// Follows the stream of events `bytes`.
    pub(crate) fn new<B: AsRef<[u8]> + Send + 'static>(bytes: impl Stream<Item = Result<B>> + Send + 'static) -> Self {
        Self {
            inner: typed(bytes, |name| name == "mission").boxed(),
        }
    }

    /// The next view; `None` at the end of the stream.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let mut views = client.mission_events("m-1").await?;
    /// while let Some(view) = views.next_view().await? {
    ///     println!("{} {:.0} %", view.status.as_str(), view.progress * 100.0);
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn next_view(&mut self) -> Result<Option<MissionView>> {
        self.inner.next().await.transpose()
    }
}

impl Stream for MissionEvents {
    type Item = Result<MissionView>;

    fn poll_next(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Self::Item>> {
        self.inner.as_mut().poll_next(cx)
    }
}

impl std::fmt::Debug for MissionEvents {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("MissionEvents")
    }
}

impl Client {
    /// `GET /v1/plans/{id}/events`: the plan's server-sent events, typed. Errors of the request itself (404
    /// for an unknown plan) come here; a broken stream later comes as an `Err` item.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// use futures_util::StreamExt;
    /// use shift_client::proto::PlanEvent;
    /// let mut events = client.events("p-1").await?;
    /// while let Some(event) = events.next().await {
    ///     match event? {
    ///         PlanEvent::Progress { progress, .. } => println!("{:.0} %", progress * 100.0),
    ///         PlanEvent::RegionReady { region, .. } => println!("region {} ready", region.region),
    ///         PlanEvent::Status(s) => println!("{}", s.status.as_str()),
    ///         PlanEvent::Correction(c) => println!("version {}", c.version),
    ///     }
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn events(&self, plan_id: &str) -> Result<PlanEvents> {
        let path = format!("/v1/plans/{}/events", segment(plan_id));
        let bytes = self.open_stream(&path).await?;
        Ok(PlanEvents {
            inner: typed(bytes, |_| true).boxed(),
        })
    }

    /// Opens `GET {path}` as an event stream: its bytes, once the answer is a 2xx `text/event-stream`.
    pub(crate) async fn open_stream(
        &self,
        path: &str,
    ) -> Result<impl Stream<Item = Result<impl AsRef<[u8]> + Send + 'static>> + Send + 'static> {
        let rb = self
            .request(Method::GET, path)
            .header(reqwest::header::ACCEPT, "text/event-stream");
        let response = self.send(rb).await?;
        let content_type = response
            .headers()
            .get(reqwest::header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .unwrap_or("")
            .to_owned();
        if !content_type.starts_with("text/event-stream") {
            return Err(ClientError::Stream(format!(
                "expected text/event-stream, got {content_type:?}"
            )));
        }
        Ok(response.bytes_stream().map(|r| r.map_err(ClientError::from)))
    }
}

/// Frames and decodes a byte stream: each event whose name `wanted` accepts, as a `T`; others are skipped.
pub(crate) fn typed<T: DeserializeOwned + Send + 'static, B: AsRef<[u8]> + Send + 'static>(
    bytes: impl Stream<Item = Result<B>> + Send + 'static,
    wanted: fn(&str) -> bool,
) -> impl Stream<Item = Result<T>> + Send + 'static {
    let state = (Box::pin(bytes), SseParser::default(), false);
    futures_util::stream::unfold(state, move |(mut bytes, mut parser, mut done)| async move {
        loop {
            if let Some(frame) = parser.next_frame() {
                if !wanted(&frame.event) {
                    continue;
                }
                let event = serde_json::from_str::<T>(&frame.data).map_err(|source| ClientError::Decode {
                    what: format!("a {:?} event", frame.event),
                    source,
                });
                return Some((event, (bytes, parser, done)));
            }
            if done {
                return None;
            }
            match bytes.next().await {
                Some(Ok(chunk)) => parser.feed(chunk.as_ref()),
                Some(Err(e)) => {
                    done = true;
                    return Some((Err(e), (bytes, parser, done)));
                }
                None => {
                    // A last event without its blank line is incomplete: dropped, as the SSE rules say.
                    done = true;
                }
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_split_anywhere_and_any_line_end() {
        let text = "event: status\r\ndata: {\"x\":\r\ndata: 1}\r\n\r\n: comment\rid: 7\revent: progress\rdata: 2\r\r\
                    data: plain\n\n";
        for chunk in [1, 2, 3, 7, text.len()] {
            let mut p = SseParser::default();
            let mut got = Vec::new();
            for part in text.as_bytes().chunks(chunk) {
                p.feed(part);
                while let Some(f) = p.next_frame() {
                    got.push(f);
                }
            }
            assert_eq!(got.len(), 3, "chunk {chunk}");
            assert_eq!((got[0].event.as_str(), got[0].data.as_str()), ("status", "{\"x\":\n1}"));
            assert_eq!((got[1].event.as_str(), got[1].data.as_str()), ("progress", "2"));
            assert_eq!(got[1].id.as_deref(), Some("7"));
            assert_eq!(got[2].event, "message");
        }
    }

    #[tokio::test]
    async fn mission_streams_decode_mission_events_and_skip_others() {
        let view = r#"{"mission_id":"m-1","site":"s","status":"planning","progress":0.5,"plans":[{"robot":"r1",
            "plan_id":"p-1","status":"planning","version":0,"driven_fraction":0.0}],"coverage":{"measured_pct":0.0},
            "created_ms":1,"updated_ms":2,"later_field":true}"#
            .replace('\n', "");
        let text = format!(
            ": keep-alive\n\nevent: mission\ndata: {view}\n\nevent: other\ndata: 1\n\nevent: mission\ndata: {{\n\n"
        );
        let chunks: Vec<Result<Vec<u8>>> = text.as_bytes().chunks(5).map(|c| Ok(c.to_vec())).collect();
        let mut events = MissionEvents::new(futures_util::stream::iter(chunks));
        let first = events.next_view().await.expect("decodes").expect("a view");
        assert_eq!((first.mission_id.as_str(), first.plans.len()), ("m-1", 1));
        assert_eq!(first.status, shift_proto::MissionStatus::Planning);
        assert!(matches!(events.next_view().await, Err(ClientError::Decode { .. })));
        assert!(events.next_view().await.expect("ends").is_none());
    }

    #[test]
    fn events_without_data_are_dropped() {
        let mut p = SseParser::default();
        p.feed(b"event: x\n\n");
        assert!(p.next_frame().is_none());
    }
}
