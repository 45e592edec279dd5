//! The `sessions` table.

use serde::{Deserialize, Serialize};

use super::backend::StoreRow;
use super::{Result, Store, clock};

/// A session's lifecycle state (`status` in the API and the table).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Queued,
    Running,
    /// Running, and waiting for a trainer's answer.
    Waiting,
    Finished,
    Failed,
    Stopped,
    /// Cut off by a shutdown or crash; `POST .../resume` continues it.
    Interrupted,
}

impl Status {
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Queued => "queued",
            Status::Running => "running",
            Status::Waiting => "waiting",
            Status::Finished => "finished",
            Status::Failed => "failed",
            Status::Stopped => "stopped",
            Status::Interrupted => "interrupted",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        [
            Status::Queued,
            Status::Running,
            Status::Waiting,
            Status::Finished,
            Status::Failed,
            Status::Stopped,
            Status::Interrupted,
        ]
        .into_iter()
        .find(|x| x.as_str() == s)
    }

    /// Whether a session in this state has a live thread (or is about to).
    /// The status the database keeps: `waiting` lives in memory only and is stored as
    /// `running` (both become `interrupted` after a crash).
    pub fn stored(self) -> Status {
        match self {
            Status::Waiting => Status::Running,
            other => other,
        }
    }

    pub fn is_active(self) -> bool {
        matches!(self, Status::Queued | Status::Running | Status::Waiting)
    }

    /// Whether `POST .../resume` may continue it.
    pub fn is_resumable(self) -> bool {
        matches!(self, Status::Interrupted | Status::Stopped | Status::Failed)
    }
}

/// One row of `sessions`.
#[derive(Clone, Debug, Serialize)]
pub struct SessionRow {
    pub id: String,
    pub task: String,
    pub method: String,
    pub trainer: String,
    pub seed: i64,
    pub budget: i64,
    pub config: serde_json::Value,
    #[serde(skip)]
    pub trainer_token: String,
    pub status: Status,
    pub reason: Option<String>,
    pub progress: i64,
    pub latest: serde_json::Value,
    pub created_at: String,
    pub started_at: Option<String>,
    pub ended_at: Option<String>,
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or(serde_json::Value::Null)
}

/// A stored session's `config` column that no longer reads as a spec.
#[derive(Debug, thiserror::Error)]
#[error("the stored config of session {id}: {error}")]
pub struct StoredSpecError {
    pub id: String,
    pub error: serde_json::Error,
}

impl SessionRow {
    /// The session as launched (its `config` column).
    pub fn spec(&self) -> std::result::Result<crate::session::SessionSpec, StoredSpecError> {
        serde_json::from_value(self.config.clone()).map_err(|error| StoredSpecError {
            id: self.id.clone(),
            error,
        })
    }

    pub(super) fn from_row(r: &impl StoreRow) -> Self {
        let status: String = r.get("status");
        Self {
            id: r.get("id"),
            task: r.get("task"),
            method: r.get("method"),
            trainer: r.get("trainer"),
            seed: r.get("seed"),
            budget: r.get("budget"),
            config: json(&r.get::<String>("config")),
            trainer_token: r.get("trainer_token"),
            status: Status::parse(&status).unwrap_or(Status::Failed),
            reason: r.get("reason"),
            progress: r.get("progress"),
            latest: json(&r.get::<String>("latest")),
            created_at: r.get("created_at"),
            started_at: r.get("started_at"),
            ended_at: r.get("ended_at"),
        }
    }
}

/// A new session's row.
pub struct NewSession<'a> {
    pub id: &'a str,
    pub task: &'a str,
    pub method: &'a str,
    pub trainer: &'a str,
    pub seed: u64,
    pub budget: u64,
    pub config: &'a serde_json::Value,
    pub trainer_token: &'a str,
}

