//! Trainers as people: `/api/sessions/{id}/trainers` (a researcher invites a named trainer, who
//! gets a link of their own; the list breaks the session down per trainer), `.../join` (a
//! trainer on the session's shared link gives their name and gets their own token), and
//! `.../agreement` (how much the trainers agree).

use axum::Json;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};

use super::json_body::JsonBody;
use super::trainer_views::{AgreementView, TrainerStats, agreement, personal_url, trainer_stats};
use crate::api::AppState;
use crate::api::auth::SessionAccess;
use crate::api::error::{ApiError, ApiResult, ErrorBody};
use crate::hub::{Identity, random_hex};
use crate::session::QueryKind;
use crate::store::{AddTrainer, SessionRow, TrainerOrigin, TrainerRow, check_name};

/// `POST .../trainers` and `POST .../join`.
#[derive(Debug, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct NameRequest {
    pub name: String,
}

/// A named trainer and their own link (the token in it is theirs alone).
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct TrainerLink {
    pub id: i64,
    pub name: String,
    pub origin: TrainerOrigin,
    pub token: String,
    pub trainer_url: String,
}

impl TrainerLink {
    fn of(t: &TrainerRow) -> Self {
        Self {
            id: t.id,
            name: t.name.clone(),
            origin: t.origin,
            token: t.token.clone(),
            trainer_url: personal_url(&t.session_id, &t.token),
        }
    }
}

/// The session's row, or 404.
pub async fn session_row(state: &AppState, id: &str) -> ApiResult<SessionRow> {
    state
        .store
        .session(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no session {id}")))
}

fn name_of(JsonBody(request): JsonBody<NameRequest>) -> ApiResult<String> {
    Ok(check_name(&request.name)?)
}

async fn add(
    state: &AppState,
    session_id: &str,
    name: &str,
    origin: TrainerOrigin,
) -> ApiResult<TrainerRow> {
    let token = random_hex(16);
    match state
        .store
        .add_trainer(session_id, name, &token, origin)
        .await?
    {
        AddTrainer::Added(t) => Ok(t),
        AddTrainer::NameTaken => Err(ApiError::Conflict(format!(
            "session {session_id} has a trainer named {name:?} already; choose another name"
        ))),
    }
}

/// `POST /api/sessions/{id}/trainers` (researcher): invite a named trainer.
#[utoipa::path(
    post,
    path = "/api/sessions/{id}/trainers",
    tag = "trainers",
    params(("id" = String, Path, description = "The session")),
    request_body = NameRequest,
    responses(
        (status = 201, description = "The trainer and their own link", body = TrainerLink),
        (status = "default", description = "An error (409: the name is taken)", body = ErrorBody)
    )
)]
pub async fn invite(
    State(state): State<AppState>,
    Path(id): Path<String>,
    body: JsonBody<NameRequest>,
) -> ApiResult<(StatusCode, Json<TrainerLink>)> {
    let name = name_of(body)?;
    session_row(&state, &id).await?;
    let t = add(&state, &id, &name, TrainerOrigin::Invited).await?;
    Ok((StatusCode::CREATED, Json(TrainerLink::of(&t))))
}

/// `POST /api/sessions/{id}/join` (the session's shared trainer token): a trainer names
/// themself and gets a token of their own. A named trainer's own token gets their record back.
#[utoipa::path(
    post,
    path = "/api/sessions/{id}/join",
    tag = "trainers",
    params(("id" = String, Path, description = "The session")),
    security(("bearer" = [])),
    request_body = NameRequest,
    responses(
        (status = 201, description = "Joined: the trainer and their own link (bearer: the session's trainer token)", body = TrainerLink),
        (status = "default", description = "An error (409: the name is taken)", body = ErrorBody)
    )
)]
pub async fn join(
    State(state): State<AppState>,
    SessionAccess(row, who): SessionAccess,
    body: JsonBody<NameRequest>,
) -> ApiResult<(StatusCode, Json<TrainerLink>)> {
    let name = name_of(body)?;
    if let Identity::Trainer(t) = who {
        let mine = state
            .store
            .trainers(&row.id)
            .await?
            .into_iter()
            .find(|x| x.id == t.id)
            .ok_or_else(|| ApiError::NotFound(format!("no trainer {}", t.id)))?;
        return Ok((StatusCode::OK, Json(TrainerLink::of(&mine))));
    }
    let t = add(&state, &row.id, &name, TrainerOrigin::Joined).await?;
    Ok((StatusCode::CREATED, Json(TrainerLink::of(&t))))
}

/// `GET /api/sessions/{id}/trainers` (researcher): the session per trainer: answers, time (T),
/// no-feedback count (NFC), latency and survey.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/trainers",
    tag = "trainers",
    params(("id" = String, Path, description = "The session")),
    responses(
        (status = 200, description = "Every named trainer, then the anonymous one if it answered", body = Vec<TrainerStats>),
        (status = "default", description = "An error", body = ErrorBody)
    )
)]
pub async fn list(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<Vec<TrainerStats>>> {
    session_row(&state, &id).await?;
    Ok(Json(breakdown(&state, &id).await?))
}

/// The per-trainer breakdown of a session (the export's `trainer` records too).
pub async fn breakdown(state: &AppState, id: &str) -> ApiResult<Vec<TrainerStats>> {
    let trainers = state.store.trainers(id).await?;
    let answers = state.store.person_answers(id).await?;
    let surveys = state.store.trainer_surveys(id).await?;
    let anonymous = state.store.survey(id).await?;
    Ok(trainer_stats(id, &trainers, &answers, &surveys, anonymous))
}

/// `GET /api/sessions/{id}/agreement` (researcher): Krippendorff's alpha (evaluative) or
/// Fleiss' kappa (preference) over the named trainers' answers, per session and per pair.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/agreement",
    tag = "trainers",
    params(("id" = String, Path, description = "The session")),
    responses(
        (status = 200, description = "How much the named trainers agree", body = AgreementView),
        (status = "default", description = "An error", body = ErrorBody)
    )
)]
pub async fn agreement_of(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<AgreementView>> {
    let row = session_row(&state, &id).await?;
    Ok(Json(session_agreement(&state, &row).await?))
}

/// The agreement of a session's trainers (the export's `agreement` record too).
pub async fn session_agreement(state: &AppState, row: &SessionRow) -> ApiResult<AgreementView> {
    let kind = row
        .spec()
        .map_or(QueryKind::Evaluative, |s| s.method.query_kind());
    let trainers = state.store.trainers(&row.id).await?;
    let answers = state.store.person_answers(&row.id).await?;
    Ok(agreement(kind, &trainers, &answers))
}
