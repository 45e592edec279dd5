//! Every way the API refuses, as one enum mapped to an HTTP status and a stable code, in the
//! shape `{"error": {"code": "...", "message": "..."}}`.

use axum::Json;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::json;
use utoipa::ToSchema;

use crate::hub::HubError;
use crate::store::{NameError, SurveyError};

#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// The request is malformed: bad JSON, an unknown field, a value out of range.
    #[error("{0}")]
    BadRequest(String),
    /// No credentials, or not the kind the route needs.
    #[error("{0}")]
    Unauthorized(String),
    /// Credentials, but not valid for this resource.
    #[error("{0}")]
    Forbidden(String),
    #[error("{0}")]
    NotFound(String),
    /// The resource is not in a state that allows this (stop a finished session, say).
    #[error("{0}")]
    Conflict(String),
    /// A launch request that parses but does not describe a session that can run.
    #[error("{0}")]
    InvalidSession(String),
    #[error("request bodies are limited to {0} bytes")]
    PayloadTooLarge(usize),
    /// The session runs on no server at this moment (PostgreSQL: queued for a free slot, or
    /// its server stopped and another has not taken it over yet): try again shortly.
    #[error("{0}")]
    Moving(String),
    /// The database does not answer (`/healthz`).
    #[error("the database does not answer: {0}")]
    Unhealthy(String),
    /// Writing an export failed.
    #[error("{0}")]
    ExportFailed(String),
    /// A database error: logged in full, reported without detail.
    #[error("the database failed; see the server log")]
    Store(#[source] sqlx::Error),
}

impl ApiError {
    pub fn status(&self) -> StatusCode {
        match self {
            ApiError::BadRequest(_) => StatusCode::BAD_REQUEST,
            ApiError::Unauthorized(_) => StatusCode::UNAUTHORIZED,
            ApiError::Forbidden(_) => StatusCode::FORBIDDEN,
            ApiError::NotFound(_) => StatusCode::NOT_FOUND,
            ApiError::Conflict(_) => StatusCode::CONFLICT,
            ApiError::InvalidSession(_) => StatusCode::UNPROCESSABLE_ENTITY,
            ApiError::PayloadTooLarge(_) => StatusCode::PAYLOAD_TOO_LARGE,
            ApiError::Unhealthy(_) | ApiError::Moving(_) => StatusCode::SERVICE_UNAVAILABLE,
            ApiError::ExportFailed(_) | ApiError::Store(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// The stable code clients match on.
    pub fn code(&self) -> &'static str {
        match self {
            ApiError::BadRequest(_) => "bad_request",
            ApiError::Unauthorized(_) => "unauthorized",
            ApiError::Forbidden(_) => "forbidden",
            ApiError::NotFound(_) => "not_found",
            ApiError::Conflict(_) => "conflict",
            ApiError::InvalidSession(_) => "invalid_session",
            ApiError::PayloadTooLarge(_) => "payload_too_large",
            ApiError::Moving(_) => "moving",
            ApiError::Unhealthy(_) => "unhealthy",
            ApiError::ExportFailed(_) => "export_failed",
            ApiError::Store(_) => "store_failed",
        }
    }

    /// Every code, for the OpenAPI document.
    pub const CODES: [&'static str; 11] = [
        "bad_request",
        "unauthorized",
        "forbidden",
        "not_found",
        "conflict",
        "invalid_session",
        "payload_too_large",
        "moving",
        "unhealthy",
        "export_failed",
        "store_failed",
    ];
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        if let ApiError::Store(e) = &self {
            tracing::error!("database error: {e}");
        }
        let body = json!({"error": {"code": self.code(), "message": self.to_string()}});
        (self.status(), Json(body)).into_response()
    }
}

impl From<sqlx::Error> for ApiError {
    fn from(e: sqlx::Error) -> Self {
        ApiError::Store(e)
    }
}

/// A trainer's name that does not check is a malformed request.
impl From<NameError> for ApiError {
    fn from(e: NameError) -> Self {
        ApiError::BadRequest(e.to_string())
    }
}

/// A survey answer off its scale is a malformed request.
impl From<SurveyError> for ApiError {
    fn from(e: SurveyError) -> Self {
        ApiError::BadRequest(e.to_string())
    }
}

impl From<HubError> for ApiError {
    fn from(e: HubError) -> Self {
        match e {
            HubError::NotFound(id) => ApiError::NotFound(format!("no session {id}")),
            HubError::Conflict(m) => ApiError::Conflict(m),
            HubError::Invalid(e) => ApiError::InvalidSession(e.to_string()),
            HubError::StoredSpec(e) => ApiError::InvalidSession(e.to_string()),
            HubError::Store(e) => e.into(),
        }
    }
}

pub type ApiResult<T> = Result<T, ApiError>;

/// Every refusal: `{"error": {"code": "...", "message": "..."}}`.
#[derive(ToSchema)]
#[allow(dead_code)] // documentation only: `ApiError` writes this shape
pub struct ErrorBody {
    error: ErrorDetail,
}

#[derive(ToSchema)]
#[allow(dead_code)]
pub struct ErrorDetail {
    /// A stable code clients match on: bad_request, unauthorized, forbidden, not_found,
    /// conflict, invalid_session, payload_too_large, moving, unhealthy, export_failed,
    /// store_failed.
    #[schema(example = "invalid_session")]
    code: String,
    message: String,
}

#[cfg(test)]
mod tests {
    use super::ApiError;

    #[test]
    fn every_variant_has_a_listed_code_and_an_error_status() {
        let all = [
            ApiError::BadRequest(String::new()),
            ApiError::Unauthorized(String::new()),
            ApiError::Forbidden(String::new()),
            ApiError::NotFound(String::new()),
            ApiError::Conflict(String::new()),
            ApiError::InvalidSession(String::new()),
            ApiError::PayloadTooLarge(1),
            ApiError::Moving(String::new()),
            ApiError::Unhealthy(String::new()),
            ApiError::ExportFailed(String::new()),
            ApiError::Store(sqlx::Error::PoolClosed),
        ];
        assert_eq!(all.len(), ApiError::CODES.len());
        for (e, code) in all.iter().zip(ApiError::CODES) {
            assert_eq!(e.code(), code);
            assert!(e.status().is_client_error() || e.status().is_server_error());
        }
    }
}
