//! A session's datasets over HTTP (researcher routes): `GET .../dataset.parquet` (labelled
//! transitions or preference pairs), `.../posterior.safetensors` (DRPL's samples and mean
//! theta), `.../policy.safetensors` (the learner's actor). See `export`.

use axum::extract::{Path, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::{ApiError, ApiResult};
use super::trainers::session_row;
use crate::export::session::{Dataset, ExportError, export, file_name};

async fn serve(state: &AppState, id: &str, what: Dataset) -> ApiResult<Response> {
    let row = session_row(state, id).await?;
    let bytes = export(&state.store, &state.data_dir, &row, what)
        .await
        .map_err(|e| match e {
            ExportError::Missing(m) => ApiError::NotFound(m),
            ExportError::Store(e) => ApiError::Store(e),
            ExportError::Failed(m) => ApiError::ExportFailed(m),
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

pub async fn dataset(State(state): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    serve(&state, &id, Dataset::Table).await
}

pub async fn posterior(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Response> {
    serve(&state, &id, Dataset::Posterior).await
}

pub async fn policy(State(state): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    serve(&state, &id, Dataset::Policy).await
}
