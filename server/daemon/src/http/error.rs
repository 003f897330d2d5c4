//! API errors: one type that every handler returns, rendered as `{"error": {"code", "message"}}` with the
//! status that fits. Extractor rejections are mapped here too, so no plain-text error reaches a client.

use axum::Json;
use axum::extract::rejection::JsonRejection;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use shift_engine::EngineError;
use shift_proto::{ErrorBody, ErrorDetail};

use crate::engine_loop::handle::LoopError;

/// An error answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ApiError {
    /// HTTP status.
    pub status: StatusCode,
    /// Stable code.
    pub code: &'static str,
    /// What is wrong and where.
    pub message: String,
    /// Seconds for a `Retry-After` header (429, 503).
    pub retry_after_s: Option<u64>,
}

impl ApiError {
    /// Builds an error.
    pub fn new(status: StatusCode, code: &'static str, message: impl Into<String>) -> Self {
        Self {
            status,
            code,
            message: message.into(),
            retry_after_s: None,
        }
    }

    /// The same error with a `Retry-After: secs` header.
    pub fn with_retry_after(self, secs: u64) -> Self {
        Self {
            retry_after_s: Some(secs),
            ..self
        }
    }

    /// 400 with code `invalid_request`.
    pub fn bad_request(message: impl Into<String>) -> Self {
        Self::new(StatusCode::BAD_REQUEST, "invalid_request", message)
    }

    /// 404.
    pub fn not_found(message: impl Into<String>) -> Self {
        Self::new(StatusCode::NOT_FOUND, "not_found", message)
    }

    /// Maps a body-reading failure by its status (413 stays 413).
    pub fn from_status(status: StatusCode, message: String) -> Self {
        match status {
            StatusCode::PAYLOAD_TOO_LARGE => Self::new(status, "payload_too_large", message),
            StatusCode::UNSUPPORTED_MEDIA_TYPE => Self::new(status, "unsupported_media_type", message),
            // axum says 422 for well-formed JSON of the wrong shape; the API says 400 for every invalid input.
            StatusCode::UNPROCESSABLE_ENTITY => Self::bad_request(message),
            s if s.is_client_error() => Self::new(s, "invalid_request", message),
            s => Self::new(s, "internal", message),
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = ErrorBody {
            error: ErrorDetail {
                code: self.code.to_owned(),
                message: self.message,
            },
        };
        let mut res = (self.status, Json(body)).into_response();
        if let Some(secs) = self.retry_after_s {
            res.headers_mut().insert(header::RETRY_AFTER, HeaderValue::from(secs));
        }
        res
    }
}

impl From<JsonRejection> for ApiError {
    fn from(r: JsonRejection) -> Self {
        Self::from_status(r.status(), r.body_text())
    }
}

impl From<EngineError> for ApiError {
    fn from(e: EngineError) -> Self {
        let status = match &e {
            EngineError::InvalidRequest(_) | EngineError::Map(_) => StatusCode::BAD_REQUEST,
            EngineError::UnknownSite(_) | EngineError::UnknownPlan(_) | EngineError::UnknownMission(_) => {
                StatusCode::NOT_FOUND
            }
            EngineError::InvalidState { .. } | EngineError::MissionState { .. } => StatusCode::CONFLICT,
            EngineError::QueueFull { .. } => StatusCode::TOO_MANY_REQUESTS,
            EngineError::ShuttingDown => StatusCode::SERVICE_UNAVAILABLE,
        };
        let code = match &e {
            EngineError::InvalidRequest(_) => "invalid_request",
            EngineError::Map(_) => "invalid_map",
            EngineError::UnknownSite(_) | EngineError::UnknownPlan(_) | EngineError::UnknownMission(_) => "not_found",
            EngineError::InvalidState { .. } | EngineError::MissionState { .. } => "invalid_state",
            EngineError::QueueFull { .. } => "queue_full",
            EngineError::ShuttingDown => "shutting_down",
        };
        Self::new(status, code, e.to_string())
    }
}

use crate::store::fault::FaultKind;

impl From<LoopError> for ApiError {
    fn from(e: LoopError) -> Self {
        match e {
            LoopError::Engine(e) => e.into(),
            LoopError::Store(e) => {
                let (status, code) = match e.kind {
                    FaultKind::Full => (StatusCode::INSUFFICIENT_STORAGE, "store_full"),
                    FaultKind::ReadOnly => (StatusCode::SERVICE_UNAVAILABLE, "store_read_only"),
                    FaultKind::Io => (StatusCode::SERVICE_UNAVAILABLE, "store_unavailable"),
                    FaultKind::Data => (StatusCode::INTERNAL_SERVER_ERROR, "store"),
                };
                Self::new(
                    status,
                    code,
                    format!("{e}; nothing of this request was stored, reads are still served"),
                )
            }
            LoopError::Stopped => Self::new(StatusCode::SERVICE_UNAVAILABLE, "shutting_down", e.to_string()),
        }
    }
}

/// `Json<T>` whose rejections are [`ApiError`]s.
#[derive(Debug, Clone, Copy, Default, axum::extract::FromRequest)]
#[from_request(via(axum::Json), rejection(ApiError))]
pub struct ApiJson<T>(pub T);

impl<T: serde::Serialize> IntoResponse for ApiJson<T> {
    fn into_response(self) -> Response {
        Json(self.0).into_response()
    }
}