impl Store {
    pub async fn insert_session(&self, s: NewSession<'_>) -> Result<SessionRow> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "INSERT INTO sessions (id, task, method, trainer, seed, budget, config, trainer_token, status, created_at)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, 'queued', $9)",
            )
            .bind(s.id)
            .bind(s.task)
            .bind(s.method)
            .bind(s.trainer)
            .bind(s.seed as i64)
            .bind(s.budget as i64)
            .bind(s.config.to_string())
            .bind(s.trainer_token)
            .bind(&now)
            .execute(pool)
            .await?;
        });
        self.session(s.id).await?.ok_or(sqlx::Error::RowNotFound)
    }

    pub async fn session(&self, id: &str) -> Result<Option<SessionRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM sessions WHERE id = $1"
        )
        .bind(id)
        .fetch_optional(pool)
        .await?
        .as_ref()
        .map(SessionRow::from_row)))
    }

    /// All sessions, newest first.
    pub async fn sessions(&self) -> Result<Vec<SessionRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM sessions ORDER BY created_at DESC, id"
        )
        .fetch_all(pool)
        .await?
        .iter()
        .map(SessionRow::from_row)
        .collect()))
    }

    /// Sessions stored as `queued` that were launched before `row` (the places ahead of it in
    /// the queue for a slot).
    pub async fn queued_before(&self, row: &SessionRow) -> Result<i64> {
        on_db!(self.db, reader, |pool| sqlx::query_scalar(
            "SELECT COUNT(*) FROM sessions WHERE status = 'queued'
             AND (created_at < $1 OR (created_at = $1 AND id < $2))"
        )
        .bind(&row.created_at)
        .bind(&row.id)
        .fetch_one(pool)
        .await)
    }

    /// Set the status (and the reason for `failed`); terminal states stamp `ended_at`, a start
    /// stamps `started_at` once.
    pub async fn set_status(&self, id: &str, status: Status, reason: Option<&str>) -> Result<()> {
        let sql = match status {
            Status::Running => {
                "UPDATE sessions SET status = $1, reason = $2, started_at = COALESCE(started_at, $4),
                 ended_at = NULL WHERE id = $3"
            }
            Status::Queued | Status::Waiting => {
                "UPDATE sessions SET status = $1, reason = $2 WHERE id = $3"
            }
            _ => "UPDATE sessions SET status = $1, reason = $2, ended_at = $4 WHERE id = $3",
        };
        // PostgreSQL takes exactly as many arguments as the statement has placeholders.
        let stamp = (!matches!(status, Status::Queued | Status::Waiting)).then(clock::now);
        on_db!(self.db, writer, |pool| {
            let mut query = sqlx::query(sql).bind(status).bind(reason).bind(id);
            if let Some(now) = &stamp {
                query = query.bind(now);
            }
            query.execute(pool).await?;
        });
        Ok(())
    }

    pub async fn set_progress(
        &self,
        id: &str,
        progress: u64,
        latest: &serde_json::Value,
    ) -> Result<()> {
        on_db!(self.db, writer, |pool| {
            sqlx::query("UPDATE sessions SET progress = $1, latest = $2 WHERE id = $3")
                .bind(progress as i64)
                .bind(latest.to_string())
                .bind(id)
                .execute(pool)
                .await?;
        });
        Ok(())
    }

    /// At start: sessions that were running when the server went away become `interrupted`
    /// (resumable); queued ones stay queued and are started again. Returns both lists.
    pub async fn recover_after_restart(&self) -> Result<(Vec<String>, Vec<String>)> {
        let interrupted: Vec<String> = on_db!(self.db, writer, |pool| {
            sqlx::query(
                "UPDATE sessions SET status = 'interrupted',
                   reason = 'the server stopped while it ran'
                 WHERE status IN ('running', 'waiting') RETURNING id",
            )
            .fetch_all(pool)
            .await?
            .iter()
            .map(|r| r.get("id"))
            .collect()
        });
        let queued = on_db!(self.db, reader, |pool| sqlx::query(
            "SELECT id FROM sessions WHERE status = 'queued' ORDER BY created_at"
        )
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| r.get("id"))
        .collect());
        Ok((interrupted, queued))
    }
}
