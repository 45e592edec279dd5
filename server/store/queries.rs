//! The `queries` and `answers` tables: what a session asked and the one answer each query got.
//! The first committed answer wins (`answers.query_id` is the primary key); a repeat of the same
//! value is idempotent.

use std::collections::{HashMap, HashSet};

use serde::Serialize;

use super::backend::StoreRow;
use super::transitions::insert_asked_step;
use super::{Db, Result, Store, clock};
use crate::guidance::evaluative_run::AskedStep;
use crate::session::{AnswerValue, Answerer, QueryKind};

/// One asked query.
#[derive(Clone, Debug, Serialize)]
pub struct QueryRow {
    pub id: i64,
    pub session_id: String,
    pub seq: i64,
    pub kind: QueryKind,
    pub step: i64,
    pub abstract_state: i64,
    pub asked_at: String,
}

/// One answered query, as `GET /api/sessions/{id}/answers` lists it.
#[derive(Clone, Debug, Serialize, utoipa::ToSchema)]
pub struct AnswerRow {
    /// The session's query number (the query's id on the websocket).
    pub query_id: i64,
    pub kind: QueryKind,
    pub step: i64,
    pub abstract_state: i64,
    pub value: AnswerValue,
    pub who: Answerer,
    /// The named trainer who gave it (`who` = trainer); none for the anonymous trainer, the
    /// synthetic one, a timeout and several trainers' combined answers.
    pub trainer: Option<String>,
    pub trainer_id: Option<i64>,
    pub asked_at: String,
    pub answered_at: String,
    pub latency_ms: i64,
    /// How often the answer changed by an undo (0: never); `value` is the one that stands.
    pub revision: i64,
}

/// What committing an answer did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommitOutcome {
    /// This answer is the query's answer.
    Committed,
    /// The query already had an answer (this value, or another one).
    AlreadyAnswered(AnswerValue),
}

/// A synthetic trainer's query and answer, stored together.
#[derive(Clone, Debug)]
pub struct SyntheticAnswer {
    pub seq: u64,
    pub kind: QueryKind,
    pub step: u64,
    pub abstract_state: u32,
    pub value: AnswerValue,
    /// What the learner saw (JSON, see `queries.data`).
    pub data: Option<String>,
    /// The step as the run stored it (sessions on a remote env; `query_transitions`).
    pub asked: Option<AskedStep>,
}

pub(super) fn value_json(v: AnswerValue) -> String {
    serde_json::to_string(&v).expect("answer values serialise")
}

pub(super) fn parse_value(text: &str) -> AnswerValue {
    serde_json::from_str(text).unwrap_or(AnswerValue::Evaluation(0))
}

impl Store {
    /// How many query numbers a session has used (its highest `seq` + 1): a session on a
    /// remote env numbers new queries after all of them.
    pub async fn query_count(&self, session_id: &str) -> Result<u64> {
        let n: i64 = on_db!(self.db, reader, |pool| sqlx::query_scalar(
            "SELECT COALESCE(MAX(seq) + 1, 0) FROM queries WHERE session_id = $1"
        )
        .bind(session_id)
        .fetch_one(pool)
        .await?);
        Ok(n as u64)
    }

