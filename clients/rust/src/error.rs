//! The client's one error type.

use shift_proto::{ErrorBody, ErrorDetail};

/// What can go wrong talking to SHIFT.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The server answered with an error status; `error` is its `{"error": {code, message}}` body (or, for an
    /// answer without that body, code `http_error` and the body's text).
    #[error("{status}: {} ({})", .error.message, .error.code)]
    Api {
        /// HTTP status.
        status: reqwest::StatusCode,
        /// The error body's inside.
        error: ErrorDetail,
        /// The wait the answer's `Retry-After` header asks for (a 429 when the plan queue is full), when it
        /// gives one in seconds.
        retry_after: Option<std::time::Duration>,
    },
    /// The request never got an answer (connection refused, timeout, broken body).
    #[error("transport: {0}")]
    Transport(#[from] reqwest::Error),
    /// An answer that is not the JSON the API promises.
    #[error("decoding {what}: {source}")]
    Decode {
        /// What was being decoded.
        what: String,
        /// Why it failed.
        #[source]
        source: serde_json::Error,
    },
    /// The event stream broke its format (not `text/event-stream`).
    #[error("event stream: {0}")]
    Stream(String),
    /// Waiting for something took longer than allowed.
    #[error("timed out: {0}")]
    Timeout(String),
    /// An argument the client refuses before sending anything (bad base URL, token, robot name…).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A Zenoh operation failed.
    #[error("zenoh: {0}")]
    Zenoh(String),
}

impl ClientError {
    /// The HTTP status of an API error.
    pub fn status(&self) -> Option<reqwest::StatusCode> {
        match self {
            Self::Api { status, .. } => Some(*status),
            _ => None,
        }
    }

    /// The API's error code (`not_found`, `invalid_request`, `queue_full`…) of an API error.
    pub fn code(&self) -> Option<&str> {
        match self {
            Self::Api { error, .. } => Some(&error.code),
            _ => None,
        }
    }

    /// The wait a 429 (or 503) asks for before the request is sent again (its `Retry-After` header).
    pub fn retry_after(&self) -> Option<std::time::Duration> {
        match self {
            Self::Api { retry_after, .. } => *retry_after,
            _ => None,
        }
    }

    /// The server answered (an API error), as opposed to a failure on the way or in the client.
    pub fn is_api(&self) -> bool {
        matches!(self, Self::Api { .. })
    }

    /// Builds the API error of a non-2xx answer from its body and its `Retry-After` header's value.
    pub(crate) fn from_answer(status: reqwest::StatusCode, body: &[u8], retry_after: Option<&str>) -> Self {
        let error = match serde_json::from_slice::<ErrorBody>(body) {
            Ok(b) => b.error,
            Err(_) => ErrorDetail {
                code: "http_error".into(),
                message: String::from_utf8_lossy(body).chars().take(500).collect(),
            },
        };
        // Delta-seconds only: shiftd sends those; an HTTP date reads as no advice.
        let retry_after = retry_after
            .and_then(|v| v.trim().parse::<u64>().ok())
            .map(std::time::Duration::from_secs);
        Self::Api {
            status,
            error,
            retry_after,
        }
    }
}

/// Results of this crate.
pub type Result<T, E = ClientError> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn api_errors_keep_the_body_or_the_text() {
        let e = ClientError::from_answer(
            reqwest::StatusCode::NOT_FOUND,
            br#"{"error": {"code": "not_found", "message": "unknown plan \"p-9\""}}"#,
            None,
        );
        assert_eq!(e.code(), Some("not_found"));
        assert_eq!(e.status(), Some(reqwest::StatusCode::NOT_FOUND));
        assert!(e.to_string().contains("unknown plan"), "{e}");
        let e = ClientError::from_answer(reqwest::StatusCode::BAD_GATEWAY, b"upstream down", None);
        assert_eq!(e.code(), Some("http_error"));
        assert!(e.to_string().contains("upstream down"));
        assert_eq!(e.retry_after(), None);
    }

    #[test]
    fn a_429_keeps_its_retry_after_in_seconds() {
        let body = br#"{"error": {"code": "queue_full", "message": "64 plans waiting"}}"#;
        let e = ClientError::from_answer(reqwest::StatusCode::TOO_MANY_REQUESTS, body, Some(" 5 "));
        assert_eq!(e.retry_after(), Some(std::time::Duration::from_secs(5)));
        let e = ClientError::from_answer(
            reqwest::StatusCode::TOO_MANY_REQUESTS,
            body,
            Some("Wed, 21 Oct 2015 07:28:00 GMT"),
        );
        assert_eq!((e.code(), e.retry_after()), (Some("queue_full"), None));
    }
}
