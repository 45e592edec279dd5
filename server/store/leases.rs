//! Several servers on one PostgreSQL: which server runs a session (`owner`, a random id per
//! process) and until when (`lease_until`, on the database's clock, so that servers whose
//! clocks differ agree on when a lease ran out). Only PostgreSQL has these: on SQLite one
//! server owns the database and every call here does nothing.
//!
//! Checkpoints: a session on our simulator resumes by replaying its stored answers from step 0
//! (the checkpoint row's digest checks the replay), so the database already holds all it needs.
//! A session on a remote env resumes from its run's latest resume checkpoint, a file in the
//! data dir of the server that ran it; on PostgreSQL its bytes are also stored in
//! `session_resumes` (the latest only), and a server that takes the session over writes them
//! into its own data dir before it starts the session. So servers need no shared data dir: the
//! database is the one place they all reach, and a killed server's disk may be gone with it.
//! (The learner's weights file, `<id>.safetensors`, is for exports and stays in the data dir of
//! the server that wrote it.)

use std::time::Duration;

use super::backend::StoreRow;
use super::sessions::{SessionRow, Status};
use super::{Db, Result, Store};

/// Who runs a session now, as the database says.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LeaseHolder {
    pub id: String,
    pub owner: Option<String>,
    pub status: Status,
    /// Whether the owner's lease still holds (by the database's clock).
    pub live: bool,
}

impl Store {
    /// Whether several servers may share this database (PostgreSQL): sessions are claimed
    /// under leases rather than run by the server that launched them.
    pub fn is_shared(&self) -> bool {
        matches!(self.db, Db::Postgres(_))
    }

    /// Claim up to `free` sessions for server `me` under a lease of `lease`: queued ones, and
    /// running ones whose lease ran out (their server died), oldest first. Rows another server
    /// is claiming at the same moment are skipped, not waited for. Returns the claimed rows as
    /// they were before (`status` says whether each was queued or running).
    pub async fn claim_sessions(
        &self,
        me: &str,
        free: usize,
        lease: Duration,
    ) -> Result<Vec<SessionRow>> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(Vec::new());
        };
        if free == 0 {
            return Ok(Vec::new());
        }
        let rows = sqlx::query(
            "UPDATE sessions SET owner = $1, lease_until = now() + make_interval(secs => $3)
             WHERE id IN (
               SELECT id FROM sessions
               WHERE status IN ('queued', 'running', 'waiting')
                 AND (lease_until IS NULL OR lease_until < now())
               ORDER BY created_at, id
               LIMIT $2
               FOR UPDATE SKIP LOCKED)
             RETURNING *",
        )
        .bind(me)
        .bind(free as i64)
        .bind(lease.as_secs_f64())
        .fetch_all(pool)
        .await?;
        let mut rows: Vec<SessionRow> = rows.iter().map(SessionRow::from_row).collect();
        rows.sort_by(|a, b| (&a.created_at, &a.id).cmp(&(&b.created_at, &b.id)));
        Ok(rows)
    }

    /// Extend the leases of `ids` that server `me` still owns; returns those it owns (a
    /// session missing from the answer was taken over, or its lease could not be renewed).
    pub async fn renew_leases(
        &self,
        me: &str,
        ids: &[String],
        lease: Duration,
    ) -> Result<Vec<String>> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(ids.to_vec());
        };
        if ids.is_empty() {
            return Ok(Vec::new());
        }
        Ok(sqlx::query(
            "UPDATE sessions SET lease_until = now() + make_interval(secs => $3)
             WHERE owner = $1 AND id = ANY($2) RETURNING id",
        )
        .bind(me)
        .bind(ids)
        .bind(lease.as_secs_f64())
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| r.get("id"))
        .collect())
    }

    /// Who holds the sessions `ids` (those that exist), for the servers that relay to them.
    pub async fn lease_holders(&self, ids: &[String]) -> Result<Vec<LeaseHolder>> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(Vec::new());
        };
        if ids.is_empty() {
            return Ok(Vec::new());
        }
        Ok(sqlx::query(
            "SELECT id, owner, status, COALESCE(lease_until > now(), false) AS live
             FROM sessions WHERE id = ANY($1)",
        )
        .bind(ids)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| {
            let status: String = r.get("status");
            LeaseHolder {
                id: r.get("id"),
                owner: r.get("owner"),
                status: Status::parse(&status).unwrap_or(Status::Failed),
                live: r.get("live"),
            }
        })
        .collect())
    }

    /// Let go of every session server `me` holds (a graceful shutdown): their leases end now,
    /// and other servers claim them at their next look. Returns how many.
    pub async fn release_leases(&self, me: &str) -> Result<u64> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(0);
        };
        Ok(sqlx::query(
            "UPDATE sessions SET lease_until = now() - interval '1 second'
             WHERE owner = $1 AND status IN ('queued', 'running', 'waiting')",
        )
        .bind(me)
        .execute(pool)
        .await?
        .rows_affected())
    }

    /// Queue a stored session again for any server to claim (a resume on PostgreSQL): no
    /// owner, no lease. Returns whether it was resumable (interrupted, stopped or failed).
    pub async fn requeue(&self, id: &str) -> Result<bool> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(false);
        };
        let done = sqlx::query(
            "UPDATE sessions SET status = 'queued', reason = NULL, owner = NULL, lease_until = NULL
             WHERE id = $1 AND status IN ('interrupted', 'stopped', 'failed')",
        )
        .bind(id)
        .execute(pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Stop a queued session no server has claimed yet; whether it was one.
    pub async fn stop_unclaimed(&self, id: &str, reason: &str) -> Result<bool> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(false);
        };
        let done = sqlx::query(
            "UPDATE sessions SET status = 'stopped', reason = $2, ended_at = $3
             WHERE id = $1 AND status = 'queued' AND (lease_until IS NULL OR lease_until < now())",
        )
        .bind(id)
        .bind(reason)
        .bind(super::clock::now())
        .execute(pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Keep a remote session's latest resume checkpoint where every server reads it
    /// (PostgreSQL only; SQLite's server has it in its data dir).
    pub async fn save_resume(&self, id: &str, bytes: &[u8]) -> Result<()> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(());
        };
        sqlx::query(
            "INSERT INTO session_resumes (session_id, bytes) VALUES ($1, $2)
             ON CONFLICT (session_id) DO UPDATE SET bytes = excluded.bytes",
        )
        .bind(id)
        .bind(bytes)
        .execute(pool)
        .await?;
        Ok(())
    }

    /// The resume checkpoint [`Store::save_resume`] kept, if any.
    pub async fn resume_bytes(&self, id: &str) -> Result<Option<Vec<u8>>> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(None);
        };
        Ok(
            sqlx::query("SELECT bytes FROM session_resumes WHERE session_id = $1")
                .bind(id)
                .fetch_optional(pool)
                .await?
                .map(|r| r.get("bytes")),
        )
    }
}