    /// Store a query (or find it again: a resumed session re-asks an unanswered query with the
    /// same `seq`) with what the learner saw (`data`, JSON) and return its id.
    #[allow(clippy::too_many_arguments)]
    pub async fn upsert_query(
        &self,
        session_id: &str,
        seq: u64,
        kind: QueryKind,
        step: u64,
        abstract_state: u32,
        payload: &str,
        data: Option<&str>,
    ) -> Result<i64> {
        let now = clock::now();
        Ok(on_db!(self.db, writer, |pool| {
            sqlx::query_scalar(
                "INSERT INTO queries
                   (session_id, seq, kind, step, abstract_state, payload, data, asked_at)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8)
                 ON CONFLICT (session_id, seq) DO UPDATE SET asked_at = excluded.asked_at
                 RETURNING id",
            )
            .bind(session_id)
            .bind(seq as i64)
            .bind(kind)
            .bind(step as i64)
            .bind(i64::from(abstract_state))
            .bind(payload)
            .bind(data)
            .bind(&now)
            .fetch_one(pool)
            .await?
        }))
    }

    /// A session's query by its number (its id on the wire).
    pub async fn query_by_number(&self, session_id: &str, seq: u64) -> Result<Option<QueryRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT id, session_id, seq, kind, step, abstract_state, asked_at FROM queries
             WHERE session_id = $1 AND seq = $2",
        )
        .bind(session_id)
        .bind(seq as i64)
        .fetch_optional(pool)
        .await?
        .map(|r| QueryRow {
            id: r.get("id"),
            session_id: r.get("session_id"),
            seq: r.get("seq"),
            kind: r.get("kind"),
            step: r.get("step"),
            abstract_state: r.get("abstract_state"),
            asked_at: r.get("asked_at"),
        })))
    }

    /// Commit an answer (by a named trainer: `trainer`); returns only after the transaction is
    /// durable. Answers committing at the same moment share one transaction (and one fsync):
    /// see `group_commit`.
    pub async fn commit_answer(
        &self,
        query_id: i64,
        session_id: &str,
        value: AnswerValue,
        who: Answerer,
        trainer: Option<i64>,
        latency_ms: u64,
    ) -> Result<CommitOutcome> {
        let (reply, outcome) = tokio::sync::oneshot::channel();
        let request = CommitRequest {
            query_id,
            session_id: session_id.to_string(),
            value,
            who,
            trainer,
            latency_ms,
            reply,
        };
        if self.committer.send(request).await.is_err() {
            return Err(sqlx::Error::PoolClosed);
        }
        outcome.await.map_err(|_| sqlx::Error::PoolClosed)?
    }

    /// The stored answer to a query, if any.
    pub async fn answer_value(&self, query_id: i64) -> Result<Option<AnswerValue>> {
        let value: Option<String> = on_db!(self.db, reader, |pool| sqlx::query_scalar(
            "SELECT value FROM answers WHERE query_id = $1"
        )
        .bind(query_id)
        .fetch_optional(pool)
        .await?);
        Ok(value.as_deref().map(parse_value))
    }

    /// A synthetic trainer's queries and answers in one transaction (a resumed synthetic
    /// session replays them: existing rows are left as they are).
    pub async fn insert_synthetic(
        &self,
        session_id: &str,
        batch: &[SyntheticAnswer],
    ) -> Result<()> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            let mut tx = pool.begin().await?;
            for a in batch {
                let id: Option<i64> = sqlx::query_scalar(
                    "INSERT INTO queries (session_id, seq, kind, step, abstract_state, payload, data, asked_at)
                     VALUES ($1, $2, $3, $4, $5, '{}', $6, $7)
                     ON CONFLICT (session_id, seq) DO NOTHING RETURNING id",
                )
                .bind(session_id)
                .bind(a.seq as i64)
                .bind(a.kind)
                .bind(a.step as i64)
                .bind(i64::from(a.abstract_state))
                .bind(a.data.as_deref())
                .bind(&now)
                .fetch_optional(&mut *tx)
                .await?;
                if let Some(id) = id {
                    sqlx::query(
                        "INSERT INTO answers (query_id, session_id, value, who, latency_ms, answered_at)
                         VALUES ($1, $2, $3, 'synthetic', 0, $4)",
                    )
                    .bind(id)
                    .bind(session_id)
                    .bind(value_json(a.value))
                    .bind(&now)
                    .execute(&mut *tx)
                    .await?;
                    if let Some(step) = &a.asked {
                        insert_asked_step(&mut *tx, id, session_id, step).await?;
                    }
                }
            }
            tx.commit().await
        })
    }

    /// The answers a resumed session replays: by query order, up to the first query without
    /// one; an answer changed by an undo as first given (the change is replayed where it was
    /// applied, see `replay_revisions`).
    pub async fn replay_answers(&self, session_id: &str) -> Result<Vec<AnswerValue>> {
        let rows: Vec<(i64, Option<String>)> = on_db!(self.db, reader, |pool| sqlx::query(
            "SELECT q.seq,
                    COALESCE((SELECT r.value FROM answer_revisions r
                              WHERE r.query_id = q.id AND r.revision = 0), a.value) AS value
             FROM queries q LEFT JOIN answers a ON a.query_id = q.id
             WHERE q.session_id = $1 ORDER BY q.seq",
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| (r.get("seq"), r.get("value")))
        .collect());
        let mut out = Vec::new();
        for (i, (seq, value)) in rows.into_iter().enumerate() {
            match value {
                Some(v) if seq == i as i64 => out.push(parse_value(&v)),
                _ => break,
            }
        }
        Ok(out)
    }

    /// Every answered query of a session, in the order asked.
    pub async fn answers(&self, session_id: &str) -> Result<Vec<AnswerRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT q.seq, q.kind, q.step, q.abstract_state, q.asked_at,
                    a.value, a.who, a.answered_at, a.latency_ms, a.revision, a.trainer_id, t.name
             FROM answers a JOIN queries q ON q.id = a.query_id
             LEFT JOIN trainers t ON t.id = a.trainer_id
             WHERE a.session_id = $1 ORDER BY q.seq",
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| AnswerRow {
            query_id: r.get("seq"),
            kind: r.get("kind"),
            step: r.get("step"),
            abstract_state: r.get("abstract_state"),
            value: parse_value(&r.get::<String>("value")),
            who: r.get("who"),
            trainer: r.get("name"),
            trainer_id: r.get("trainer_id"),
            asked_at: r.get("asked_at"),
            answered_at: r.get("answered_at"),
            latency_ms: r.get("latency_ms"),
            revision: r.get("revision"),
        })
        .collect()))
    }

    /// Answers per source (`trainer`, `trainers`, `synthetic`, `timeout`) and how many were "no feedback"
    /// (value 0) or skips, for the session's summary.
    pub async fn answer_counts(&self, session_id: &str) -> Result<AnswerCounts> {
        on_db!(self.db, reader, |pool| {
            let r = sqlx::query(
                "SELECT COUNT(*) AS total,
                        COUNT(*) FILTER (WHERE who IN ('trainer', 'trainers')) AS by_trainer,
                        COUNT(*) FILTER (WHERE who = 'timeout') AS timeouts,
                        COUNT(*) FILTER (WHERE value IN ('0', '\"skip\"')) AS no_feedback
                 FROM answers WHERE session_id = $1",
            )
            .bind(session_id)
            .fetch_one(pool)
            .await?;
            Ok(AnswerCounts {
                total: r.get("total"),
                by_trainer: r.get("by_trainer"),
                timeouts: r.get("timeouts"),
                no_feedback: r.get("no_feedback"),
            })
        })
    }
}

