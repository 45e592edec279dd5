//! The `trainers`, `trainer_answers` and `trainer_surveys` tables: named trainers of a session,
//! each trainer's own answers in sessions that combine several per query, and each named
//! trainer's survey. Answers without a trainer (stored before names existed, or given on the
//! shared link without one) belong to the anonymous trainer.

use serde::Serialize;

use super::backend::StoreRow;
use super::queries::{parse_value, value_json};
use super::{Result, Store, Survey, clock};
use crate::session::AnswerValue;

/// How a trainer came to the session.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum TrainerOrigin {
    /// A researcher invited them: a link of their own.
    Invited,
    /// They gave their name on the session's shared link.
    Joined,
}

impl TrainerOrigin {
    pub fn as_str(self) -> &'static str {
        match self {
            TrainerOrigin::Invited => "invited",
            TrainerOrigin::Joined => "joined",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        [TrainerOrigin::Invited, TrainerOrigin::Joined]
            .into_iter()
            .find(|o| o.as_str() == s)
    }
}

/// A named trainer, as answers and the API name them.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, serde::Deserialize)]
pub struct TrainerRef {
    pub id: i64,
    pub name: String,
}

/// One row of `trainers`.
#[derive(Clone, Debug, Serialize)]
pub struct TrainerRow {
    pub id: i64,
    pub session_id: String,
    pub name: String,
    #[serde(skip)]
    pub token: String,
    pub origin: TrainerOrigin,
    pub created_at: String,
}

impl TrainerRow {
    pub fn as_ref(&self) -> TrainerRef {
        TrainerRef {
            id: self.id,
            name: self.name.clone(),
        }
    }

    fn from_row(r: &impl StoreRow) -> Self {
        Self {
            id: r.get("id"),
            session_id: r.get("session_id"),
            name: r.get("name"),
            token: r.get("token"),
            origin: r.get("origin"),
            created_at: r.get("created_at"),
        }
    }
}

/// What adding a trainer did.
#[derive(Clone, Debug)]
pub enum AddTrainer {
    Added(TrainerRow),
    /// The session has a trainer of that name already.
    NameTaken,
}

/// What committing a trainer's own answer did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoteOutcome {
    Committed,
    /// This trainer answered the query before (this value or another).
    AlreadyAnswered(AnswerValue),
}

/// One answer a person gave: a `first` session's answer with its trainer (or none: the
/// anonymous trainer), or one trainer's own answer in a session that combines several.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PersonAnswer {
    /// The session's query number.
    pub query_id: i64,
    pub trainer_id: Option<i64>,
    pub value: AnswerValue,
    pub latency_ms: i64,
    /// Seconds since the epoch (for spans; the API shows the text times of the answers).
    pub asked_s: f64,
    pub answered_s: f64,
}

/// Why a trainer's name is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    #[error("a trainer's name has 1 to 40 characters")]
    Length,
    #[error("a trainer's name cannot hold control characters")]
    ControlCharacter,
}

/// A trainer's name: what a person types, trimmed; 1 to 40 characters, no control characters.
pub fn check_name(name: &str) -> std::result::Result<String, NameError> {
    let name = name.trim();
    if name.is_empty() || name.chars().count() > 40 {
        return Err(NameError::Length);
    }
    if name.chars().any(char::is_control) {
        return Err(NameError::ControlCharacter);
    }
    Ok(name.to_string())
}

impl Store {
    /// Add a named trainer with their own token (refused if the session has the name).
    pub async fn add_trainer(
        &self,
        session_id: &str,
        name: &str,
        token: &str,
        origin: TrainerOrigin,
    ) -> Result<AddTrainer> {
        let now = clock::now();
        let row = on_db!(self.db, writer, |pool| sqlx::query(
            "INSERT INTO trainers (session_id, name, token, origin, created_at)
             VALUES ($1, $2, $3, $4, $5) ON CONFLICT (session_id, name) DO NOTHING RETURNING *",
        )
        .bind(session_id)
        .bind(name)
        .bind(token)
        .bind(origin)
        .bind(&now)
        .fetch_optional(pool)
        .await?
        .as_ref()
        .map(TrainerRow::from_row));
        Ok(match row {
            Some(r) => AddTrainer::Added(r),
            None => AddTrainer::NameTaken,
        })
    }

