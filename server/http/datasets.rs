//! A session's datasets over HTTP (researcher routes): `GET .../dataset.parquet` (labelled
//! transitions or preference pairs), `.../posterior.safetensors` (DRPL's samples and mean
//! theta), `.../policy.safetensors` (the learner's actor). See `export`.

use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::trainers::session_row;
use crate::api::AppState;
use crate::api::error::{ApiError, ApiResult, ErrorBody};
use crate::export::session::{Dataset, ExportError, export, file_name};

async fn serve(state: &AppState, id: &str, what: Dataset) -> ApiResult<Response> {
    let row = session_row(state, id).await?;
    let bytes = export(&state.store, &state.data_dir, &row, what)
        .await
        .map_err(|e| match e {
            ExportError::Missing(m) => ApiError::NotFound(m),
            ExportError::Store(e) => ApiError::Store(e),
            e @ (ExportError::Table(_) | ExportError::Policy(_)) => {
                ApiError::ExportFailed(e.to_string())
            }
        })?;
    let content_type = match what {
        Dataset::Table => "application/vnd.apache.parquet",
        _ => "application/octet-stream",
    };
    Ok((
        [
            (header::CONTENT_TYPE, content_type.to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"{}\"", file_name(&row, what)),
            ),
        ],
        bytes,
    )
        .into_response())
}

/// The session's labelled data as Parquet: each answered query's transition (evaluative
/// sessions) or pair (preference sessions).
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/dataset.parquet",
    tag = "datasets",
    params(("id" = String, Path, description = "The session")),
    responses(
        (status = 200, description = "Parquet, one row per answered query: evaluative sessions' query_id, step, abstract_state, observation, action, reward, next_observation, label, who, trainer, latency_ms, trainer_names, trainer_labels; preference sessions' left_/right_ trajectory, start, end, abstract_state, features, raw_features, choice, who, trainer, latency_ms, trainer_names, trainer_choices", content((Vec<u8> = "application/vnd.apache.parquet"))),
        (status = "default", description = "An error", body = ErrorBody)
    )
)]
pub async fn dataset(State(state): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    serve(&state, &id, Dataset::Table).await
}

/// A preference session's posterior at its latest checkpoint.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/posterior.safetensors",
    tag = "datasets",
    params(("id" = String, Path, description = "The session")),
    responses(
        (status = 200, description = "safetensors: `samples` [n, d] and `mean_theta` [d], f64; the feature names in the metadata", content((Vec<u8> = "application/octet-stream"))),
        (status = "default", description = "An error (404 for an evaluative session, or before the first checkpoint)", body = ErrorBody)
    )
)]
pub async fn posterior(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Response> {
    serve(&state, &id, Dataset::Posterior).await
}

/// An evaluative session's policy at its latest checkpoint.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/policy.safetensors",
    tag = "datasets",
    params(("id" = String, Path, description = "The session")),
    responses(
        (status = 200, description = "safetensors: the actor's layers (`actor.layers.<i>.weight`, `.bias`, f32, [out, in]); the learner's config and sizes in the metadata", content((Vec<u8> = "application/octet-stream"))),
        (status = "default", description = "An error (404 for a preference session, or before the first checkpoint)", body = ErrorBody)
    )
)]
pub async fn policy(State(state): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    serve(&state, &id, Dataset::Policy).await
}
