//! Bearer-token check on mutating routes (POST, PUT, PATCH, DELETE) when a token is configured. Reads are open
//! (operators watch status from a browser).
//!
//! - no `Authorization` header, or one that is not `Bearer <token>` → **401** `unauthorized`, with
//!   `WWW-Authenticate: Bearer` (the client did not authenticate);
//! - a bearer token that is not the configured one, whatever its length → **403** `forbidden`.
//!
//! The comparison is [`super::token::token_matches`] (constant time); the token is never logged.

use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::error::ApiError;
use super::token::{Secret, token_matches};

/// The token of a `Bearer` authorization header (the scheme is case-insensitive, RFC 7235).
fn bearer(req: &Request) -> Option<&[u8]> {
    let value = req.headers().get(header::AUTHORIZATION)?.as_bytes();
    let (scheme, rest) = value.split_at_checked(7)?;
    scheme.eq_ignore_ascii_case(b"bearer ").then(|| rest.trim_ascii())
}

/// The middleware; an empty `token` = no authentication.
pub async fn require_token(State(token): State<Arc<Secret>>, req: Request, next: Next) -> Response {
    let mutating = matches!(
        *req.method(),
        Method::POST | Method::PUT | Method::PATCH | Method::DELETE
    );
    if token.is_empty() || !mutating {
        return next.run(req).await;
    }
    match bearer(&req) {
        None => {
            let mut res = ApiError::new(
                StatusCode::UNAUTHORIZED,
                "unauthorized",
                "Authorization: this route needs a bearer token (Authorization: Bearer <token>)",
            )
            .into_response();
            res.headers_mut()
                .insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
            res
        }
        Some(given) if bool::from(token_matches(given, &token)) => next.run(req).await,
        Some(_) => ApiError::new(
            StatusCode::FORBIDDEN,
            "forbidden",
            "Authorization: the bearer token is not valid",
        )
        .into_response(),
    }
}
