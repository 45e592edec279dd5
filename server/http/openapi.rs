//! `GET /api/openapi.json`: the REST API as OpenAPI 3.1, generated from the handlers' own
//! `#[utoipa::path]` annotations and their request and response types as the router registers
//! them (`http::api_routes`), so the document cannot drift from the routes.

use std::sync::Arc;

use axum::{Extension, Json};
use utoipa::openapi::security::{Http, HttpAuthScheme, SecurityScheme};
use utoipa::{Modify, OpenApi};

use crate::api::error::{ErrorBody, ErrorDetail};

/// The document's frame: title, version, the bearer scheme, and the schemas every route
/// shares. Paths are added by the router.
#[derive(OpenApi)]
#[openapi(
    info(
        title = "dualrep",
        description = "Train robot policies in simulation with people's guidance (DREF and DRPL)."
    ),
    security(("bearer" = [])),
    modifiers(&BearerScheme),
    components(schemas(ErrorBody, ErrorDetail)),
    tags(
        (name = "sessions", description = "Launch, watch, stop and resume training sessions; their answers, episodes and recordings"),
        (name = "trainers", description = "Trainers as people: what a trainer's link reaches (the websocket, joining by name, the survey), named trainers, the session per trainer and their agreement"),
        (name = "datasets", description = "A session's data for other tools: Parquet tables, the posterior and the policy as safetensors"),
        (name = "studies", description = "Human-subject studies: conditions in a counterbalanced order per participant from one link, surveys, results and within-subject tests"),
        (name = "service", description = "Self-description and health")
    )
)]
pub struct ApiDoc;

struct BearerScheme;

impl Modify for BearerScheme {
    fn modify(&self, openapi: &mut utoipa::openapi::OpenApi) {
        let mut scheme = Http::new(HttpAuthScheme::Bearer);
        scheme.description =
            Some("The researcher token (--token, DUALREP_TOKEN, or <data-dir>/token)".into());
        openapi
            .components
            .get_or_insert_with(Default::default)
            .add_security_scheme("bearer", SecurityScheme::Http(scheme));
    }
}

/// The generated document, as served.
pub fn document() -> serde_json::Value {
    serde_json::to_value(super::api_routes().into_openapi()).expect("the document serialises")
}

/// This document.
#[utoipa::path(
    get,
    path = "/api/openapi.json",
    tag = "service",
    security(()),
    responses((status = 200, description = "OpenAPI 3.1", body = Object))
)]
pub async fn openapi(Extension(doc): Extension<Arc<serde_json::Value>>) -> Json<serde_json::Value> {
    Json((*doc).clone())
}
