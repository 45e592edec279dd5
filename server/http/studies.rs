//! Studies for researchers: create one (its conditions checked as session launches, so a
//! study never fails on a participant's third condition), list them, see who is where, and the
//! results (`GET /api/studies/{id}/results`, and the tidy table as CSV or Parquet).
//! Participants' own routes are in [`super::participants`].

use axum::Json;
use axum::extract::{Path, Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};

use super::json_body::JsonBody;
use super::study_runs::{participant_runs, step_of, study_row};
use crate::api::AppState;
use crate::api::error::{ApiError, ApiResult, ErrorBody};
use crate::export::study_table;
use crate::hub::random_hex;
use crate::session::plan::SessionPlan;
use crate::study::progress::Step;
use crate::study::results::{StudyResults, summarise};
use crate::study::{StudySpec, spec::Condition};

/// A study as the list shows it.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct StudyView {
    pub id: String,
    pub title: String,
    /// The one link for every participant, relative to the server.
    pub link: String,
    pub participants: usize,
    pub created_at: String,
}

/// A participant as the researcher sees them: pseudonymous id, order and where they are.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct ParticipantSummary {
    pub id: String,
    pub number: i64,
    pub ordering: Vec<String>,
    pub consented: bool,
    pub step: Step,
    /// The sessions launched so far, by position.
    pub sessions: Vec<String>,
}

/// A study with its design and participants.
#[derive(Debug, Serialize, utoipa::ToSchema)]
pub struct StudyDetail {
    #[serde(flatten)]
    pub study: StudyView,
    #[schema(value_type = Object)]
    pub spec: StudySpec,
    pub participants_detail: Vec<ParticipantSummary>,
}

/// The link a participant opens first.
pub fn study_link(link_token: &str) -> String {
    format!("/study/{link_token}")
}

/// Every condition as participant 0's session would be launched: a study whose condition could
/// not run is refused now, naming the condition.
fn check_conditions(spec: &StudySpec) -> ApiResult<()> {
    for (index, Condition { name, .. }) in spec.conditions.iter().enumerate() {
        let session = spec
            .session_spec(index, 0)
            .map_err(|e| ApiError::InvalidSession(e.to_string()))?;
        SessionPlan::new(session)
            .map_err(|e| ApiError::InvalidSession(format!("conditions[{index}] ({name}): {e}")))?;
    }
    Ok(())
}

/// `POST /api/studies`: create a study; its link is for every participant.
#[utoipa::path(
    post,
    path = "/api/studies",
    tag = "studies",
    request_body(content = Object, description = "A StudySpec: title, conditions [{name, task, method, params}], ordering (williams | random | fixed), seed, budget {steps | queries}, survey [{id, text, points, low, high}], consent, main_contrast"),
    responses((status = 201, description = "Created", body = StudyView), (status = "default", description = "An error (422: a condition that cannot run)", body = ErrorBody))
)]
pub async fn create(
    State(state): State<AppState>,
    JsonBody(spec): JsonBody<StudySpec>,
) -> ApiResult<(StatusCode, Json<StudyView>)> {
    spec.validate()
        .map_err(|e| ApiError::InvalidSession(e.to_string()))?;
    check_conditions(&spec)?;
    let id = random_hex(6);
    let link = random_hex(12);
    let json = serde_json::to_value(&spec).expect("a study spec serialises");
    let row = state
        .store
        .insert_study(&id, &spec.title, &json, &link)
        .await?;
    Ok((
        StatusCode::CREATED,
        Json(StudyView {
            id: row.id,
            title: row.title,
            link: study_link(&row.link_token),
            participants: 0,
            created_at: row.created_at,
        }),
    ))
}

