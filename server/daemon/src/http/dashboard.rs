//! The operator's page (issue 21): `dashboard/` beside this crate's `src/`, compiled into the binary with
//! `include_dir` and served at `/` (index.html) and `/dashboard/{file}`. Plain ES modules, no build step: the
//! page talks only to this daemon's API (reads are open; mutating calls carry the operator's bearer token in a
//! header, never in a URL).

use axum::extract::Path;
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};
use include_dir::{Dir, include_dir};

use super::error::ApiError;

static ASSETS: Dir<'_> = include_dir!("$CARGO_MANIFEST_DIR/dashboard");

/// Content type by extension (only the kinds the page ships).
fn content_type(name: &str) -> &'static str {
    match name.rsplit_once('.').map(|(_, ext)| ext) {
        Some("html") => "text/html; charset=utf-8",
        Some("js") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("svg") => "image/svg+xml",
        Some("png") => "image/png",
        Some("json") => "application/json",
        _ => "application/octet-stream",
    }
}

fn asset(name: &str) -> Result<Response, ApiError> {
    // Flat folder: no sub-paths, so nothing outside it can be named.
    let file = (!name.contains('/') && !name.contains(".."))
        .then(|| ASSETS.get_file(name))
        .flatten()
        .ok_or_else(|| ApiError::not_found(format!("no dashboard file {name:?}")))?;
    let mut res = file.contents().into_response();
    let headers = res.headers_mut();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(content_type(name)));
    // The binary is the version: a new daemon may ship a new page, so browsers revalidate.
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    Ok(res)
}

/// `GET /`: the page.
pub async fn index() -> Result<Response, ApiError> {
    asset("index.html")
}

/// `GET /dashboard/{file}`: its scripts and styles.
pub async fn file(Path(name): Path<String>) -> Result<Response, ApiError> {
    asset(&name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_page_and_its_modules_are_embedded_with_their_types() {
        let names: Vec<&str> = ASSETS.files().filter_map(|f| f.path().to_str()).collect();
        assert!(names.contains(&"index.html"), "{names:?}");
        assert!(names.iter().any(|n| n.ends_with(".js")), "{names:?}");
        assert_eq!(content_type("app.js"), "text/javascript; charset=utf-8");
        assert_eq!(content_type("index.html"), "text/html; charset=utf-8");
        assert!(asset("../Cargo.toml").is_err());
        assert!(asset("nope.js").is_err());
    }
}
