//! Who may call what, as extractors: [`Researcher`] for the researcher routes
//! (`Authorization: Bearer <token>`); [`SessionAccess`] for a session's own routes (its websocket,
//! joining with a name, the survey), which take the session's shared trainer token (from the
//! `trainer_url`), a named trainer's own token (from their invitation or their join), or the
//! researcher's, as a bearer token or as `?token=`, and say who the caller is. Comparisons of
//! the session's and the researcher's tokens take constant time so they cannot be guessed byte
//! by byte; a named trainer's token is looked up in the database by its value.

use axum::extract::{FromRequestParts, Path, Query};
use axum::http::header::AUTHORIZATION;
use axum::http::request::Parts;
use serde::Deserialize;

use super::AppState;
use super::error::ApiError;
use crate::hub::Identity;
use crate::store::SessionRow;

/// Equal in time independent of where the first difference is.
pub fn same_token(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

/// The bearer token of a request, if it has one.
fn bearer(parts: &Parts) -> Option<&str> {
    parts
        .headers
        .get(AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::trim)
}

/// The caller holds the researcher token.
#[derive(Clone, Copy, Debug)]
pub struct Researcher;

impl FromRequestParts<AppState> for Researcher {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, ApiError> {
        match bearer(parts) {
            Some(token) if same_token(token, &state.token) => Ok(Researcher),
            Some(_) => Err(ApiError::Unauthorized(
                "the bearer token is not the researcher token".into(),
            )),
            None => Err(ApiError::Unauthorized(
                "researcher routes need `Authorization: Bearer <token>`".into(),
            )),
        }
    }
}

#[derive(Debug, Deserialize)]
struct TokenQuery {
    token: Option<String>,
}

/// The caller holds a token of the session named in the path (its shared trainer token, a named
/// trainer's own, or the researcher token); the session's row and who the caller is come with
/// it.
#[derive(Clone, Debug)]
pub struct SessionAccess(pub SessionRow, pub Identity);

impl FromRequestParts<AppState> for SessionAccess {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, state: &AppState) -> Result<Self, ApiError> {
        let id = match Path::<String>::from_request_parts(parts, state).await {
            Ok(Path(id)) => id,
            Err(e) => return Err(ApiError::BadRequest(e.body_text())),
        };
        let row = state
            .store
            .session(&id)
            .await?
            .ok_or_else(|| ApiError::NotFound(format!("no session {id}")))?;
        let query = Query::<TokenQuery>::try_from_uri(&parts.uri)
            .ok()
            .and_then(|q| q.0.token);
        let Some(token) = bearer(parts).map(str::to_owned).or(query) else {
            return Err(ApiError::Unauthorized(
                "send the session's trainer token as `Authorization: Bearer <token>` or `?token=<token>`"
                    .into(),
            ));
        };
        if same_token(&token, &state.token) {
            return Ok(SessionAccess(row, Identity::Researcher));
        }
        if same_token(&token, &row.trainer_token) {
            return Ok(SessionAccess(row, Identity::Anonymous));
        }
        match state.store.trainer_by_token(&token).await? {
            Some(t) if t.session_id == row.id => {
                Ok(SessionAccess(row, Identity::Trainer(t.as_ref())))
            }
            _ => Err(ApiError::Forbidden(format!(
                "this token is not valid for session {id}"
            ))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::same_token;

    #[test]
    fn tokens_compare_exactly() {
        assert!(same_token("abc", "abc"));
        assert!(!same_token("abc", "abd"));
        assert!(!same_token("abc", "abcd"));
        assert!(!same_token("", "a"));
    }
}