/// `GET /api/studies`: every study, newest first.
#[utoipa::path(
    get,
    path = "/api/studies",
    tag = "studies",
    responses((status = 200, description = "Studies", body = Vec<StudyView>), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn list(State(state): State<AppState>) -> ApiResult<Json<Vec<StudyView>>> {
    let mut out = Vec::new();
    for row in state.store.studies().await? {
        let participants = state.store.participants(&row.id).await?.len();
        out.push(StudyView {
            link: study_link(&row.link_token),
            id: row.id,
            title: row.title,
            participants,
            created_at: row.created_at,
        });
    }
    Ok(Json(out))
}

/// `GET /api/studies/{id}`: the design and every participant's place in it.
#[utoipa::path(
    get,
    path = "/api/studies/{id}",
    tag = "studies",
    params(("id" = String, Path, description = "The study")),
    responses((status = 200, description = "The study", body = StudyDetail), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn get(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<StudyDetail>> {
    let (row, spec) = study_row(&state.store, &id).await?;
    let mut detail = Vec::new();
    for p in state.store.participants(&row.id).await? {
        let sessions = state.store.participant_sessions(&p.id).await?;
        let step = step_of(&state, &p, &sessions).await?;
        detail.push(ParticipantSummary {
            consented: p.consented_at.is_some(),
            sessions: sessions.into_iter().map(|s| s.session_id).collect(),
            id: p.id,
            number: p.number,
            ordering: p.ordering,
            step,
        });
    }
    Ok(Json(StudyDetail {
        study: StudyView {
            id: row.id,
            title: row.title,
            link: study_link(&row.link_token),
            participants: detail.len(),
            created_at: row.created_at,
        },
        spec,
        participants_detail: detail,
    }))
}

/// `GET /api/studies/{id}/results`: per condition the cumulative reward curve, feedback %, T,
/// NFC and survey (means ± s.e. over participants, medians and distributions), and the
/// within-subject tests of each measure.
#[utoipa::path(
    get,
    path = "/api/studies/{id}/results",
    tag = "studies",
    params(("id" = String, Path, description = "The study")),
    responses((status = 200, description = "The results", body = Object), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn results(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> ApiResult<Json<StudyResults>> {
    let (row, spec) = study_row(&state.store, &id).await?;
    let participants = state.store.participants(&row.id).await?.len();
    let runs = participant_runs(&state.store, &row.id).await?;
    Ok(Json(summarise(&spec, participants, &runs)))
}

#[derive(Debug, Deserialize, utoipa::IntoParams)]
pub struct TableQuery {
    /// `csv` (the default) or `parquet`.
    pub format: Option<String>,
}

/// `GET /api/studies/{id}/table?format=csv|parquet`: a row per participant × condition (for R
/// or pandas): ids, position, session, status, ended early, cumulative reward, feedback %, T,
/// NFC and each survey answer.
#[utoipa::path(
    get,
    path = "/api/studies/{id}/table",
    tag = "studies",
    params(("id" = String, Path, description = "The study"), TableQuery),
    responses((status = 200, description = "The tidy table"), (status = "default", description = "An error", body = ErrorBody))
)]
pub async fn table(
    State(state): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<TableQuery>,
) -> ApiResult<Response> {
    let (row, spec) = study_row(&state.store, &id).await?;
    let runs = participant_runs(&state.store, &row.id).await?;
    let (bytes, content_type, ext) = match q.format.as_deref().unwrap_or("csv") {
        "csv" => (
            study_table::csv(&spec, &runs).into_bytes(),
            "text/csv",
            "csv",
        ),
        "parquet" => (
            study_table::parquet(&spec, &runs)
                .map_err(|e| ApiError::ExportFailed(e.to_string()))?,
            "application/vnd.apache.parquet",
            "parquet",
        ),
        other => {
            return Err(ApiError::BadRequest(format!(
                "format: {other:?} is not csv or parquet"
            )));
        }
    };
    let disposition = format!("attachment; filename=\"study-{}.{ext}\"", row.id);
    Ok((
        [
            (header::CONTENT_TYPE, content_type.to_string()),
            (header::CONTENT_DISPOSITION, disposition),
        ],
        bytes,
    )
        .into_response())
}
