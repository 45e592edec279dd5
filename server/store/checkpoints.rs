//! The `checkpoints` table: a session's progress and its learner's digest at that point (the
//! weights themselves go to a file in the data dir).

use super::backend::StoreRow;
use super::{Result, Store, clock};
use serde::Serialize;

#[derive(Clone, Debug, Serialize)]
pub struct CheckpointRow {
    pub progress: i64,
    pub answers: i64,
    pub digest: String,
    pub file: Option<String>,
    pub created_at: String,
}

impl Store {
    /// Store a checkpoint (again at the same progress, after a resumed session's replay:
    /// replacing the row).
    pub async fn insert_checkpoint(
        &self,
        session_id: &str,
        progress: u64,
        answers: u64,
        digest: &str,
        file: Option<&str>,
    ) -> Result<()> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "INSERT INTO checkpoints (session_id, progress, answers, digest, file, created_at)
                 VALUES ($1, $2, $3, $4, $5, $6)
                 ON CONFLICT (session_id, progress) DO UPDATE SET
                   answers = excluded.answers,
                   digest = excluded.digest,
                   file = excluded.file,
                   created_at = excluded.created_at",
            )
            .bind(session_id)
            .bind(progress as i64)
            .bind(answers as i64)
            .bind(digest)
            .bind(file)
            .bind(&now)
            .execute(pool)
            .await?;
        });
        Ok(())
    }

    /// The latest checkpoint whose answers are all stored (a resume replays up to it).
    pub async fn latest_checkpoint(&self, session_id: &str) -> Result<Option<CheckpointRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM checkpoints WHERE session_id = $1 ORDER BY progress DESC LIMIT 1",
        )
        .bind(session_id)
        .fetch_optional(pool)
        .await?
        .map(|r| CheckpointRow {
            progress: r.get("progress"),
            answers: r.get("answers"),
            digest: r.get("digest"),
            file: r.get("file"),
            created_at: r.get("created_at"),
        })))
    }
}
