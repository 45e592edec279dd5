//! The `query_transitions` table, and what a session on a remote env resumes with: its stored
//! evaluative queries, each with the moment it asked about, its answer as first given and the
//! step exactly as the session's run stored it ([`AskedStep`]). A resumed run catches up on the
//! moments it meets again and takes in the answered steps it does not (`session::remote`).
//!
//! The step is stored with its query, before the query reaches anyone, so every answer that is
//! committed (by a trainer, a timeout, several trainers combined or a synthetic trainer) has its
//! step stored. Arrays are f32 as little-endian bytes: the run gets back the very bits it
//! stored, which JSON (`queries.data`, for datasets) does not promise.

use serde::Deserialize;
use sqlx::{Database, Encode, Executor, IntoArguments, Type};

use super::backend::StoreRow;
use super::queries::parse_value;
use super::{Result, Store};
use crate::guidance::evaluative_run::AskedStep;
use crate::scene_graph::AbstractState;
use crate::session::StoredMoment;

fn to_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The f32s of a stored array; an error names the column of a blob that is not whole f32s.
fn from_bytes(bytes: &[u8], column: &str) -> Result<Vec<f32>> {
    if !bytes.len().is_multiple_of(4) {
        return Err(sqlx::Error::Decode(
            format!(
                "query_transitions.{column}: {} bytes are not whole f32s",
                bytes.len()
            )
            .into(),
        ));
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

/// Store the step query `query_id` asked about; a query asked again keeps the step stored
/// first (the same moment). `executor`: a pool or a transaction of either database.
pub(super) async fn insert_asked_step<'c, DB>(
    executor: impl Executor<'c, Database = DB>,
    query_id: i64,
    session_id: &str,
    s: &AskedStep,
) -> Result<()>
where
    DB: Database,
    DB::Arguments: IntoArguments<DB>,
    for<'e> i64: Encode<'e, DB> + Type<DB>,
    for<'e> String: Encode<'e, DB> + Type<DB>,
    for<'e> Vec<u8>: Encode<'e, DB> + Type<DB>,
    for<'e> f64: Encode<'e, DB> + Type<DB>,
    for<'e> bool: Encode<'e, DB> + Type<DB>,
{
    sqlx::query(
        "INSERT INTO query_transitions
             (query_id, session_id, observation, action, reward, next_observation, terminated,
              predicted)
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8) ON CONFLICT (query_id) DO NOTHING",
    )
    .bind(query_id)
    .bind(session_id.to_string())
    .bind(to_bytes(&s.obs))
    .bind(to_bytes(&s.action))
    .bind(f64::from(s.reward))
    .bind(to_bytes(&s.next_obs))
    .bind(s.terminated)
    .bind(f64::from(s.predicted))
    .execute(executor)
    .await?;
    Ok(())
}

/// The action in a query's `data` (JSON text; read here rather than with SQLite's
/// `json_extract`, which PostgreSQL spells otherwise). Numbers parse straight to f32, as they
/// did from `json_extract`'s text.
fn data_action(data: &str) -> Option<Vec<f32>> {
    #[derive(Deserialize)]
    struct Data {
        action: Option<Vec<f32>>,
    }
    serde_json::from_str::<Data>(data).ok()?.action
}

impl Store {
    /// Store the step query `query_id` (a row of `queries`) asked about.
    pub async fn store_asked_step(
        &self,
        query_id: i64,
        session_id: &str,
        step: &AskedStep,
    ) -> Result<()> {
        on_db!(self.db, writer, |pool| insert_asked_step(
            pool, query_id, session_id, step
        )
        .await)
    }

    /// A session's evaluative queries in query order, each with the step and action it asked
    /// about, its answer as first given (like `replay_answers`), if it has one, and its step as
    /// the run stored it, if it was kept: a session on a remote env, resumed from a checkpoint,
    /// catches up on those stored after it and takes in the rest.
    pub async fn stored_moments(&self, session_id: &str) -> Result<Vec<StoredMoment>> {
        on_db!(self.db, reader, |pool| sqlx::query(
            "SELECT q.seq, q.step, q.abstract_state, q.data,
                    COALESCE((SELECT r.value FROM answer_revisions r
                              WHERE r.query_id = q.id AND r.revision = 0), a.value) AS value,
                    t.observation, t.action, t.reward, t.next_observation, t.terminated,
                    t.predicted
             FROM queries q LEFT JOIN answers a ON a.query_id = q.id
                            LEFT JOIN query_transitions t ON t.query_id = q.id
             WHERE q.session_id = $1 AND q.kind = 'evaluative' ORDER BY q.seq",
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(stored_moment)
        .collect())
    }
}

/// One row of `stored_moments`.
fn stored_moment(r: &impl StoreRow) -> Result<StoredMoment> {
    let asked = match r.get::<Option<Vec<u8>>>("observation") {
        None => None,
        Some(obs) => Some(AskedStep {
            obs: from_bytes(&obs, "observation")?,
            action: from_bytes(&r.get::<Vec<u8>>("action"), "action")?,
            reward: r.get::<f64>("reward") as f32,
            next_obs: from_bytes(&r.get::<Vec<u8>>("next_observation"), "next_observation")?,
            terminated: r.get("terminated"),
            abstract_state: AbstractState(r.get::<i64>("abstract_state") as u32),
            predicted: r.get::<f64>("predicted") as f32,
        }),
    };
    // The exact action where the step was kept; else as `queries.data` has it.
    let action = match &asked {
        Some(s) => Some(s.action.clone()),
        None => r
            .get::<Option<String>>("data")
            .and_then(|d| data_action(&d)),
    };
    Ok(StoredMoment {
        seq: r.get::<i64>("seq") as u64,
        step: r.get::<i64>("step") as u64,
        action,
        value: r.get::<Option<String>>("value").map(|v| parse_value(&v)),
        asked,
    })
}
