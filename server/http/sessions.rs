//! `/api/sessions`: launch, list, inspect, stop, resume; episodes, answers, export.

use axum::Json;
use axum::extract::{Path, Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};

use super::json_body::JsonBody;
use crate::api::AppState;
use crate::api::auth::SessionAccess;
use crate::api::error::{ApiError, ApiResult, ErrorBody};
use crate::export::answers_csv::answers_csv;
use crate::export::session_jsonl::{SessionRecords, session_jsonl};
use crate::remote_env::RemoteTarget;
use crate::session::spec::{DEFAULT_QUERIES, default_steps};
use crate::session::{SessionMethod, SessionSpec, TrainerKind};
use crate::settings::Settings;
use crate::sim::Task;
use crate::store::{AlignmentRow, AnswerCounts, AnswerRow, EpisodeRow, SessionRow, Status, Survey};

/// What to train, how, with whom, and for how long.
#[derive(Debug, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct LaunchRequest {
    /// A built-in task; with `env`, the task that env stands in for (its scene graph,
    /// features and expert). Give a task, an env, or both.
    #[serde(default)]
    pub task: Option<Task>,
    /// An environment in another process (`{"url": "tcp://HOST:PORT"}`, see
    /// `docs/env-protocol.md`) instead of our simulator.
    #[serde(default)]
    pub env: Option<RemoteTarget>,
    /// dref, ef-<percent> (ef-100, ef-50, ef-6.2, ...), sac, drpl, drpl-mi, drpl-ss, fragment or full.
    #[schema(value_type = String, example = "dref")]
    pub method: SessionMethod,
    pub trainer: TrainerKind,
    #[serde(default)]
    pub seed: u64,
    /// Environment steps (evaluative methods) [default: the paper's for the task].
    pub steps: Option<u64>,
    /// Queries (preference methods) [default: 40].
    pub queries: Option<u64>,
    /// Session settings and hyper-parameters by name (`GET /api/tasks` lists them with their
    /// defaults). A setting that is unknown, of the wrong type or out of range makes an invalid
    /// session (422).
    // Read into `Settings` by `into_spec`, so that a bad setting is a 422, not a malformed body.
    #[serde(default)]
    #[schema(value_type = Option<Settings>)]
    pub params: serde_json::Value,
}

/// A launched session.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct Launched {
    pub id: String,
    pub status: Status,
    /// The trainer's link (path and per-session token), relative to the server.
    pub trainer_url: String,
}

impl LaunchRequest {
    pub fn into_spec(self) -> Result<SessionSpec, ApiError> {
        let params = match self.params {
            serde_json::Value::Null => Settings::default(),
            params => Settings::from_json(params)
                .map_err(|e| ApiError::InvalidSession(format!("params: {e}")))?,
        };
        let budget = if self.method.is_preference() {
            if self.steps.is_some() {
                return Err(ApiError::BadRequest(format!(
                    "{} asks queries: give `queries`, not `steps`",
                    self.method
                )));
            }
            self.queries.unwrap_or(DEFAULT_QUERIES as u64)
        } else {
            if self.queries.is_some() {
                return Err(ApiError::BadRequest(format!(
                    "{} takes environment steps: give `steps`, not `queries`",
                    self.method
                )));
            }
            self.steps.unwrap_or_else(|| default_steps(self.task))
        };
        Ok(SessionSpec {
            task: self.task,
            env: self.env,
            method: self.method,
            trainer: self.trainer,
            seed: self.seed,
            budget,
            params,
        })
    }
}

/// A session as the API shows it.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct SessionView {
    pub id: String,
    /// The task (`remote`: a remote env's own task).
    pub task: String,
    /// The remote env the session steps, if not our simulator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env: Option<RemoteTarget>,
    pub method: String,
    pub trainer: String,
    pub seed: i64,
    pub budget: i64,
    /// `steps` or `queries`.
    pub unit: &'static str,
    pub status: Status,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    pub progress: i64,
    /// The settings it was launched with.
    #[schema(value_type = Settings)]
    pub params: serde_json::Value,
    pub answers: AnswerCounts,
    /// The latest metrics: answered, feedback fraction, recent returns, alignment.
    #[schema(value_type = Object)]
    pub latest: serde_json::Value,
    pub trainer_url: String,
    pub created_at: String,
    pub started_at: Option<String>,
    pub ended_at: Option<String>,
    /// The trainer's total time in seconds: first query asked to last answer (the paper's T).
    pub trainer_seconds: Option<f64>,
    /// The trainer's answers to the three questions after a human session.
    pub survey: Option<Survey>,
}

pub fn trainer_url(row: &SessionRow) -> String {
    format!("/train/{}?token={}", row.id, row.trainer_token)
}

