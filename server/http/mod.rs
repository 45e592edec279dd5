//! The HTTP edge: REST routes under `/api`, the trainer websocket under `/ws`, the web UI's
//! files, `/healthz`. Researcher routes sit behind the bearer token; bodies are capped; CORS is
//! closed unless origins are configured.
//!
//! - `sessions`: launch, list, inspect, stop, resume, episodes, answers, export.
//! - `trainers`: named trainers (invite, join by name), the per-trainer breakdown, agreement;
//!   `trainer_views` builds those views.
//! - `datasets`: a session's Parquet table, posterior and policy files.
//! - `studies`: human-subject studies for researchers (create, list, who is where, results,
//!   the tidy table); `participants`: a study's participants from its one link (join, consent,
//!   start each condition, survey); `study_runs` reads both from the store.
//! - `tasks`, `openapi`: self-description.
//! - `json_body`: request bodies whose errors name the field that was wrong (who may call, the
//!   JSON error shape and the state handlers reach are in [`crate::api`], shared with `ws`).
//! - `security_headers`: the CSP, referrer and MIME-sniffing headers on every response.

pub mod datasets;
pub mod json_body;
pub mod openapi;
pub mod participants;
pub mod security_headers;
pub mod sessions;
pub mod studies;
pub mod study_runs;
pub mod tasks;
pub mod trainer_views;
pub mod trainers;

use std::sync::Arc;

use axum::extract::{Path, State};
use axum::http::{Method, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{any, get};
use axum::{Extension, Json, Router, middleware};
use tower_http::cors::CorsLayer;
use tower_http::limit::RequestBodyLimitLayer;
use tower_http::services::{ServeDir, ServeFile};
use tower_http::trace::TraceLayer;
use utoipa::OpenApi;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use crate::api::AppState;
use crate::api::auth;
use crate::api::error::{ApiError, ApiResult, ErrorBody};

/// Largest request body the API takes (launch requests are a few hundred bytes).
pub const MAX_BODY_BYTES: usize = 64 * 1024;

/// Every documented route, before the state is supplied: the researcher routes (behind the
/// bearer token in [`app`]) and the public ones. The OpenAPI document is generated from these.
pub(crate) fn api_routes() -> OpenApiRouter<AppState> {
    OpenApiRouter::with_openapi(openapi::ApiDoc::openapi())
        .merge(researcher_routes())
        .merge(public_routes())
}

fn researcher_routes() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(sessions::create, sessions::list))
        .routes(routes!(sessions::get))
        .routes(routes!(sessions::stop))
        .routes(routes!(sessions::resume))
        .routes(routes!(sessions::episodes))
        .routes(routes!(sessions::episode_frames))
        .routes(routes!(sessions::answers))
        .routes(routes!(sessions::alignment))
        .routes(routes!(sessions::export))
        .routes(routes!(recording))
        .routes(routes!(trainers::invite, trainers::list))
        .routes(routes!(trainers::agreement_of))
        .routes(routes!(datasets::dataset))
        .routes(routes!(datasets::posterior))
        .routes(routes!(datasets::policy))
        .routes(routes!(studies::create, studies::list))
        .routes(routes!(studies::get))
        .routes(routes!(studies::results))
        .routes(routes!(studies::table))
}

fn public_routes() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(sessions::survey))
        .routes(routes!(trainers::join))
        .routes(routes!(participants::join))
        .routes(routes!(participants::get))
        .routes(routes!(participants::consent))
        .routes(routes!(participants::start))
        .routes(routes!(participants::survey))
        .routes(routes!(tasks::tasks))
        .routes(routes!(openapi::openapi))
        .routes(routes!(healthz))
        .routes(routes!(crate::ws::socket::upgrade))
}

