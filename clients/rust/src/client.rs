//! The HTTP client: base URL, bearer token, and the plumbing every call shares (URLs, auth header, error
//! bodies, JSON decoding). The calls themselves are grouped by resource in `sites.rs`, `plans.rs`, `robots.rs`
//! and `missions.rs`.

use std::time::Duration;

use reqwest::{Method, RequestBuilder, Response};
use serde::de::DeserializeOwned;

use crate::error::{ClientError, Result};

/// Default address of `shiftd serve`.
pub const DEFAULT_BASE_URL: &str = "http://127.0.0.1:7878";

/// An async client of one SHIFT daemon. Cheap to clone (the connection pool is shared).
///
/// ```no_run
/// # async fn run() -> shift_client::Result<()> {
/// let client = shift_client::Client::new("http://127.0.0.1:7878")?.with_token("s3cret");
/// let sites = client.sites().await?;
/// println!("{} sites", sites.items.len());
/// # Ok(()) }
/// ```
#[derive(Debug, Clone)]
pub struct Client {
    http: reqwest::Client,
    base: String,
    token: Option<String>,
}

impl Client {
    /// A client of the daemon at `base_url` (`http://host:port`, no path), with a 60 s request timeout (event
    /// streams have none).
    ///
    /// ```
    /// let client = shift_client::Client::new("http://127.0.0.1:7878/")?;
    /// assert_eq!(client.base_url(), "http://127.0.0.1:7878");
    /// assert!(shift_client::Client::new("127.0.0.1:7878").is_err());
    /// # Ok::<(), shift_client::ClientError>(())
    /// ```
    pub fn new(base_url: &str) -> Result<Self> {
        let http = reqwest::Client::builder()
            .connect_timeout(Duration::from_secs(10))
            .build()?;
        Self::with_http_client(base_url, http)
    }

    /// Like [`Client::new`] with a `reqwest::Client` configured by the caller (timeouts, proxies).
    ///
    /// ```
    /// let http = reqwest::Client::new();
    /// let client = shift_client::Client::with_http_client("http://10.0.0.5:7878", http)?;
    /// # Ok::<(), shift_client::ClientError>(())
    /// ```
    pub fn with_http_client(base_url: &str, http: reqwest::Client) -> Result<Self> {
        let base = base_url.trim().trim_end_matches('/');
        let rest = base
            .strip_prefix("http://")
            .or_else(|| base.strip_prefix("https://"))
            .ok_or_else(|| ClientError::InvalidInput(format!("base URL {base_url:?} must start with http://")))?;
        if rest.is_empty() || rest.contains('/') || rest.contains(char::is_whitespace) {
            return Err(ClientError::InvalidInput(format!(
                "base URL {base_url:?} must be scheme://host[:port] without a path"
            )));
        }
        Ok(Self {
            http,
            base: base.to_owned(),
            token: None,
        })
    }

    /// The same client sending `Authorization: Bearer {token}` (needed by mutating routes when the daemon
    /// has `auth_token` set). An empty token sends none.
    ///
    /// ```
    /// let client = shift_client::Client::new("http://127.0.0.1:7878")?.with_token("s3cret");
    /// # Ok::<(), shift_client::ClientError>(())
    /// ```
    pub fn with_token(mut self, token: impl Into<String>) -> Self {
        let token = token.into();
        self.token = (!token.trim().is_empty()).then(|| token.trim().to_owned());
        self
    }

    /// The daemon's base URL, without a trailing slash.
    pub fn base_url(&self) -> &str {
        &self.base
    }

    /// `GET /healthz`: true when the daemon answers 2xx.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// assert!(client.healthy().await?);
    /// # Ok(()) }
    /// ```
    pub async fn healthy(&self) -> Result<bool> {
        Ok(self
            .request(Method::GET, "/healthz")
            .send()
            .await?
            .status()
            .is_success())
    }

    /// `GET /readyz`: true when the store is open and the Zenoh session up.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// while !client.ready().await? {
    ///     tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    /// }
    /// # Ok(()) }
    /// ```
    pub async fn ready(&self) -> Result<bool> {
        Ok(self.request(Method::GET, "/readyz").send().await?.status().is_success())
    }

    /// `GET /openapi.json`: the API description.
    ///
    /// ```no_run
    /// # async fn run() -> shift_client::Result<()> {
    /// # let client = shift_client::Client::new("http://127.0.0.1:7878")?;
    /// let api = client.openapi().await?;
    /// assert!(api["paths"]["/v1/plans"].is_object());
    /// # Ok(()) }
    /// ```
    pub async fn openapi(&self) -> Result<serde_json::Value> {
        self.json(self.request(Method::GET, "/openapi.json"), "the OpenAPI document")
            .await
    }

    /// A request to `path` (starting with `/`) with the auth header.
    pub(crate) fn request(&self, method: Method, path: &str) -> RequestBuilder {
        let rb = self.http.request(method, format!("{}{path}", self.base));
        match &self.token {
            Some(t) => rb.bearer_auth(t),
            None => rb,
        }
    }

    /// Sends, and turns a non-2xx answer into [`ClientError::Api`].
    pub(crate) async fn send(&self, rb: RequestBuilder) -> Result<Response> {
        let r = rb.send().await?;
        if r.status().is_success() {
            return Ok(r);
        }
        let status = r.status();
        let retry_after = r
            .headers()
            .get(reqwest::header::RETRY_AFTER)
            .and_then(|v| v.to_str().ok())
            .map(str::to_owned);
        let body = r.bytes().await.unwrap_or_default();
        Err(ClientError::from_answer(status, &body, retry_after.as_deref()))
    }

    /// Sends and decodes a JSON answer.
    pub(crate) async fn json<T: DeserializeOwned>(&self, rb: RequestBuilder, what: &str) -> Result<T> {
        let body = self.send(rb).await?.bytes().await?;
        serde_json::from_slice(&body).map_err(|source| ClientError::Decode {
            what: what.to_owned(),
            source,
        })
    }
}

/// Percent-encodes one path segment (ids and names may hold characters a URL path must escape).
pub(crate) fn segment(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'_' | b'.' | b'~') {
            out.push(char::from(b));
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base_urls_and_segments() {
        assert!(Client::new("http://localhost:7878").is_ok());
        assert!(Client::new("https://shift.example").is_ok());
        assert!(Client::new("http://host/v1").is_err());
        assert!(Client::new("ftp://host").is_err());
        assert!(Client::new("http://").is_err());
        assert_eq!(segment("p-1"), "p-1");
        assert_eq!(segment("a b/c"), "a%20b%2Fc");
        assert_eq!(segment("é"), "%C3%A9");
    }
}