async fn view(state: &AppState, row: SessionRow) -> ApiResult<SessionView> {
    let snapshot = state.hub.session(&row.id).map(|s| s.snapshot());
    let status = snapshot.as_ref().map_or(row.status, |s| s.status);
    let (progress, latest) = match snapshot {
        Some(s) if status.is_active() => (
            s.progress.progress as i64,
            serde_json::to_value(s.progress).unwrap_or_default(),
        ),
        _ => (row.progress, row.latest.clone()),
    };
    let answers = state.store.answer_counts(&row.id).await?;
    let trainer_seconds = state.store.trainer_seconds(&row.id).await?;
    let survey = state.store.survey(&row.id).await?;
    Ok(SessionView {
        unit: row.spec().map_or("steps", |s| s.method.budget_unit()),
        trainer_url: trainer_url(&row),
        params: row.config.get("params").cloned().unwrap_or_default(),
        env: row
            .config
            .get("env")
            .and_then(|env| serde_json::from_value(env.clone()).ok()),
        id: row.id,
        task: row.task,
        method: row.method,
        trainer: row.trainer,
        seed: row.seed,
        budget: row.budget,
        status,
        reason: if status.is_active() { None } else { row.reason },
        progress,
        answers,
        latest,
        created_at: row.created_at,
        started_at: row.started_at,
        ended_at: row.ended_at,
        trainer_seconds,
        survey,
    })
}

async fn row(state: &AppState, id: &str) -> ApiResult<SessionRow> {
    state
        .store
        .session(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no session {id}")))
}

/// Launch a session: it queues, then runs on its own thread when a slot is free.
#[utoipa::path(
    post,
    path = "/api/sessions",
    tag = "sessions",
    request_body = LaunchRequest,
    responses(
        (status = 201, description = "Queued", body = Launched),
        (status = "default", description = "An error", body = ErrorBody)
    )
)]
pub async fn create(
    State(state): State<AppState>,
    JsonBody(request): JsonBody<LaunchRequest>,
) -> ApiResult<(StatusCode, Json<Launched>)> {
    let spec = request.into_spec()?;
    let row = state.hub.launch(spec).await?;
    let status = state.hub.status_of(&row);
    Ok((
        StatusCode::CREATED,
        Json(Launched {
            trainer_url: trainer_url(&row),
            id: row.id,
            status,
        }),
    ))
}

