//! Studies, their participants, the session each participant trains per condition, and their
//! survey answers (`migrations/0006_studies.sql`). What a participant is to do next is derived
//! from these rows by [`crate::study::progress`]; nothing here decides it.

use super::backend::StoreRow;
use super::{Result, Store, clock};

/// One row of `studies`.
#[derive(Clone, Debug)]
pub struct StudyRow {
    pub id: String,
    pub title: String,
    pub spec: serde_json::Value,
    pub link_token: String,
    pub created_at: String,
}

impl StudyRow {
    fn from_row(r: &impl StoreRow) -> Self {
        let spec: String = r.get("spec");
        Self {
            id: r.get("id"),
            title: r.get("title"),
            spec: serde_json::from_str(&spec).unwrap_or(serde_json::Value::Null),
            link_token: r.get("link_token"),
            created_at: r.get("created_at"),
        }
    }
}

/// One row of `participants`.
#[derive(Clone, Debug)]
pub struct ParticipantRow {
    pub id: String,
    pub study_id: String,
    pub number: i64,
    pub token: String,
    /// The condition names in this participant's order.
    pub ordering: Vec<String>,
    pub consented_at: Option<String>,
    pub created_at: String,
}

impl ParticipantRow {
    fn from_row(r: &impl StoreRow) -> Self {
        let ordering: String = r.get("ordering");
        Self {
            id: r.get("id"),
            study_id: r.get("study_id"),
            number: r.get("number"),
            token: r.get("token"),
            ordering: serde_json::from_str(&ordering).unwrap_or_default(),
            consented_at: r.get("consented_at"),
            created_at: r.get("created_at"),
        }
    }
}

/// A participant's session in one condition.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StudySessionRow {
    pub participant_id: String,
    pub position: i64,
    pub condition: String,
    pub session_id: String,
}

/// One survey answer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StudyAnswerRow {
    pub participant_id: String,
    pub position: i64,
    pub question: String,
    pub value: i64,
}

/// What storing a survey did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurveyOutcome {
    Stored,
    /// The survey after that position was answered before; nothing changed.
    AlreadyAnswered,
}

