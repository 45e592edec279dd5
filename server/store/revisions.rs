//! Undo, in the `answer_revisions` table: a trainer takes back an answer (the query opens
//! again) and answers it anew. `answers` keeps the answer that stands now; each revision keeps
//! the progress at which the session's learner took it in, so a resumed session replays the
//! undo where it happened.

use sqlx::Row;

use super::queries::{parse_value, value_json};
use super::{Result, Store};
use crate::session::events::{Revision, StoredRevision};
use crate::session::{AnswerValue, Answerer, QueryKind};

/// What an undo did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UndoOutcome {
    /// Undone: this is the revision's number; the answer now reads as "no feedback" / skip.
    Undone(u32),
    /// The query has no answer to take back.
    NotAnswered,
    /// Undone already and not answered again yet.
    AlreadyUndone,
}

/// What answering an undone query did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReanswerOutcome {
    Committed(u32),
    /// The query is not open for a new answer (never undone, or answered again already): the
    /// answer that stands.
    Stands(AnswerValue),
}

impl Store {
    /// Take back the answer to `query_id` (by the named trainer `by`, if one); until it is
    /// answered again it stands as `AnswerValue::timeout(kind)` ("no feedback" or a skip, what
    /// the learner uses meanwhile).
    pub async fn undo_answer(
        &self,
        query_id: i64,
        session_id: &str,
        kind: QueryKind,
        by: Option<i64>,
    ) -> Result<UndoOutcome> {
        let mut tx = self.writer().begin().await?;
        let Some(row) = sqlx::query(
            "SELECT value, who, trainer_id, latency_ms, revision FROM answers
             WHERE query_id = ? AND session_id = ?",
        )
        .bind(query_id)
        .bind(session_id)
        .fetch_optional(&mut *tx)
        .await?
        else {
            return Ok(UndoOutcome::NotAnswered);
        };
        let revision: i64 = row.get("revision");
        if revision == 0 {
            // The original answer is what a resumed session feeds at the query itself.
            let original = RevisionRow {
                revision: 0,
                value: Some(row.get("value")),
                who: row.get("who"),
                trainer: row.get("trainer_id"),
                latency_ms: row.get("latency_ms"),
            };
            original.insert(&mut tx, query_id, session_id).await?;
        } else if last_is_undo(&mut tx, query_id, revision).await? {
            return Ok(UndoOutcome::AlreadyUndone);
        }
        let next = revision + 1;
        let undo = RevisionRow {
            revision: next,
            value: None,
            who: Answerer::Trainer,
            trainer: by,
            latency_ms: 0,
        };
        undo.insert(&mut tx, query_id, session_id).await?;
        sqlx::query("UPDATE answers SET value = ?, revision = ? WHERE query_id = ?")
            .bind(value_json(AnswerValue::timeout(kind)))
            .bind(next)
            .bind(query_id)
            .execute(&mut *tx)
            .await?;
        tx.commit().await?;
        Ok(UndoOutcome::Undone(next as u32))
    }

    /// Answer a query whose answer was undone (by the named trainer `trainer`, if one);
    /// returns after the commit.
    pub async fn reanswer(
        &self,
        query_id: i64,
        value: AnswerValue,
        who: Answerer,
        trainer: Option<i64>,
        latency_ms: u64,
    ) -> Result<ReanswerOutcome> {
        let mut tx = self.writer().begin().await?;
        let row = sqlx::query("SELECT value, revision, session_id FROM answers WHERE query_id = ?")
            .bind(query_id)
            .fetch_one(&mut *tx)
            .await?;
        let revision: i64 = row.get("revision");
        if revision == 0 || !last_is_undo(&mut tx, query_id, revision).await? {
            return Ok(ReanswerOutcome::Stands(parse_value(row.get("value"))));
        }
        let next = revision + 1;
        let again = RevisionRow {
            revision: next,
            value: Some(value_json(value)),
            who,
            trainer,
            latency_ms: latency_ms as i64,
        };
        let session_id: String = row.get("session_id");
        again.insert(&mut tx, query_id, &session_id).await?;
        sqlx::query(concat!(
            "UPDATE answers SET value = ?, who = ?, trainer_id = ?, latency_ms = ?, revision = ?, answered_at = ",
            now!(),
            " WHERE query_id = ?"
        ))
        .bind(value_json(value))
        .bind(who)
        .bind(trainer)
        .bind(latency_ms as i64)
        .bind(next)
        .bind(query_id)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(ReanswerOutcome::Committed(next as u32))
    }

