//! The `checkpoints` table: a session's progress and its learner's digest at that point (the
//! weights themselves go to a file in the data dir).

use serde::Serialize;
use sqlx::Row;

use super::{Result, Store};

#[derive(Clone, Debug, Serialize)]
pub struct CheckpointRow {
    pub progress: i64,
    pub answers: i64,
    pub digest: String,
    pub file: Option<String>,
    pub created_at: String,
}

impl Store {
    pub async fn insert_checkpoint(
        &self,
        session_id: &str,
        progress: u64,
        answers: u64,
        digest: &str,
        file: Option<&str>,
    ) -> Result<()> {
        sqlx::query(concat!(
            "INSERT OR REPLACE INTO checkpoints (session_id, progress, answers, digest, file, created_at)
             VALUES (?, ?, ?, ?, ?, ", now!(), ")"
        ))
        .bind(session_id)
        .bind(progress as i64)
        .bind(answers as i64)
        .bind(digest)
        .bind(file)
        .execute(self.writer())
        .await?;
        Ok(())
    }

    /// The latest checkpoint whose answers are all stored (a resume replays up to it).
    pub async fn latest_checkpoint(&self, session_id: &str) -> Result<Option<CheckpointRow>> {
        let row = sqlx::query(
            "SELECT * FROM checkpoints WHERE session_id = ? ORDER BY progress DESC LIMIT 1",
        )
        .bind(session_id)
        .fetch_optional(self.pool())
        .await?;
        Ok(row.map(|r| CheckpointRow {
            progress: r.get("progress"),
            answers: r.get("answers"),
            digest: r.get("digest"),
            file: r.get("file"),
            created_at: r.get("created_at"),
        }))
    }
}
