//! The `queries` and `answers` tables: what a session asked and the one answer each query got.
//! The first committed answer wins (`answers.query_id` is the primary key); a repeat of the same
//! value is idempotent.

use serde::Serialize;
use sqlx::Row;

use super::{Result, Store};
use crate::session::AnswerValue;

/// One asked query.
#[derive(Clone, Debug, Serialize)]
pub struct QueryRow {
    pub id: i64,
    pub session_id: String,
    pub seq: i64,
    pub kind: String,
    pub step: i64,
    pub abstract_state: i64,
    pub asked_at: String,
}

/// One answered query, as `GET /api/sessions/{id}/answers` lists it.
#[derive(Clone, Debug, Serialize)]
pub struct AnswerRow {
    pub query_id: i64,
    pub seq: i64,
    pub kind: String,
    pub step: i64,
    pub abstract_state: i64,
    pub value: AnswerValue,
    /// `trainer`, `synthetic` or `timeout`.
    pub who: String,
    pub asked_at: String,
    pub answered_at: String,
    pub latency_ms: i64,
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
    pub kind: &'static str,
    pub step: u64,
    pub abstract_state: u32,
    pub value: AnswerValue,
}

fn value_json(v: AnswerValue) -> String {
    serde_json::to_string(&v).expect("answer values serialise")
}

fn parse_value(text: &str) -> AnswerValue {
    serde_json::from_str(text).unwrap_or(AnswerValue::Evaluation(0))
}

impl Store {
    /// Store a query (or find it again: a resumed session re-asks an unanswered query with the
    /// same `seq`) and return its id.
    pub async fn upsert_query(
        &self,
        session_id: &str,
        seq: u64,
        kind: &str,
        step: u64,
        abstract_state: u32,
        payload: &str,
    ) -> Result<i64> {
        let row =
            sqlx::query(concat!(
            "INSERT INTO queries (session_id, seq, kind, step, abstract_state, payload, asked_at)
             VALUES (?, ?, ?, ?, ?, ?, ", now!(), ")
             ON CONFLICT (session_id, seq) DO UPDATE SET asked_at = excluded.asked_at
             RETURNING id"
        ))
            .bind(session_id)
            .bind(seq as i64)
            .bind(kind)
            .bind(step as i64)
            .bind(i64::from(abstract_state))
            .bind(payload)
            .fetch_one(self.pool())
            .await?;
        Ok(row.get("id"))
    }

    pub async fn query(&self, id: i64) -> Result<Option<QueryRow>> {
        let row = sqlx::query(
            "SELECT id, session_id, seq, kind, step, abstract_state, asked_at FROM queries WHERE id = ?",
        )
        .bind(id)
        .fetch_optional(self.pool())
        .await?;
        Ok(row.map(|r| QueryRow {
            id: r.get("id"),
            session_id: r.get("session_id"),
            seq: r.get("seq"),
            kind: r.get("kind"),
            step: r.get("step"),
            abstract_state: r.get("abstract_state"),
            asked_at: r.get("asked_at"),
        }))
    }

    /// The stored payload (JSON text) of a query.
    pub async fn query_payload(&self, id: i64) -> Result<Option<String>> {
        let row = sqlx::query("SELECT payload FROM queries WHERE id = ?")
            .bind(id)
            .fetch_optional(self.pool())
            .await?;
        Ok(row.map(|r| r.get("payload")))
    }