    /// The session applied revision `revision` of query `seq` at `progress` (kept the first
    /// time only: a resumed session re-applies it at the same point).
    pub async fn revision_applied(
        &self,
        session_id: &str,
        seq: u64,
        revision: u32,
        progress: u64,
    ) -> Result<()> {
        sqlx::query(
            "UPDATE answer_revisions SET applied_at = ?
             WHERE revision = ? AND applied_at IS NULL
               AND query_id = (SELECT id FROM queries WHERE session_id = ? AND seq = ?)",
        )
        .bind(progress as i64)
        .bind(i64::from(revision))
        .bind(session_id)
        .bind(seq as i64)
        .execute(self.writer())
        .await?;
        Ok(())
    }

    /// The revisions a resumed session replays: where they were applied, in the order they
    /// were; those never applied last, in the order committed.
    pub async fn replay_revisions(&self, session_id: &str) -> Result<Vec<StoredRevision>> {
        let rows = sqlx::query(
            "SELECT q.seq, r.revision, r.value, r.applied_at
             FROM answer_revisions r JOIN queries q ON q.id = r.query_id
             WHERE r.session_id = ? AND r.revision > 0
             ORDER BY r.applied_at IS NULL, r.applied_at, r.rowid",
        )
        .bind(session_id)
        .fetch_all(self.pool())
        .await?;
        Ok(rows
            .iter()
            .map(|r| StoredRevision {
                revision: Revision {
                    seq: r.get::<i64, _>("seq") as u64,
                    revision: r.get::<i64, _>("revision") as u32,
                    value: r.get::<Option<String>, _>("value").map(|v| parse_value(&v)),
                },
                applied_at: r.get::<Option<i64>, _>("applied_at").map(|p| p as u64),
            })
            .collect())
    }
}

/// One row of `answer_revisions` before it is applied.
struct RevisionRow {
    revision: i64,
    /// JSON; `None` for an undo.
    value: Option<String>,
    who: Answerer,
    /// The named trainer, if one.
    trainer: Option<i64>,
    latency_ms: i64,
}

impl RevisionRow {
    async fn insert(
        &self,
        tx: &mut sqlx::SqliteConnection,
        query_id: i64,
        session_id: &str,
    ) -> Result<()> {
        sqlx::query(concat!(
            "INSERT INTO answer_revisions
               (query_id, session_id, revision, value, who, trainer_id, latency_ms, applied_at, created_at)
             VALUES (?, ?, ?, ?, ?, ?, ?, NULL, ",
            now!(),
            ")"
        ))
        .bind(query_id)
        .bind(session_id)
        .bind(self.revision)
        .bind(self.value.as_deref())
        .bind(self.who)
        .bind(self.trainer)
        .bind(self.latency_ms)
        .execute(tx)
        .await?;
        Ok(())
    }
}

/// Whether the latest revision of `query_id` is an undo not yet answered.
async fn last_is_undo(
    tx: &mut sqlx::SqliteConnection,
    query_id: i64,
    revision: i64,
) -> Result<bool> {
    let value: Option<Option<String>> =
        sqlx::query("SELECT value FROM answer_revisions WHERE query_id = ? AND revision = ?")
            .bind(query_id)
            .bind(revision)
            .fetch_optional(tx)
            .await?
            .map(|r| r.get("value"));
    Ok(matches!(value, Some(None)))
}
