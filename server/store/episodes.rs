//! The `episodes` table: one row per finished episode of an evaluative session.

use super::backend::StoreRow;
use super::{Result, Store};
use crate::guidance::evaluative_run::EpisodeRecord;
use serde::Serialize;

/// One finished episode, as `GET /api/sessions/{id}/episodes` lists it.
#[derive(Clone, Debug, Serialize, utoipa::ToSchema)]
pub struct EpisodeRow {
    /// 0-based episode index.
    pub episode: i64,
    /// The run's environment steps when the episode ended.
    pub step: i64,
    /// This episode's return.
    #[serde(rename = "return")]
    pub episode_return: f64,
    /// This episode's steps.
    pub length: i64,
    /// A running total: the returns of every episode so far, this one included.
    pub cumulative_return: f64,
    /// A running total: queries asked since the session started (not in this episode alone).
    pub feedback_count: i64,
    /// A running total: `feedback_count / step`, the share of all steps so far that were asked.
    pub feedback_fraction: f64,
    pub outcome: String,
}

impl Store {
    /// Store an episode; a resumed session's replay stores the same episodes again, which
    /// replaces them with identical rows.
    pub async fn insert_episode(&self, session_id: &str, e: &EpisodeRecord) -> Result<()> {
        let outcome = serde_json::to_value(e.outcome)
            .ok()
            .and_then(|v| v.as_str().map(str::to_owned))
            .unwrap_or_default();
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "INSERT INTO episodes
                 (session_id, episode, step, return, length, cumulative_return, feedback_count, feedback_fraction, outcome)
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9)
                 ON CONFLICT (session_id, episode) DO UPDATE SET
                   step = excluded.step,
                   return = excluded.return,
                   length = excluded.length,
                   cumulative_return = excluded.cumulative_return,
                   feedback_count = excluded.feedback_count,
                   feedback_fraction = excluded.feedback_fraction,
                   outcome = excluded.outcome",
            )
            .bind(session_id)
            .bind(e.episode as i64)
            .bind(e.step as i64)
            .bind(e.episode_return)
            .bind(i64::from(e.length))
            .bind(e.cumulative_return)
            .bind(e.feedback_count as i64)
            .bind(e.feedback_fraction)
            .bind(&outcome)
            .execute(pool)
            .await?;
        });
        Ok(())
    }

    pub async fn episodes(&self, session_id: &str) -> Result<Vec<EpisodeRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM episodes WHERE session_id = $1 ORDER BY episode"
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| EpisodeRow {
            episode: r.get("episode"),
            step: r.get("step"),
            episode_return: r.get("return"),
            length: r.get("length"),
            cumulative_return: r.get("cumulative_return"),
            feedback_count: r.get("feedback_count"),
            feedback_fraction: r.get("feedback_fraction"),
            outcome: r.get("outcome"),
        })
        .collect()))
    }
}
