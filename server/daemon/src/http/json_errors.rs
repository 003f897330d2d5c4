//! Error answers that no handler wrote — tower-http's 413 (a declared `Content-Length` over the route's
//! limit) and 408 (request timeout), axum's 405 and path rejections — get the API's error body
//! `{"error": {code, message}}` too, naming what was refused. Headers (`Allow`, `Retry-After`, …) are kept.

use axum::extract::{Request, State};
use axum::http::{StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::error::ApiError;

/// The per-route body limits, for the 413 message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BodyLimits {
    /// Map uploads (`[http] max_body_bytes`).
    pub map_bytes: usize,
    /// Every other route (`[http] max_request_bytes`).
    pub request_bytes: usize,
}

impl BodyLimits {
    /// The site uploads' limit (map, field, terrain).
    pub fn map(&self) -> BodyLimit {
        BodyLimit {
            bytes: self.map_bytes,
            key: "max_body_bytes",
        }
    }

    /// The other routes' limit.
    pub fn request(&self) -> BodyLimit {
        BodyLimit {
            bytes: self.request_bytes,
            key: "max_request_bytes",
        }
    }
}

/// One route's body limit and the configuration key that sets it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BodyLimit {
    /// Most bytes.
    pub bytes: usize,
    /// The `[http]` key that sets it.
    pub key: &'static str,
}

impl BodyLimit {
    /// The API's 413 for this limit.
    fn too_large(&self) -> ApiError {
        ApiError::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            "payload_too_large",
            format!(
                "body: the request body is larger than this route accepts ({} bytes, [http] {})",
                self.bytes, self.key
            ),
        )
    }

    /// A route's own 413 (tower-http's, plain text) as the API's error naming this limit; other responses
    /// pass. Layered on each limited route, so the message comes from the route table itself.
    pub async fn name_in_413(self, res: Response) -> Response {
        if res.status() != StatusCode::PAYLOAD_TOO_LARGE || is_json(&res) {
            return res;
        }
        let (parts, _) = res.into_parts();
        with_headers(self.too_large(), parts)
    }
}

fn is_json(res: &Response) -> bool {
    res.headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.starts_with("application/json"))
}

/// The middleware.
pub async fn json_errors(State(limits): State<BodyLimits>, req: Request, next: Next) -> Response {
    let (method, path) = (req.method().clone(), req.uri().path().to_owned());
    let res = next.run(req).await;
    let status = res.status();
    if !(status.is_client_error() || status.is_server_error()) || is_json(&res) {
        return res;
    }
    let error = match status {
        // A route without its own limit has the router's default, the site uploads' one.
        StatusCode::PAYLOAD_TOO_LARGE => limits.map().too_large(),
        StatusCode::REQUEST_TIMEOUT => ApiError::new(
            status,
            "request_timeout",
            "the request was not received and answered within [http] request_timeout_s",
        ),
        StatusCode::METHOD_NOT_ALLOWED => ApiError::new(
            status,
            "method_not_allowed",
            format!("method: {method} is not allowed on {path}"),
        ),
        s => {
            // axum's own rejections (a path segment that does not parse, say) say what is wrong in text.
            let (parts, body) = res.into_parts();
            let text = axum::body::to_bytes(body, 4096).await.unwrap_or_default();
            let text = String::from_utf8_lossy(&text).trim().to_owned();
            let reason = s.canonical_reason().unwrap_or("error");
            let message = if text.is_empty() {
                format!("{reason}: {path}")
            } else {
                format!("{path}: {text}")
            };
            return with_headers(ApiError::from_status(s, message), parts);
        }
    };
    let (parts, _) = res.into_parts();
    with_headers(error, parts)
}

/// The error's response with the original response's headers (`Allow`, `Retry-After`, …) but its own body type.
fn with_headers(error: ApiError, mut parts: axum::http::response::Parts) -> Response {
    let mut fixed = error.into_response();
    parts.headers.remove(header::CONTENT_TYPE);
    parts.headers.remove(header::CONTENT_LENGTH);
    for (name, value) in &parts.headers {
        fixed.headers_mut().append(name.clone(), value.clone());
    }
    fixed
}
