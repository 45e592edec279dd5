//! The HTTP edge: REST routes under `/api`, the trainer websocket under `/ws`, the web UI's
//! files, `/healthz`. Researcher routes sit behind the bearer token; bodies are capped; CORS is
//! closed unless origins are configured.
//!
//! - `sessions`: launch, list, inspect, stop, resume, episodes, answers, export.
//! - `trainers`: named trainers (invite, join by name), the per-trainer breakdown, agreement;
//!   `trainer_views` builds those views.
//! - `datasets`: a session's Parquet table, posterior and policy files.
//! - `tasks`, `openapi`: self-description.
//! - `auth`, `error`: the bearer check and the JSON error shape.

pub mod auth;
pub mod datasets;
pub mod error;
pub mod openapi;
pub mod sessions;
pub mod tasks;
pub mod trainer_views;
pub mod trainers;

use std::path::PathBuf;
use std::sync::Arc;

use axum::extract::{Path, State};
use axum::http::{HeaderValue, Method, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{any, get, post};
use axum::{Json, Router, middleware};
use tower_http::cors::CorsLayer;
use tower_http::limit::RequestBodyLimitLayer;
use tower_http::services::{ServeDir, ServeFile};
use tower_http::trace::TraceLayer;

use crate::hub::Hub;
use crate::store::Store;
use error::{ApiError, ApiResult};

/// Largest request body the API takes (launch requests are a few hundred bytes).
pub const MAX_BODY_BYTES: usize = 64 * 1024;

/// What every handler can reach.
#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    pub hub: Arc<Hub>,
    /// The researcher token.
    pub token: Arc<str>,
    /// Serve the web UI from this folder; `None` serves the copy inside the binary.
    pub web_dir: Option<PathBuf>,
    pub data_dir: PathBuf,
    /// Origins allowed to call the API from other sites (none by default).
    pub cors_origins: Vec<HeaderValue>,
}

pub fn app(state: AppState) -> Router {
    let researcher = Router::new()
        .route("/api/sessions", post(sessions::create).get(sessions::list))
        .route("/api/sessions/{id}", get(sessions::get))
        .route("/api/sessions/{id}/stop", post(sessions::stop))
        .route("/api/sessions/{id}/resume", post(sessions::resume))
        .route("/api/sessions/{id}/episodes", get(sessions::episodes))
        .route(
            "/api/sessions/{id}/episodes/{episode}/frames",
            get(sessions::episode_frames),
        )
        .route("/api/sessions/{id}/answers", get(sessions::answers))
        .route("/api/sessions/{id}/alignment", get(sessions::alignment))
        .route("/api/sessions/{id}/export", get(sessions::export))
        .route("/api/sessions/{id}/recording.rrd", get(recording))
        .route(
            "/api/sessions/{id}/trainers",
            post(trainers::invite).get(trainers::list),
        )
        .route("/api/sessions/{id}/agreement", get(trainers::agreement_of))
        .route("/api/sessions/{id}/dataset.parquet", get(datasets::dataset))
        .route(
            "/api/sessions/{id}/posterior.safetensors",
            get(datasets::posterior),
        )
        .route(
            "/api/sessions/{id}/policy.safetensors",
            get(datasets::policy),
        )
        .route_layer(middleware::from_extractor_with_state::<auth::Researcher, _>(state.clone()));
    let mut router = Router::new()
        .merge(researcher)
        .route("/api/sessions/{id}/survey", post(sessions::survey))
        .route("/api/sessions/{id}/join", post(trainers::join))
        .route("/api/tasks", get(tasks::tasks))
        .route("/api/openapi.json", get(openapi::openapi))
        .route("/api/{*rest}", any(api_not_found))
        .route("/healthz", get(healthz))
        .route("/ws/sessions/{id}", get(crate::ws::socket::upgrade));
    router = match &state.web_dir {
        Some(web) => router
            .route_service("/train/{id}", ServeFile::new(web.join("train.html")))
            .route_service("/review/{id}", ServeFile::new(web.join("review.html")))
            .fallback_service(ServeDir::new(web)),
        None => router
            .route("/train/{id}", get(|| shipped_page("train.html")))
            .route("/review/{id}", get(|| shipped_page("review.html")))
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
    router.with_state(state)
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

async fn healthz(State(state): State<AppState>) -> Response {
    match state.store.ping().await {
        Ok(()) => Json(serde_json::json!({"status": "ok"})).into_response(),
        Err(e) => ApiError::Unhealthy(e.to_string()).into_response(),
    }
}

/// `<data dir>/recordings/<id>.rrd`, written by the session's recorder.
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
