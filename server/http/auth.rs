//! Who may call what: researcher routes need `Authorization: Bearer <token>`; a trainer's
//! websocket needs its session's own token (from the `trainer_url`). Comparisons take constant
//! time so a token cannot be guessed byte by byte.

use axum::extract::{Request, State};
use axum::http::header::AUTHORIZATION;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::AppState;
use super::error::ApiError;

/// Equal in time independent of where the first difference is.
pub fn same_token(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

/// Middleware for researcher routes.
pub async fn require_researcher(
    State(state): State<AppState>,
    request: Request,
    next: Next,
) -> Response {
    let given = request
        .headers()
        .get(AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "));
    match given {
        Some(token) if same_token(token.trim(), &state.token) => next.run(request).await,
        Some(_) => {
            ApiError::unauthorized("the bearer token is not the researcher token").into_response()
        }
        None => ApiError::unauthorized("researcher routes need `Authorization: Bearer <token>`")
            .into_response(),
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
