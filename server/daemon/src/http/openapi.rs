//! `GET /openapi.json`, generated from the handlers' annotations and the wire types, and `GET /docs`, a small
//! self-contained page that lists the routes from that document (no external assets).

use axum::Json;
use axum::response::Html;
use utoipa::OpenApi;

/// The API description.
#[derive(OpenApi)]
#[openapi(
    info(title = "SHIFT API", description = "Coverage plans for robot fleets (DESIGN §5.3)."),
    paths(
        super::sites::upload_map,
        super::sites::get_site,
        super::field::upload_field,
        super::terrain::upload_terrain,
        super::listings::list_sites,
        super::listings::get_site_map,
        super::listings::list_plans,
        super::plans::create_plan,
        super::plans::get_plan,
        super::plans::get_path,
        super::plans::get_speed_profile,
        super::plans::get_corrections,
        super::plans::cancel_plan,
        super::live::get_live,
        super::site_events::site_events,
        super::robots::assign_plan,
        super::robots::list_robots,
        super::robots::get_robot,
        super::events::plan_events,
        super::missions::create_mission,
        super::missions::get_mission,
        super::missions::assign_mission,
        super::missions::cancel_mission,
        super::missions::replan_mission,
        super::missions::join_mission,
        super::missions::mission_events,
        super::missions::get_site_coverage,
        super::ops::healthz,
        super::ops::readyz,
        super::ops::metrics_text,
    ),
    tags((name = "plans"), (name = "missions"), (name = "sites"), (name = "robots"), (name = "ops"))
)]
pub struct ApiDoc;

/// The OpenAPI document.
pub async fn openapi_json() -> Json<utoipa::openapi::OpenApi> {
    Json(ApiDoc::openapi())
}

/// A small docs page.
pub async fn docs_page() -> Html<&'static str> {
    Html(include_str!("docs.html"))
}
