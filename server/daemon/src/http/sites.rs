//! `POST /v1/sites/{site}/map` and `GET /v1/sites/{site}`.

use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Path, Request, State};
use axum::http::{StatusCode, header};
use shift_engine::{Event, LoadedSite, MapSource, SiteRecord};
use shift_proto::{ErrorBody, OccupancyGridDoc, SiteSummary};

use super::AppState;
use super::error::{ApiError, ApiJson};

/// Upload an occupancy map: multipart with parts `yaml` (map_server YAML) and `image` (PGM or PNG), or
/// `Content-Type: application/json` with a nav_msgs/OccupancyGrid-shaped grid. Replaces the site's map.
#[utoipa::path(post, path = "/v1/sites/{site}/map", tag = "sites",
    params(("site" = String, Path, description = "site name: letters, digits, '-', '_'")),
    request_body(content = String, description = "multipart (yaml, image) or JSON grid",
        content_type = "multipart/form-data"),
    responses((status = 201, body = SiteSummary),
        (status = 400, description = "invalid site name or map (named in the message)", body = ErrorBody),
        (status = 401, description = "no bearer token", body = ErrorBody),
        (status = 403, description = "wrong bearer token", body = ErrorBody),
        (status = 408, description = "request not received in time", body = ErrorBody),
        (status = 413, description = "body over [http] max_body_bytes", body = ErrorBody),
        (status = 415, body = ErrorBody)))]
pub async fn upload_map(
    State(state): State<AppState>,
    Path(site): Path<String>,
    req: Request,
) -> Result<(StatusCode, ApiJson<SiteSummary>), ApiError> {
    // The name before the body: a bad name costs the client nothing to learn.
    shift_engine::site::validate_site_name(&site)?;
    let content_type = req
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    let source = if content_type.starts_with("application/json") {
        let body = Bytes::from_request(req, &())
            .await
            .map_err(|r| ApiError::from_status(r.status(), r.body_text()))?;
        // The shape first, so a refusal names the field (`origin[0]: number out of range`); the engine then
        // reads the same text into its grid.
        let _shape: axum::Json<OccupancyGridDoc> = axum::Json::from_bytes(&body)?;
        let text = String::from_utf8(body.to_vec()).map_err(|_| ApiError::bad_request("body is not UTF-8"))?;
        MapSource::Json { text }
    } else if content_type.starts_with("multipart/form-data") {
        let mut mp = Multipart::from_request(req, &())
            .await
            .map_err(|r| ApiError::from_status(r.status(), r.body_text()))?;
        let (mut yaml, mut image) = (None, None);
        while let Some(field) = mp
            .next_field()
            .await
            .map_err(|e| ApiError::from_status(e.status(), e.body_text()))?
        {
            let name = field.name().unwrap_or("").to_owned();
            let data = field
                .bytes()
                .await
                .map_err(|e| ApiError::from_status(e.status(), e.body_text()))?;
            match name.as_str() {
                "yaml" => {
                    yaml =
                        Some(String::from_utf8(data.to_vec()).map_err(|_| ApiError::bad_request("yaml is not UTF-8"))?)
                }
                "image" => image = Some(data.to_vec()),
                other => return Err(ApiError::bad_request(format!("unexpected multipart part {other:?}"))),
            }
        }
        MapSource::Ros {
            yaml: yaml.ok_or_else(|| ApiError::bad_request("multipart part \"yaml\" is missing"))?,
            image: image.ok_or_else(|| ApiError::bad_request("multipart part \"image\" is missing"))?,
        }
    } else {
        return Err(ApiError::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "unsupported_media_type",
            "send multipart/form-data (yaml, image) or application/json",
        ));
    };
    store_site(
        &state,
        SiteRecord {
            site,
            source,
            updated_ms: state.clock.now_ms(),
        },
        "map parser",
    )
    .await
}

/// Parses an uploaded site off the async workers (decoding a large image or rasterising a field takes a while),
/// hands it to the engine, which replaces the site's map and stores it, and answers 201 with its summary.
/// `parser` names the parsing step in the 500 that answers a parser that stopped.
pub(super) async fn store_site(
    state: &AppState,
    record: SiteRecord,
    parser: &str,
) -> Result<(StatusCode, ApiJson<SiteSummary>), ApiError> {
    let loaded = tokio::task::spawn_blocking(move || LoadedSite::parse(record))
        .await
        .map_err(|_| {
            ApiError::new(
                StatusCode::INTERNAL_SERVER_ERROR,
                "internal",
                format!("{parser} stopped"),
            )
        })??;
    let reply = state.engine.call(Event::MapUploaded { site: loaded }).await?;
    let summary = reply
        .sites
        .into_iter()
        .next()
        .ok_or_else(|| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", "no site summary"))?;
    Ok((StatusCode::CREATED, ApiJson(summary)))
}

/// A site's map summary.
#[utoipa::path(get, path = "/v1/sites/{site}", tag = "sites",
    params(("site" = String, Path, description = "site name")),
    responses((status = 200, body = SiteSummary), (status = 404, body = ErrorBody)))]
pub async fn get_site(
    State(state): State<AppState>,
    Path(site): Path<String>,
) -> Result<ApiJson<SiteSummary>, ApiError> {
    let mut summary = state
        .views
        .site(&site)
        .ok_or_else(|| ApiError::not_found(format!("unknown site {site:?}")))?;
    state.live.annotate(&mut summary, state.clock.now_ms());
    Ok(ApiJson(summary))
}