    /// The trainer whose own token this is, if any.
    pub async fn trainer_by_token(&self, token: &str) -> Result<Option<TrainerRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM trainers WHERE token = $1"
        )
        .bind(token)
        .fetch_optional(pool)
        .await?
        .as_ref()
        .map(TrainerRow::from_row)))
    }

    /// A session's named trainers in the order they came.
    pub async fn trainers(&self, session_id: &str) -> Result<Vec<TrainerRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM trainers WHERE session_id = $1 ORDER BY id"
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(TrainerRow::from_row)
        .collect()))
    }

    /// Store one trainer's own answer to a query that takes several; returns after the commit.
    pub async fn commit_vote(
        &self,
        query_id: i64,
        session_id: &str,
        trainer_id: i64,
        value: AnswerValue,
        latency_ms: u64,
    ) -> Result<VoteOutcome> {
        let now = clock::now();
        let stored: Option<String> = on_db!(self.db, writer, |pool| {
            let inserted: Option<i64> = sqlx::query_scalar(
                "INSERT INTO trainer_answers (query_id, session_id, trainer_id, value, latency_ms, answered_at)
                 VALUES ($1, $2, $3, $4, $5, $6)
                 ON CONFLICT (query_id, trainer_id) DO NOTHING RETURNING query_id",
            )
            .bind(query_id)
            .bind(session_id)
            .bind(trainer_id)
            .bind(value_json(value))
            .bind(latency_ms as i64)
            .bind(&now)
            .fetch_optional(pool)
            .await?;
            match inserted {
                Some(_) => None,
                None => Some(
                    sqlx::query_scalar(
                        "SELECT value FROM trainer_answers WHERE query_id = $1 AND trainer_id = $2",
                    )
                    .bind(query_id)
                    .bind(trainer_id)
                    .fetch_one(pool)
                    .await?,
                ),
            }
        });
        Ok(match stored {
            None => VoteOutcome::Committed,
            Some(v) => VoteOutcome::AlreadyAnswered(parse_value(&v)),
        })
    }

    /// The trainers' own answers to one query so far, in the order given (a query asked again
    /// after a restart keeps them).
    pub async fn query_votes(&self, query_id: i64) -> Result<Vec<(TrainerRef, AnswerValue)>> {
        on_db!(self.db, reader, |pool| {
            Ok(sqlx::query(
                "SELECT t.id, t.name, v.value
                 FROM trainer_answers v JOIN trainers t ON t.id = v.trainer_id
                 WHERE v.query_id = $1 ORDER BY v.rowid",
            )
            .bind(query_id)
            .fetch_all(pool)
            .await?
            .iter()
            .map(|r| {
                let who = TrainerRef {
                    id: r.get("id"),
                    name: r.get("name"),
                };
                (who, parse_value(&r.get::<String>("value")))
            })
            .collect())
        })
    }

    /// Every answer a person gave in a session, in the order asked: the answers of a `first`
    /// session (anonymous ones with no trainer) and each trainer's own answers of a session
    /// that combines several.
    pub async fn person_answers(&self, session_id: &str) -> Result<Vec<PersonAnswer>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT q.seq, x.trainer_id, x.value, x.latency_ms, q.asked_at, x.answered_at
             FROM (SELECT query_id, trainer_id, value, latency_ms, answered_at, 0 AS kind
                   FROM answers WHERE session_id = $1 AND who = 'trainer'
                   UNION ALL
                   SELECT query_id, trainer_id, value, latency_ms, answered_at, 1 AS kind
                   FROM trainer_answers WHERE session_id = $1) x
             JOIN queries q ON q.id = x.query_id
             ORDER BY q.seq, x.kind, x.answered_at",
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| PersonAnswer {
            query_id: r.get("seq"),
            trainer_id: r.get("trainer_id"),
            value: parse_value(&r.get::<String>("value")),
            latency_ms: r.get("latency_ms"),
            asked_s: clock::seconds(&r.get::<String>("asked_at")).unwrap_or(f64::NAN),
            answered_s: clock::seconds(&r.get::<String>("answered_at")).unwrap_or(f64::NAN),
        })
        .collect()))
    }

    /// Store (or replace) a named trainer's survey.
    pub async fn save_trainer_survey(
        &self,
        trainer_id: i64,
        session_id: &str,
        s: &Survey,
    ) -> Result<()> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "INSERT INTO trainer_surveys
                 (trainer_id, session_id, overall_experience, perceived_intelligence, cognitive_ease, answered_at)
                 VALUES ($1, $2, $3, $4, $5, $6)
                 ON CONFLICT (trainer_id) DO UPDATE SET
                   session_id = excluded.session_id,
                   overall_experience = excluded.overall_experience,
                   perceived_intelligence = excluded.perceived_intelligence,
                   cognitive_ease = excluded.cognitive_ease,
                   answered_at = excluded.answered_at",
            )
            .bind(trainer_id)
            .bind(session_id)
            .bind(i64::from(s.overall_experience))
            .bind(i64::from(s.perceived_intelligence))
            .bind(i64::from(s.cognitive_ease))
            .bind(&now)
            .execute(pool)
            .await?;
        });
        Ok(())
    }

    /// The named trainers' surveys of a session, by trainer.
    pub async fn trainer_surveys(&self, session_id: &str) -> Result<Vec<(i64, Survey)>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM trainer_surveys WHERE session_id = $1"
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| {
            let survey = Survey {
                overall_experience: r.get::<i64>("overall_experience") as u8,
                perceived_intelligence: r.get::<i64>("perceived_intelligence") as u8,
                cognitive_ease: r.get::<i64>("cognitive_ease") as u8,
            };
            (r.get("trainer_id"), survey)
        })
        .collect()))
    }
}