/// A session's answers counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, utoipa::ToSchema)]
pub struct AnswerCounts {
    pub total: i64,
    pub by_trainer: i64,
    pub timeouts: i64,
    /// "No feedback" answers and skipped pairs, timeouts included (the paper's NFC).
    pub no_feedback: i64,
}

impl Store {
    /// Seconds from the first query a person was asked to the last answer (the paper's T), for
    /// sessions with human answers.
    pub async fn trainer_seconds(&self, session_id: &str) -> Result<Option<f64>> {
        let (first, last): (Option<String>, Option<String>) = on_db!(self.db, reader, |pool| {
            let r = sqlx::query(
                "SELECT MIN(q.asked_at) AS first, MAX(a.answered_at) AS last
                 FROM answers a JOIN queries q ON q.id = a.query_id
                 WHERE a.session_id = $1 AND a.who IN ('trainer', 'trainers', 'timeout')",
            )
            .bind(session_id)
            .fetch_one(pool)
            .await?;
            (r.get("first"), r.get("last"))
        });
        Ok(clock::span(first.as_deref(), last.as_deref()))
    }
}

/// One answer waiting to be committed.
pub(super) struct CommitRequest {
    query_id: i64,
    session_id: String,
    value: AnswerValue,
    who: Answerer,
    trainer: Option<i64>,
    latency_ms: u64,
    reply: tokio::sync::oneshot::Sender<Result<CommitOutcome>>,
}

