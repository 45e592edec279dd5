//! A study's participants, from its one link: join (a pseudonymous id and a link of one's own),
//! see where one is, consent, start the next condition's session, answer the survey after it.
//! Every route names the study link and the participant's token, and refuses a token of
//! another study's participant. A step is derived from what is stored
//! ([`crate::study::progress`]), so reloading the page, or opening one's link on another day,
//! continues where the participant was.

use std::collections::BTreeMap;

use axum::Json;
use axum::extract::{Path, State};
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};

use super::json_body::JsonBody;
use super::sessions::trainer_url;
use super::study_runs::{spec_of, step_of};
use crate::api::AppState;
use crate::api::error::{ApiError, ApiResult, ErrorBody};
use crate::hub::random_hex;
use crate::store::{ParticipantRow, Status, StudyRow, StudySessionRow, SurveyOutcome};
use crate::study::StudySpec;
use crate::study::progress::Step;
use crate::study::spec::Question;

/// A participant's view of their study.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct ParticipantView {
    pub participant_id: String,
    /// The participant's own link, to come back to.
    pub url: String,
    pub title: String,
    pub consent: String,
    pub survey: Vec<Question>,
    /// The conditions in this participant's order (their names, which the survey names).
    pub ordering: Vec<String>,
    /// What the participant's page shows for each of them: the conditions' labels ("Method A",
    /// ... unless the study gives its own), never the method's name.
    pub labels: Vec<String>,
    pub step: Step,
    /// The session to train in now (step `training`): its trainer page, status, and how many
    /// sessions wait for a slot before it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub training: Option<Training>,
}

#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct Training {
    pub trainer_url: String,
    pub status: Status,
    /// Queued sessions launched before this one (0 once it runs).
    pub queued_ahead: usize,
}

/// The survey after a condition: every question of the study, by id, on its scale.
#[derive(Debug, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SurveyAnswers {
    /// The condition the answers are about (the one just trained).
    pub condition: String,
    pub answers: BTreeMap<String, i64>,
}

/// The participant page of a study link.
fn participant_url(link: &str, token: &str) -> String {
    format!("/study/{link}?participant={token}")
}

async fn study_by_link(state: &AppState, link: &str) -> ApiResult<(StudyRow, StudySpec)> {
    let row = state
        .store
        .study_by_link(link)
        .await?
        .ok_or_else(|| ApiError::NotFound("no study has this link".into()))?;
    let spec = spec_of(&row)?;
    Ok((row, spec))
}

/// The study and the participant, or an error that says which did not match.
async fn participant(
    state: &AppState,
    link: &str,
    token: &str,
) -> ApiResult<(StudyRow, StudySpec, ParticipantRow)> {
    let (study, spec) = study_by_link(state, link).await?;
    let p = state
        .store
        .participant_by_token(token)
        .await?
        .ok_or_else(|| ApiError::NotFound("no participant has this token".into()))?;
    if p.study_id != study.id {
        return Err(ApiError::Forbidden(
            "this participant belongs to another study: open the link you were given".into(),
        ));
    }
    Ok((study, spec, p))
}

async fn view(
    state: &AppState,
    link: &str,
    spec: &StudySpec,
    p: &ParticipantRow,
) -> ApiResult<ParticipantView> {
    let sessions = state.store.participant_sessions(&p.id).await?;
    let step = step_of(state, p, &sessions).await?;
    let training = match &step {
        Step::Training { session_id, .. } => Some(training(state, session_id).await?),
        _ => None,
    };
    Ok(ParticipantView {
        participant_id: p.id.clone(),
        url: participant_url(link, &p.token),
        title: spec.title.clone(),
        consent: spec.consent.clone(),
        survey: spec.survey.clone(),
        ordering: p.ordering.clone(),
        labels: p.ordering.iter().map(|name| spec.label_of(name)).collect(),
        step,
        training,
    })
}

async fn training(state: &AppState, session_id: &str) -> ApiResult<Training> {
    let row = super::trainers::session_row(state, session_id).await?;
    let status = state.hub.status_of(&row);
    // A count in the database, not a read of every session: the page asks every second or two.
    let queued_ahead = if status == Status::Queued {
        usize::try_from(state.store.queued_before(&row).await?).unwrap_or(0)
    } else {
        0
    };
    Ok(Training {
        trainer_url: trainer_url(&row),
        status,
        queued_ahead,
    })
}