    /// Commit an answer; returns only after the transaction is durable.
    pub async fn commit_answer(
        &self,
        query_id: i64,
        session_id: &str,
        value: AnswerValue,
        who: &str,
        latency_ms: u64,
    ) -> Result<CommitOutcome> {
        let inserted = sqlx::query(concat!(
            "INSERT INTO answers (query_id, session_id, value, who, latency_ms, answered_at)
             VALUES (?, ?, ?, ?, ?, ",
            now!(),
            ") ON CONFLICT (query_id) DO NOTHING"
        ))
        .bind(query_id)
        .bind(session_id)
        .bind(value_json(value))
        .bind(who)
        .bind(latency_ms as i64)
        .execute(self.pool())
        .await?
        .rows_affected();
        if inserted == 1 {
            return Ok(CommitOutcome::Committed);
        }
        let row = sqlx::query("SELECT value FROM answers WHERE query_id = ?")
            .bind(query_id)
            .fetch_one(self.pool())
            .await?;
        Ok(CommitOutcome::AlreadyAnswered(parse_value(
            row.get("value"),
        )))
    }

    /// The stored answer to a query, if any.
    pub async fn answer_value(&self, query_id: i64) -> Result<Option<AnswerValue>> {
        let row = sqlx::query("SELECT value FROM answers WHERE query_id = ?")
            .bind(query_id)
            .fetch_optional(self.pool())
            .await?;
        Ok(row.map(|r| parse_value(r.get("value"))))
    }

    /// A synthetic trainer's queries and answers in one transaction (a resumed synthetic
    /// session replays them: existing rows are left as they are).
    pub async fn insert_synthetic(
        &self,
        session_id: &str,
        batch: &[SyntheticAnswer],
    ) -> Result<()> {
        let mut tx = self.pool().begin().await?;
        for a in batch {
            let id: Option<i64> = sqlx::query(concat!(
                "INSERT INTO queries (session_id, seq, kind, step, abstract_state, payload, asked_at)
                 VALUES (?, ?, ?, ?, ?, '{}', ", now!(), ") ON CONFLICT (session_id, seq) DO NOTHING RETURNING id"
            ))
            .bind(session_id)
            .bind(a.seq as i64)
            .bind(a.kind)
            .bind(a.step as i64)
            .bind(i64::from(a.abstract_state))
            .fetch_optional(&mut *tx)
            .await?
            .map(|r| r.get("id"));
            if let Some(id) = id {
                sqlx::query(concat!(
                    "INSERT INTO answers (query_id, session_id, value, who, latency_ms, answered_at)
                     VALUES (?, ?, ?, 'synthetic', 0, ", now!(), ")"
                ))
                .bind(id)
                .bind(session_id)
                .bind(value_json(a.value))
                .execute(&mut *tx)
                .await?;
            }
        }
        tx.commit().await
    }

    /// The answers a resumed session replays: by query order, up to the first query without
    /// one.
    pub async fn replay_answers(&self, session_id: &str) -> Result<Vec<AnswerValue>> {
        let rows = sqlx::query(
            "SELECT q.seq, a.value FROM queries q LEFT JOIN answers a ON a.query_id = q.id
             WHERE q.session_id = ? ORDER BY q.seq",
        )
        .bind(session_id)
        .fetch_all(self.pool())
        .await?;
        let mut out = Vec::new();
        for (i, r) in rows.iter().enumerate() {
            let seq: i64 = r.get("seq");
            let value: Option<String> = r.get("value");
            match value {
                Some(v) if seq == i as i64 => out.push(parse_value(&v)),
                _ => break,
            }
        }
        Ok(out)
    }

    /// Every answered query of a session, in the order asked.
    pub async fn answers(&self, session_id: &str) -> Result<Vec<AnswerRow>> {
        let rows = sqlx::query(
            "SELECT q.id, q.seq, q.kind, q.step, q.abstract_state, q.asked_at,
                    a.value, a.who, a.answered_at, a.latency_ms
             FROM answers a JOIN queries q ON q.id = a.query_id
             WHERE a.session_id = ? ORDER BY q.seq",
        )
        .bind(session_id)
        .fetch_all(self.pool())
        .await?;
        Ok(rows
            .iter()
            .map(|r| AnswerRow {
                query_id: r.get("id"),
                seq: r.get("seq"),
                kind: r.get("kind"),
                step: r.get("step"),
                abstract_state: r.get("abstract_state"),
                value: parse_value(r.get("value")),
                who: r.get("who"),
                asked_at: r.get("asked_at"),
                answered_at: r.get("answered_at"),
                latency_ms: r.get("latency_ms"),
            })
            .collect())
    }

    /// Answers per source (`trainer`, `synthetic`, `timeout`) and how many were "no feedback"
    /// (value 0) or skips, for the session's summary.
    pub async fn answer_counts(&self, session_id: &str) -> Result<AnswerCounts> {
        let r = sqlx::query(
            "SELECT COUNT(*) AS total,
                    COALESCE(SUM(who = 'trainer'), 0) AS by_trainer,
                    COALESCE(SUM(who = 'timeout'), 0) AS timeouts,
                    COALESCE(SUM(value IN ('0', '\"skip\"')), 0) AS no_feedback
             FROM answers WHERE session_id = ?",
        )
        .bind(session_id)
        .fetch_one(self.pool())
        .await?;
        Ok(AnswerCounts {
            total: r.get("total"),
            by_trainer: r.get("by_trainer"),
            timeouts: r.get("timeouts"),
            no_feedback: r.get("no_feedback"),
        })
    }
}

/// A session's answers counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
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
        let r = sqlx::query(
            "SELECT (julianday(MAX(a.answered_at)) - julianday(MIN(q.asked_at))) * 86400.0 AS seconds
             FROM answers a JOIN queries q ON q.id = a.query_id
             WHERE a.session_id = ? AND a.who IN ('trainer', 'timeout')",
        )
        .bind(session_id)
        .fetch_one(self.pool())
        .await?;
        Ok(r.get("seconds"))
    }
}