pub fn app(state: AppState) -> Router {
    let researcher = researcher_routes()
        .route_layer(middleware::from_extractor_with_state::<auth::Researcher, _>(state.clone()));
    let (router, doc) = OpenApiRouter::with_openapi(openapi::ApiDoc::openapi())
        .merge(researcher)
        .merge(public_routes())
        .split_for_parts();
    let doc = Arc::new(serde_json::to_value(doc).expect("the OpenAPI document serialises"));
    let mut router = router
        .route("/api/{*rest}", any(api_not_found))
        .layer(Extension(doc));
    router = match &state.web_dir {
        Some(web) => router
            .route_service("/train/{id}", ServeFile::new(web.join("train.html")))
            .route_service("/review/{id}", ServeFile::new(web.join("review.html")))
            .route_service(
                "/study/{link}",
                ServeFile::new(web.join("participate.html")),
            )
            .fallback_service(ServeDir::new(web)),
        None => router
            .route("/train/{id}", get(|| shipped_page("train.html")))
            .route("/review/{id}", get(|| shipped_page("review.html")))
            .route("/study/{link}", get(|| shipped_page("participate.html")))
            .fallback(shipped_file),
    };
    let mut router = router
        .layer(RequestBodyLimitLayer::new(MAX_BODY_BYTES))
        .layer(TraceLayer::new_for_http());
    if !state.cors_origins.is_empty() {
        router = router.layer(
            CorsLayer::new()
                .allow_origin(state.cors_origins.clone())
                .allow_methods([Method::GET, Method::POST])
                .allow_headers([header::AUTHORIZATION, header::CONTENT_TYPE]),
        );
    }
    // Outermost, so that CORS preflights and body-limit refusals carry them too.
    security_headers::add(router).with_state(state)
}

/// A page of the web UI inside the binary.
async fn shipped_page(name: &'static str) -> Response {
    serve_shipped(name)
}

/// Any other path: a file of the web UI inside the binary (`/` is `index.html`).
async fn shipped_file(uri: axum::http::Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    serve_shipped(if path.is_empty() { "index.html" } else { path })
}

fn serve_shipped(path: &str) -> Response {
    match crate::shipped::web_file(path) {
        Some((bytes, mime)) => ([(header::CONTENT_TYPE, mime)], bytes).into_response(),
        None => (StatusCode::NOT_FOUND, "not found").into_response(),
    }
}

async fn api_not_found() -> ApiError {
    ApiError::NotFound("no such API route; see /api/openapi.json".into())
}

/// Liveness and a database check.
#[utoipa::path(
    get,
    path = "/healthz",
    tag = "service",
    security(()),
    responses(
        (status = 200, description = "Healthy: `{\"status\": \"ok\", \"server\": \"<id>\"}` (which server answered: one of several behind a proxy, docs/serving-several.md)", body = Object),
        (status = 503, description = "The database does not answer", body = ErrorBody)
    )
)]
async fn healthz(State(state): State<AppState>) -> Response {
    match state.store.ping().await {
        Ok(()) => {
            Json(serde_json::json!({"status": "ok", "server": state.hub.server_id})).into_response()
        }
        Err(e) => ApiError::Unhealthy(e.to_string()).into_response(),
    }
}

/// `<data dir>/recordings/<id>.rrd`, written by the session's recorder.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/recording.rrd",
    tag = "sessions",
    params(("id" = String, Path, description = "The session")),
    responses(
        (status = 200, description = "The session's Rerun recording (open with `rerun <file>`)", content_type = "application/octet-stream", body = Vec<u8>),
        (status = "default", description = "An error", body = ErrorBody)
    )
)]
async fn recording(State(state): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    if state.store.session(&id).await?.is_none() {
        return Err(ApiError::NotFound(format!("no session {id}")));
    }
    let path = state.hub.recording_path(&id);
    let bytes = tokio::fs::read(&path).await.map_err(|_| {
        ApiError::NotFound(format!(
            "session {id} has no recording (recording was off, or it has not started)"
        ))
    })?;
    Ok((
        [
            (header::CONTENT_TYPE, "application/octet-stream".to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{id}.rrd\""),
            ),
        ],
        bytes,
    )
        .into_response())
}