/// `POST /api/study-links/{link}/participants`: a person opened the study link: a new
/// pseudonymous participant, ordered by the study's ordering, with a link of their own.
#[utoipa::path(
    post,
    path = "/api/study-links/{link}/participants",
    tag = "studies",
    security(()),
    params(("link" = String, Path, description = "The study link's token")),
    responses((status = 201, description = "Joined: the participant's view, with their own `url`", body = ParticipantView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn join(
    State(state): State<AppState>,
    Path(link): Path<String>,
) -> ApiResult<(StatusCode, Json<ParticipantView>)> {
    let (study, spec) = study_by_link(&state, &link).await?;
    let design = spec.design();
    let id = format!("P{}", random_hex(4));
    let token = random_hex(16);
    let p = state
        .store
        .add_participant(&study.id, &id, &token, |number| {
            design
                .order_for(number)
                .into_iter()
                .map(String::from)
                .collect()
        })
        .await?;
    Ok((
        StatusCode::CREATED,
        Json(view(&state, &link, &spec, &p).await?),
    ))
}

/// `GET /api/study-links/{link}/participants/{token}`: where the participant is.
#[utoipa::path(
    get,
    path = "/api/study-links/{link}/participants/{token}",
    tag = "studies",
    security(()),
    params(("link" = String, Path, description = "The study link's token"), ("token" = String, Path, description = "The participant's token")),
    responses((status = 200, description = "The participant's view", body = ParticipantView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn get(
    State(state): State<AppState>,
    Path((link, token)): Path<(String, String)>,
) -> ApiResult<Json<ParticipantView>> {
    let (_, spec, p) = participant(&state, &link, &token).await?;
    Ok(Json(view(&state, &link, &spec, &p).await?))
}

/// `POST .../participants/{token}/consent`: the participant agrees to the consent text.
#[utoipa::path(
    post,
    path = "/api/study-links/{link}/participants/{token}/consent",
    tag = "studies",
    security(()),
    params(("link" = String, Path, description = "The study link's token"), ("token" = String, Path, description = "The participant's token")),
    responses((status = 200, description = "The participant's view", body = ParticipantView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn consent(
    State(state): State<AppState>,
    Path((link, token)): Path<(String, String)>,
) -> ApiResult<Json<ParticipantView>> {
    let (_, spec, p) = participant(&state, &link, &token).await?;
    state.store.consent(&p.id).await?;
    let p = state
        .store
        .participant_by_token(&token)
        .await?
        .ok_or_else(|| ApiError::NotFound("no participant has this token".into()))?;
    Ok(Json(view(&state, &link, &spec, &p).await?))
}

/// `POST .../participants/{token}/start`: launch the session of the participant's next
/// condition (a human session of the condition's task, method and settings, the study's budget
/// and the participant's seed). It waits as `queued` while the server's slots are full. Asked
/// twice, the second call returns the session the first launched.
#[utoipa::path(
    post,
    path = "/api/study-links/{link}/participants/{token}/start",
    tag = "studies",
    security(()),
    params(("link" = String, Path, description = "The study link's token"), ("token" = String, Path, description = "The participant's token")),
    responses((status = 200, description = "The participant's view, step `training`", body = ParticipantView), (status = "default", description = "An error (409: not at a condition's start)", body = ErrorBody))
)]
pub async fn start(
    State(state): State<AppState>,
    Path((link, token)): Path<(String, String)>,
) -> ApiResult<Json<ParticipantView>> {
    let (_, spec, p) = participant(&state, &link, &token).await?;
    // One launch at a time in this process; across servers the position's unique row decides.
    let _one_at_a_time = state.study_launches.lock().await;
    let sessions = state.store.participant_sessions(&p.id).await?;
    match step_of(&state, &p, &sessions).await? {
        Step::Ready { position } => {
            let condition = &p.ordering[position];
            let index = spec
                .conditions
                .iter()
                .position(|c| &c.name == condition)
                .ok_or_else(|| {
                    ApiError::Conflict(format!("condition {condition:?} is no longer in the study"))
                })?;
            let session = spec
                .session_spec(index, p.number as usize)
                .map_err(|e| ApiError::InvalidSession(e.to_string()))?;
            let row = state.hub.launch(session).await?;
            let linked = state
                .store
                .link_study_session(&StudySessionRow {
                    participant_id: p.id.clone(),
                    position: position as i64,
                    condition: condition.clone(),
                    session_id: row.id.clone(),
                })
                .await?;
            if !linked {
                // Another server (several share one PostgreSQL; the lock above is this
                // process's only) launched this position first: its session is the one.
                state.hub.stop(&row.id).await?;
            }
        }
        Step::Training { .. } => {}
        Step::Consent => {
            return Err(ApiError::Conflict(
                "consent comes first: POST .../consent".into(),
            ));
        }
        Step::Survey { .. } => {
            return Err(ApiError::Conflict(
                "the survey about the last condition comes before the next one".into(),
            ));
        }
        Step::Done => {
            return Err(ApiError::Conflict(
                "every condition of the study is done".into(),
            ));
        }
    }
    Ok(Json(view(&state, &link, &spec, &p).await?))
}

/// `POST .../participants/{token}/survey`: the answers about the condition just trained, every
/// question of the study on its scale; stored in one transaction, once.
#[utoipa::path(
    post,
    path = "/api/study-links/{link}/participants/{token}/survey",
    tag = "studies",
    security(()),
    params(("link" = String, Path, description = "The study link's token"), ("token" = String, Path, description = "The participant's token")),
    request_body = SurveyAnswers,
    responses((status = 200, description = "The participant's view, at the next step", body = ParticipantView), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn survey(
    State(state): State<AppState>,
    Path((link, token)): Path<(String, String)>,
    JsonBody(body): JsonBody<SurveyAnswers>,
) -> ApiResult<Json<ParticipantView>> {
    let (_, spec, p) = participant(&state, &link, &token).await?;
    if spec.condition(&body.condition).is_none() {
        let names: Vec<&str> = spec.conditions.iter().map(|c| c.name.as_str()).collect();
        return Err(ApiError::BadRequest(format!(
            "condition: {:?} is not a condition of this study ({})",
            body.condition,
            names.join(", ")
        )));
    }
    let answers = check_answers(&spec.survey, &body.answers)?;
    let sessions = state.store.participant_sessions(&p.id).await?;
    let position = match step_of(&state, &p, &sessions).await? {
        Step::Survey { position, .. } if p.ordering[position] == body.condition => position,
        Step::Survey { position, .. } => {
            return Err(ApiError::Conflict(format!(
                "the open survey is about {:?}, not {:?}",
                p.ordering[position], body.condition
            )));
        }
        _ => {
            return Err(ApiError::Conflict(format!(
                "no survey is open: {:?} is not the condition just trained",
                body.condition
            )));
        }
    };
    match state
        .store
        .save_study_survey(&p.id, position as i64, &answers)
        .await?
    {
        SurveyOutcome::Stored => {}
        SurveyOutcome::AlreadyAnswered => {
            return Err(ApiError::Conflict(format!(
                "the survey about {:?} was answered before",
                body.condition
            )));
        }
    }
    Ok(Json(view(&state, &link, &spec, &p).await?))
}

/// Every question answered, on its scale, and nothing else.
fn check_answers(
    questions: &[Question],
    answers: &BTreeMap<String, i64>,
) -> ApiResult<Vec<(String, i64)>> {
    for id in answers.keys() {
        if !questions.iter().any(|q| &q.id == id) {
            return Err(ApiError::BadRequest(format!(
                "answers.{id}: not a question of this study"
            )));
        }
    }
    questions
        .iter()
        .map(|q| match answers.get(&q.id) {
            None => Err(ApiError::BadRequest(format!(
                "answers.{}: missing (every question needs an answer)",
                q.id
            ))),
            Some(&v) if !(1..=i64::from(q.points)).contains(&v) => Err(ApiError::BadRequest(
                format!("answers.{}: must be 1 to {}, got {v}", q.id, q.points),
            )),
            Some(&v) => Ok((q.id.clone(), v)),
        })
        .collect()
}