/// Answers per transaction at most.
const GROUP_COMMIT_MAX: usize = 256;

/// The answer writer: takes every request that queued while the previous transaction was
/// committing and commits them together, so that a burst of answers (many sessions asking at
/// once) costs one fsync instead of one each. Each caller learns its own outcome.
pub(super) async fn group_commit(db: Db, mut rx: tokio::sync::mpsc::Receiver<CommitRequest>) {
    while let Some(first) = rx.recv().await {
        let mut batch = vec![first];
        while batch.len() < GROUP_COMMIT_MAX {
            match rx.try_recv() {
                Ok(r) => batch.push(r),
                Err(_) => break,
            }
        }
        match commit_batch(&db, &batch).await {
            Ok(outcomes) => {
                for (r, o) in batch.into_iter().zip(outcomes) {
                    let _ = r.reply.send(Ok(o));
                }
            }
            Err(e) => {
                tracing::error!("committing {} answer(s) failed: {e}", batch.len());
                let message = e.to_string();
                for r in batch {
                    let _ = r.reply.send(Err(sqlx::Error::Protocol(message.clone())));
                }
            }
        }
    }
}

/// One multi-row statement (one implicit transaction, one fsync) for the whole batch; rows that
/// hit an existing answer come back with that answer.
async fn commit_batch(db: &Db, batch: &[CommitRequest]) -> Result<Vec<CommitOutcome>> {
    let now = clock::now();
    let (inserted, existing) = on_db!(*db, writer, |writer: DB| {
        let mut insert = sqlx::QueryBuilder::<DB>::new(
            "INSERT INTO answers (query_id, session_id, value, who, trainer_id, latency_ms, answered_at) ",
        );
        insert.push_values(batch, |mut row, r| {
            row.push_bind(r.query_id)
                .push_bind(r.session_id.clone())
                .push_bind(value_json(r.value))
                .push_bind(r.who)
                .push_bind(r.trainer)
                .push_bind(r.latency_ms as i64)
                .push_bind(now.clone());
        });
        insert.push(" ON CONFLICT (query_id) DO NOTHING RETURNING query_id");
        let inserted: HashSet<i64> = insert
            .build()
            .fetch_all(writer)
            .await?
            .iter()
            .map(|r| r.get("query_id"))
            .collect();
        let conflicts: Vec<i64> = batch
            .iter()
            .map(|r| r.query_id)
            .filter(|q| !inserted.contains(q))
            .collect();
        let mut existing = HashMap::new();
        if !conflicts.is_empty() {
            let mut select = sqlx::QueryBuilder::<DB>::new(
                "SELECT query_id, value FROM answers WHERE query_id IN (",
            );
            let mut ids = select.separated(", ");
            for q in &conflicts {
                ids.push_bind(*q);
            }
            select.push(")");
            for r in select.build().fetch_all(writer).await? {
                existing.insert(
                    r.get::<i64>("query_id"),
                    parse_value(&r.get::<String>("value")),
                );
            }
        }
        (inserted, existing)
    });
    // Within a batch, the first request for a query is the one that was inserted.
    let mut claimed = HashSet::new();
    Ok(batch
        .iter()
        .map(|r| {
            if inserted.contains(&r.query_id) && claimed.insert(r.query_id) {
                CommitOutcome::Committed
            } else {
                let stored = existing
                    .get(&r.query_id)
                    .copied()
                    .or_else(|| {
                        batch
                            .iter()
                            .find(|b| b.query_id == r.query_id)
                            .map(|b| b.value)
                    })
                    .unwrap_or(r.value);
                CommitOutcome::AlreadyAnswered(stored)
            }
        })
        .collect())
}