/// Every session, newest first.
#[utoipa::path(
    get,
    path = "/api/sessions",
    tag = "sessions",
    responses((status = 200, description = "Sessions", body = Vec<SessionView>), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn list(State(state): State<AppState>) -> ApiResult<Json<Vec<SessionView>>> {
    let mut out = Vec::new();
    for r in state.store.sessions().await? {
        out.push(view(&state, r).await?);
    }
    Ok(Json(out))
}

/// A session: status, progress, answer counts, latest metrics.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}",
    tag = "sessions",
    params(("id" = String, Path, description = "The session")),
    responses((status = 200, description = "The session", body = SessionView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn get(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<SessionView>> {
    let r = row(&state, &id).await?;
    Ok(Json(view(&state, r).await?))
}

/// Stop a queued or running session.
#[utoipa::path(
    post,
    path = "/api/sessions/{id}/stop",
    tag = "sessions",
    params(("id" = String, Path, description = "The session")),
    responses((status = 200, description = "The session", body = SessionView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn stop(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<SessionView>> {
    state.hub.stop(&id).await?;
    let r = row(&state, &id).await?;
    Ok(Json(view(&state, r).await?))
}

/// Resume an interrupted, stopped or failed session; stored answers are replayed, never
/// asked again.
#[utoipa::path(
    post,
    path = "/api/sessions/{id}/resume",
    tag = "sessions",
    params(("id" = String, Path, description = "The session")),
    responses((status = 200, description = "The session", body = SessionView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn resume(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<SessionView>> {
    let r = state.hub.resume(&id).await?;
    Ok(Json(view(&state, r).await?))
}

/// The session's finished episodes.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/episodes",
    tag = "sessions",
    params(("id" = String, Path, description = "The session")),
    responses((status = 200, description = "Episodes", body = Vec<EpisodeRow>), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn episodes(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Response> {
    row(&state, &id).await?;
    Ok(Json(state.store.episodes(&id).await?).into_response())
}

/// Answered queries in the order asked.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/answers",
    tag = "sessions",
    params(("id" = String, Path, description = "The session")),
    responses((status = 200, description = "Answers", body = Vec<AnswerRow>), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn answers(State(state): State<AppState>, Path(id): Path<String>) -> ApiResult<Response> {
    row(&state, &id).await?;
    Ok(Json(state.store.answers(&id).await?).into_response())
}

/// `GET .../alignment`: a preference session's posterior alignment after every answer (and
/// after every undo), oldest first (empty for evaluative sessions).
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/alignment",
    tag = "sessions",
    params(("id" = String, Path, description = "The session")),
    responses((status = 200, description = "Alignment by query", body = Vec<AlignmentRow>), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn alignment(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Response> {
    row(&state, &id).await?;
    Ok(Json(state.store.alignment(&id).await?).into_response())
}

#[derive(Debug, Deserialize, utoipa::IntoParams)]
pub struct ExportQuery {
    /// `jsonl` (default) or `csv`.
    pub format: Option<String>,
}

/// `GET .../export?format=jsonl|csv`: JSONL holds the session, then every answer and episode,
/// each trainer's summary and own answers, and the trainers' agreement, one record per line
/// (`"record"` names it); CSV holds the answers, with the trainer who gave each.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/export",
    tag = "sessions",
    params(("id" = String, Path, description = "The session"), ExportQuery),
    responses(
        (status = 200, description = "JSONL: the session, then every answer and episode, each trainer's summary (`trainer`) and own answers (`trainer_answer`), and their agreement (`agreement`), one record per line (`record` names it); CSV: the answers, with the trainer who gave each", content(
            (String = "application/x-ndjson"),
            (String = "text/csv")
        )),
        (status = "default", description = "An error", body = ErrorBody)
    )
)]
pub async fn export(
    State(state): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<ExportQuery>,
) -> ApiResult<Response> {
    let r = row(&state, &id).await?;
    let answers = state.store.answers(&id).await?;
    let format = q.format.as_deref().unwrap_or("jsonl");
    let (body, content_type, ext) = match format {
        "jsonl" => {
            let session = view(&state, r).await?;
            let episodes = state.store.episodes(&id).await?;
            let trainers = super::trainers::breakdown(&state, &id).await?;
            let trainer_answers = state.store.person_answers(&id).await?;
            let row = super::trainers::session_row(&state, &id).await?;
            let agreement = super::trainers::session_agreement(&state, &row).await?;
            let records = SessionRecords {
                session: &session,
                answers: &answers,
                episodes: &episodes,
                trainers: &trainers,
                trainer_answers: &trainer_answers,
                agreement: &agreement,
            };
            (session_jsonl(&records), "application/x-ndjson", "jsonl")
        }
        "csv" => {
            let text = answers_csv(&answers).map_err(|e| ApiError::ExportFailed(e.to_string()))?;
            (text, "text/csv", "csv")
        }
        other => {
            return Err(ApiError::BadRequest(format!(
                "format {other:?}: expected jsonl or csv"
            )));
        }
    };
    Ok((
        [
            (header::CONTENT_TYPE, content_type.to_string()),
            (
                header::CONTENT_DISPOSITION,
                format!("attachment; filename=\"dualrep-{id}.{ext}\""),
            ),
        ],
        body,
    )
        .into_response())
}

/// `POST /api/sessions/{id}/survey`: the trainer (the session's shared token, or a named
/// trainer's own, who then answers for themself) or a researcher stores the answers to the
/// three questions, once the session has ended.
#[utoipa::path(
    post,
    path = "/api/sessions/{id}/survey",
    tag = "trainers",
    params(("id" = String, Path, description = "The session")),
    security(("bearer" = [])),
    request_body = Survey,
    responses((status = 200, description = "The session, with `survey` (bearer: the session's trainer token, a named trainer's own token, or the researcher token; a named trainer's answers are theirs, `GET .../trainers`)", body = SessionView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn survey(
    State(state): State<AppState>,
    SessionAccess(r, who): SessionAccess,
    JsonBody(survey): JsonBody<Survey>,
) -> ApiResult<Json<SessionView>> {
    let id = r.id.clone();
    survey.validate()?;
    if state.hub.status_of(&r).is_active() {
        return Err(ApiError::Conflict(
            "the questions come after the session has ended".into(),
        ));
    }
    match who.trainer_id() {
        Some(trainer) => {
            state
                .store
                .save_trainer_survey(trainer, &id, &survey)
                .await?
        }
        None => state.store.save_survey(&id, &survey).await?,
    }
    Ok(Json(view(&state, r).await?))
}

/// `GET .../episodes/{n}/frames`: an episode of a human session as `{geometry, frames}`, for
/// replay in the review page.
#[utoipa::path(
    get,
    path = "/api/sessions/{id}/episodes/{episode}/frames",
    tag = "sessions",
    params(("id" = String, Path, description = "The session"), ("episode" = u64, Path, description = "The episode, from 0")),
    responses((status = 200, description = "`{geometry, frames}`", body = Object), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn episode_frames(
    State(state): State<AppState>,
    Path((id, episode)): Path<(String, u64)>,
) -> ApiResult<Response> {
    row(&state, &id).await?;
    let path = state.hub.frames_path(&id, episode);
    let bytes = tokio::fs::read(&path).await.map_err(|_| {
        ApiError::NotFound(format!(
            "no frames of episode {episode} of session {id} (frames are kept for the episodes of human sessions)"
        ))
    })?;
    Ok(([(header::CONTENT_TYPE, "application/json")], bytes).into_response())
}
