//! A Server-Sent Events reader for the tests: `(event name, JSON data)` pairs, keep-alive comments skipped.

use std::pin::Pin;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use futures_util::{Stream, StreamExt};
use serde_json::Value;

type Bytes = Pin<Box<dyn Stream<Item = reqwest::Result<Vec<u8>>> + Send>>;

/// One open event stream.
pub struct SseReader {
    stream: Bytes,
    buf: String,
}

impl SseReader {
    /// Opens `url` (it must answer 200).
    pub async fn open(http: &reqwest::Client, url: &str) -> Result<Self> {
        let r = http.get(url).send().await?;
        if r.status().as_u16() != 200 {
            bail!("{url}: {}", r.status());
        }
        Ok(Self {
            stream: Box::pin(r.bytes_stream().map(|chunk| chunk.map(|b| b.to_vec()))),
            buf: String::new(),
        })
    }

    /// The next event, waiting at most `timeout` for it; `None` when the stream ended.
    pub async fn next(&mut self, timeout: Duration) -> Result<Option<(String, Value)>> {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            while let Some(end) = self.buf.find("\n\n") {
                let block: String = self.buf.drain(..end + 2).collect();
                let mut name = String::new();
                let mut data = String::new();
                for line in block.lines() {
                    if let Some(v) = line.strip_prefix("event:") {
                        name = v.trim().to_owned();
                    } else if let Some(v) = line.strip_prefix("data:") {
                        data.push_str(v.trim());
                    }
                }
                if !name.is_empty() {
                    let value = serde_json::from_str(&data).with_context(|| format!("event {name}: {data}"))?;
                    return Ok(Some((name, value)));
                }
            }
            let chunk = tokio::time::timeout_at(deadline, self.stream.next())
                .await
                .context("no event in time")?;
            match chunk {
                Some(bytes) => self.buf.push_str(&String::from_utf8_lossy(&bytes?)),
                None => return Ok(None),
            }
        }
    }

    /// Events until `stop` says so (inclusive) or the stream ends, each waited for at most `timeout`.
    pub async fn until(
        &mut self,
        timeout: Duration,
        mut stop: impl FnMut(&str, &Value) -> bool,
    ) -> Result<Vec<(String, Value)>> {
        let mut out = Vec::new();
        while let Some((name, value)) = self.next(timeout).await? {
            let done = stop(&name, &value);
            out.push((name, value));
            if done {
                break;
            }
        }
        Ok(out)
    }
}
