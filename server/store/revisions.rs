//! Undo, in the `answer_revisions` table: a trainer takes back an answer (the query opens
//! again) and answers it anew. `answers` keeps the answer that stands now; each revision keeps
//! the progress at which the session's learner took it in, so a resumed session replays the
//! undo where it happened.

use sqlx::{Database, Encode, Executor, IntoArguments, Type};

use super::backend::StoreRow;
use super::queries::{parse_value, value_json};
use super::{Result, Store, clock};
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
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            let mut tx = pool.begin().await?;
            // The row's lock first (on PostgreSQL an undo or a new answer at the same moment
            // waits here for this transaction): the revision read is the one this writes after.
            // Dropping `tx` without a commit takes the increment back.
            let Some(row) = sqlx::query(
                "UPDATE answers SET revision = revision + 1
                 WHERE query_id = $1 AND session_id = $2
                 RETURNING value, who, trainer_id, latency_ms, revision - 1 AS revision",
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
                original
                    .insert(&mut *tx, query_id, session_id, &now)
                    .await?;
            } else if last_is_undo(&mut *tx, query_id, revision).await? {
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
            undo.insert(&mut *tx, query_id, session_id, &now).await?;
            sqlx::query("UPDATE answers SET value = $1 WHERE query_id = $2")
                .bind(value_json(AnswerValue::timeout(kind)))
                .bind(query_id)
                .execute(&mut *tx)
                .await?;
            tx.commit().await?;
            Ok(UndoOutcome::Undone(next as u32))
        })
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
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            let mut tx = pool.begin().await?;
            // Locked first, as in `undo_answer`.
            let row = sqlx::query(
                "UPDATE answers SET revision = revision + 1 WHERE query_id = $1
                 RETURNING value, revision - 1 AS revision, session_id",
            )
            .bind(query_id)
            .fetch_optional(&mut *tx)
            .await?
            .ok_or(sqlx::Error::RowNotFound)?;
            let revision: i64 = row.get("revision");
            if revision == 0 || !last_is_undo(&mut *tx, query_id, revision).await? {
                return Ok(ReanswerOutcome::Stands(parse_value(
                    &row.get::<String>("value"),
                )));
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
            again.insert(&mut *tx, query_id, &session_id, &now).await?;
            sqlx::query(
                "UPDATE answers SET value = $1, who = $2, trainer_id = $3, latency_ms = $4,
                 answered_at = $5 WHERE query_id = $6",
            )
            .bind(value_json(value))
            .bind(who)
            .bind(trainer)
            .bind(latency_ms as i64)
            .bind(&now)
            .bind(query_id)
            .execute(&mut *tx)
            .await?;
            tx.commit().await?;
            Ok(ReanswerOutcome::Committed(next as u32))
        })
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
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "UPDATE answer_revisions SET applied_at = $1
                 WHERE revision = $2 AND applied_at IS NULL
                   AND query_id = (SELECT id FROM queries WHERE session_id = $3 AND seq = $4)",
            )
            .bind(progress as i64)
            .bind(i64::from(revision))
            .bind(session_id)
            .bind(seq as i64)
            .execute(pool)
            .await?;
        });
        Ok(())
    }

    /// The revisions a resumed session replays: where they were applied, in the order they
    /// were; those never applied last, in the order committed (`rowid`: SQLite's insertion
    /// order, an identity column of that name on PostgreSQL).
    pub async fn replay_revisions(&self, session_id: &str) -> Result<Vec<StoredRevision>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT q.seq, r.revision, r.value, r.applied_at
             FROM answer_revisions r JOIN queries q ON q.id = r.query_id
             WHERE r.session_id = $1 AND r.revision > 0
             ORDER BY r.applied_at IS NULL, r.applied_at, r.rowid",
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| StoredRevision {
            revision: Revision {
                seq: r.get::<i64>("seq") as u64,
                revision: r.get::<i64>("revision") as u32,
                value: r.get::<Option<String>>("value").map(|v| parse_value(&v)),
            },
            applied_at: r.get::<Option<i64>>("applied_at").map(|p| p as u64),
        })
        .collect()))
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
    /// Insert the row in the transaction `tx` (of either database).
    async fn insert<'c, DB>(
        &self,
        tx: impl Executor<'c, Database = DB>,
        query_id: i64,
        session_id: &str,
        now: &str,
    ) -> Result<()>
    where
        DB: Database,
        DB::Arguments: IntoArguments<DB>,
        for<'e> i64: Encode<'e, DB> + Type<DB>,
        for<'e> Option<i64>: Encode<'e, DB> + Type<DB>,
        for<'e> String: Encode<'e, DB> + Type<DB>,
        for<'e> Option<String>: Encode<'e, DB> + Type<DB>,
        for<'e> Answerer: Encode<'e, DB> + Type<DB>,
    {
        sqlx::query(
            "INSERT INTO answer_revisions
               (query_id, session_id, revision, value, who, trainer_id, latency_ms, applied_at, created_at)
             VALUES ($1, $2, $3, $4, $5, $6, $7, NULL, $8)",
        )
        .bind(query_id)
        .bind(session_id.to_string())
        .bind(self.revision)
        .bind(self.value.clone())
        .bind(self.who)
        .bind(self.trainer)
        .bind(self.latency_ms)
        .bind(now.to_string())
        .execute(tx)
        .await?;
        Ok(())
    }
}

/// Whether the latest revision of `query_id` is an undo not yet answered.
async fn last_is_undo<'c, DB>(
    tx: impl Executor<'c, Database = DB>,
    query_id: i64,
    revision: i64,
) -> Result<bool>
where
    DB: Database,
    DB::Arguments: IntoArguments<DB>,
    DB::Row: StoreRow,
    for<'e> i64: Encode<'e, DB> + Type<DB>,
{
    let value: Option<Option<String>> =
        sqlx::query("SELECT value FROM answer_revisions WHERE query_id = $1 AND revision = $2")
            .bind(query_id)
            .bind(revision)
            .fetch_optional(tx)
            .await?
            .map(|r| r.get("value"));
    Ok(matches!(value, Some(None)))
}
