//! What the study routes read from the store: a study and its spec, each participant's step
//! (with the live status of their sessions), and every participant × condition as a
//! [`ParticipantRun`] for the results and the tidy table (`dualrep report study` reads the
//! same through [`participant_runs`]).

use std::collections::BTreeMap;

use crate::api::AppState;
use crate::api::error::{ApiError, ApiResult};
use crate::store::{ParticipantRow, Status, Store, StudyRow, StudySessionRow};
use crate::study::StudySpec;
use crate::study::progress::{PositionSession, Step, next_step};
use crate::study::results::ParticipantRun;

/// A study and its spec, or 404.
pub async fn study_row(store: &Store, id: &str) -> ApiResult<(StudyRow, StudySpec)> {
    let row = store
        .study(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no study {id}")))?;
    let spec = spec_of(&row)?;
    Ok((row, spec))
}

/// The stored spec of a study (it was validated when stored).
pub fn spec_of(row: &StudyRow) -> ApiResult<StudySpec> {
    serde_json::from_value(row.spec.clone()).map_err(|e| {
        ApiError::Conflict(format!(
            "study {}: its stored design does not read: {e}",
            row.id
        ))
    })
}

/// Where a participant is, with the hub's live status of their sessions.
pub async fn step_of(
    state: &AppState,
    p: &ParticipantRow,
    sessions: &[StudySessionRow],
) -> ApiResult<Step> {
    let mut placed = Vec::new();
    for s in sessions {
        let status = match state.store.session(&s.session_id).await? {
            Some(row) => state.hub.status_of(&row),
            None => Status::Failed,
        };
        placed.push(PositionSession {
            position: s.position as usize,
            session_id: s.session_id.clone(),
            status,
        });
    }
    let surveyed: Vec<usize> = state
        .store
        .answered_positions(&p.id)
        .await?
        .into_iter()
        .map(|x| x as usize)
        .collect();
    Ok(next_step(
        p.consented_at.is_some(),
        p.ordering.len(),
        &placed,
        &surveyed,
    ))
}

/// Every participant × condition with a session, in participant then position order. Statuses
/// are the stored ones (a live session's progress is its latest stored).
pub async fn participant_runs(
    store: &Store,
    study_id: &str,
) -> Result<Vec<ParticipantRun>, sqlx::Error> {
    let participants = store.participants(study_id).await?;
    let number: BTreeMap<&str, usize> = participants
        .iter()
        .map(|p| (p.id.as_str(), p.number as usize))
        .collect();
    let mut answers: BTreeMap<(String, i64), BTreeMap<String, i64>> = BTreeMap::new();
    for a in store.study_answers(study_id).await? {
        answers
            .entry((a.participant_id, a.position))
            .or_default()
            .insert(a.question, a.value);
    }
    let mut runs = Vec::new();
    for s in store.study_sessions(study_id).await? {
        let Some(session) = store.session(&s.session_id).await? else {
            continue;
        };
        let episodes = store.episodes(&s.session_id).await?;
        let counts = store.answer_counts(&s.session_id).await?;
        let preference = session.spec().is_ok_and(|spec| spec.method.is_preference());
        let feedback_pct = if preference {
            // Pairs answered with a preference per pair asked.
            if counts.total > 0 {
                100.0 * (counts.total - counts.no_feedback) as f64 / counts.total as f64
            } else {
                0.0
            }
        } else if session.progress > 0 {
            // Queries per environment step.
            100.0 * counts.total as f64 / session.progress as f64
        } else {
            0.0
        };
        runs.push(ParticipantRun {
            participant: number.get(s.participant_id.as_str()).copied().unwrap_or(0),
            position: s.position as usize,
            survey: answers
                .remove(&(s.participant_id.clone(), s.position))
                .unwrap_or_default(),
            participant_id: s.participant_id,
            condition: s.condition,
            seconds: store.session_seconds(&s.session_id).await?,
            session_id: s.session_id,
            status: session.status.as_str().to_string(),
            ended_early: !session.status.is_active() && session.status != Status::Finished,
            progress: session.progress,
            cumulative_reward: episodes.last().map_or(0.0, |e| e.cumulative_return),
            feedback_pct,
            no_feedback: counts.no_feedback,
            curve: episodes
                .iter()
                .map(|e| (e.step as f64, e.cumulative_return))
                .collect(),
        });
    }
    Ok(runs)
}