impl Store {
    /// Store a study (its spec validated by the caller).
    pub async fn insert_study(
        &self,
        id: &str,
        title: &str,
        spec: &serde_json::Value,
        link_token: &str,
    ) -> Result<StudyRow> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| Ok(StudyRow::from_row(
            &sqlx::query(
                "INSERT INTO studies (id, title, spec, link_token, created_at)
                 VALUES ($1, $2, $3, $4, $5) RETURNING *",
            )
            .bind(id)
            .bind(title)
            .bind(spec.to_string())
            .bind(link_token)
            .bind(&now)
            .fetch_one(pool)
            .await?
        )))
    }

    pub async fn study(&self, id: &str) -> Result<Option<StudyRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM studies WHERE id = $1"
        )
        .bind(id)
        .fetch_optional(pool)
        .await?
        .as_ref()
        .map(StudyRow::from_row)))
    }

    pub async fn study_by_link(&self, link_token: &str) -> Result<Option<StudyRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM studies WHERE link_token = $1"
        )
        .bind(link_token)
        .fetch_optional(pool)
        .await?
        .as_ref()
        .map(StudyRow::from_row)))
    }

    /// Every study, newest first.
    pub async fn studies(&self) -> Result<Vec<StudyRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM studies ORDER BY created_at DESC, id"
        )
        .fetch_all(pool)
        .await?
        .iter()
        .map(StudyRow::from_row)
        .collect()))
    }

    /// A new participant with the next number of the study; `ordering` is computed from the
    /// number by the caller, so both are written in one statement (two people opening the
    /// link at once, or on two servers, get different numbers: the insert retries on the
    /// unique number).
    pub async fn add_participant(
        &self,
        study_id: &str,
        id: &str,
        token: &str,
        ordering_for: impl Fn(usize) -> Vec<String>,
    ) -> Result<ParticipantRow> {
        loop {
            let next: i64 = on_db!(self.db, writer, |pool| sqlx::query_scalar(
                "SELECT COALESCE(MAX(number) + 1, 0) FROM participants WHERE study_id = $1",
            )
            .bind(study_id)
            .fetch_one(pool)
            .await?);
            let ordering = serde_json::to_string(&ordering_for(next as usize))
                .expect("a list of names serialises");
            let now = clock::now();
            let row = on_db!(self.db, writer, |pool| sqlx::query(
                "INSERT INTO participants (id, study_id, number, token, ordering, created_at)
                 VALUES ($1, $2, $3, $4, $5, $6)
                 ON CONFLICT (study_id, number) DO NOTHING RETURNING *",
            )
            .bind(id)
            .bind(study_id)
            .bind(next)
            .bind(token)
            .bind(ordering)
            .bind(&now)
            .fetch_optional(pool)
            .await?
            .as_ref()
            .map(ParticipantRow::from_row));
            if let Some(row) = row {
                return Ok(row);
            }
        }
    }

    pub async fn participant_by_token(&self, token: &str) -> Result<Option<ParticipantRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM participants WHERE token = $1"
        )
        .bind(token)
        .fetch_optional(pool)
        .await?
        .as_ref()
        .map(ParticipantRow::from_row)))
    }

    /// A study's participants in the order they came.
    pub async fn participants(&self, study_id: &str) -> Result<Vec<ParticipantRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM participants WHERE study_id = $1 ORDER BY number"
        )
        .bind(study_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(ParticipantRow::from_row)
        .collect()))
    }

    /// Record consent (the first time only; a second consent keeps the first time).
    pub async fn consent(&self, participant_id: &str) -> Result<()> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "UPDATE participants SET consented_at = $1 WHERE id = $2 AND consented_at IS NULL",
            )
            .bind(&now)
            .bind(participant_id)
            .execute(pool)
            .await?;
        });
        Ok(())
    }

    /// Link a launched session to a participant's position. Returns `false` when that position
    /// has a session already (the caller launched a second by mistake and must stop it).
    pub async fn link_study_session(&self, row: &StudySessionRow) -> Result<bool> {
        let linked = on_db!(self.db, writer, |pool| sqlx::query(
            "INSERT INTO study_sessions (participant_id, position, condition, session_id)
             VALUES ($1, $2, $3, $4) ON CONFLICT (participant_id, position) DO NOTHING",
        )
        .bind(&row.participant_id)
        .bind(row.position)
        .bind(&row.condition)
        .bind(&row.session_id)
        .execute(pool)
        .await?
        .rows_affected());
        Ok(linked == 1)
    }

    /// The sessions of the participants of a study (or of one participant).
    pub async fn study_sessions(&self, study_id: &str) -> Result<Vec<StudySessionRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT s.* FROM study_sessions s JOIN participants p ON p.id = s.participant_id
             WHERE p.study_id = $1 ORDER BY p.number, s.position",
        )
        .bind(study_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(study_session_from_row)
        .collect()))
    }

    pub async fn participant_sessions(&self, participant_id: &str) -> Result<Vec<StudySessionRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM study_sessions WHERE participant_id = $1 ORDER BY position"
        )
        .bind(participant_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(study_session_from_row)
        .collect()))
    }

    /// Store the survey after one position, all questions in one transaction; a survey
    /// answered before is kept as it was. Two submissions at once (two tabs, two servers):
    /// the second one's insert waits for the first one's commit and then inserts nothing, and
    /// it is answered as already answered too.
    pub async fn save_study_survey(
        &self,
        participant_id: &str,
        position: i64,
        answers: &[(String, i64)],
    ) -> Result<SurveyOutcome> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            let mut tx = pool.begin().await?;
            let before: i64 = sqlx::query_scalar(
                "SELECT COUNT(*) FROM study_answers WHERE participant_id = $1 AND position = $2",
            )
            .bind(participant_id)
            .bind(position)
            .fetch_one(&mut *tx)
            .await?;
            if before > 0 {
                return Ok(SurveyOutcome::AlreadyAnswered);
            }
            for (question, value) in answers {
                let inserted: Option<i64> = sqlx::query_scalar(
                    "INSERT INTO study_answers (participant_id, position, question, value, answered_at)
                     VALUES ($1, $2, $3, $4, $5)
                     ON CONFLICT (participant_id, position, question) DO NOTHING RETURNING position",
                )
                .bind(participant_id)
                .bind(position)
                .bind(question)
                .bind(value)
                .bind(&now)
                .fetch_optional(&mut *tx)
                .await?;
                if inserted.is_none() {
                    // Rolled back as `tx` drops: the other submission's answers stand.
                    return Ok(SurveyOutcome::AlreadyAnswered);
                }
            }
            tx.commit().await?;
            Ok(SurveyOutcome::Stored)
        })
    }

    /// Every survey answer of a study's participants.
    pub async fn study_answers(&self, study_id: &str) -> Result<Vec<StudyAnswerRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT a.* FROM study_answers a JOIN participants p ON p.id = a.participant_id
             WHERE p.study_id = $1 ORDER BY p.number, a.position, a.question",
        )
        .bind(study_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(study_answer_from_row)
        .collect()))
    }

    /// The positions whose survey a participant has answered.
    pub async fn answered_positions(&self, participant_id: &str) -> Result<Vec<i64>> {
        on_db!(self.db, reader, |pool| {
            sqlx::query_scalar(
                "SELECT DISTINCT position FROM study_answers WHERE participant_id = $1
                 ORDER BY position",
            )
            .bind(participant_id)
            .fetch_all(pool)
            .await
        })
    }
}

fn study_session_from_row(r: &impl StoreRow) -> StudySessionRow {
    StudySessionRow {
        participant_id: r.get("participant_id"),
        position: r.get("position"),
        condition: r.get("condition"),
        session_id: r.get("session_id"),
    }
}

fn study_answer_from_row(r: &impl StoreRow) -> StudyAnswerRow {
    StudyAnswerRow {
        participant_id: r.get("participant_id"),
        position: r.get("position"),
        question: r.get("question"),
        value: r.get("value"),
    }
}

impl Store {
    /// Seconds from a session's start to its end (or to now while it runs); `None` before it
    /// started.
    pub async fn session_seconds(&self, session_id: &str) -> Result<Option<f64>> {
        let times: Option<(Option<String>, Option<String>)> = on_db!(self.db, reader, |pool| {
            sqlx::query("SELECT started_at, ended_at FROM sessions WHERE id = $1")
                .bind(session_id)
                .fetch_optional(pool)
                .await?
                .map(|r| (r.get("started_at"), r.get("ended_at")))
        });
        let Some((Some(started), ended)) = times else {
            return Ok(None);
        };
        let ended = ended.unwrap_or_else(clock::now);
        Ok(clock::span(Some(&started), Some(&ended)))
    }
}
