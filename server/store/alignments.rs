//! The `alignments` table: a preference session's alignment curve (the dashboard's plot, and
//! Figure 5's measure for a session).

use super::backend::StoreRow;
use super::{Result, Store};
use serde::Serialize;

/// The posterior after `queries` queries.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, utoipa::ToSchema)]
pub struct AlignmentRow {
    pub queries: i64,
    pub alignment: f64,
    pub alignment_of_mean: f64,
}

impl Store {
    /// Store the alignment after `queries` queries (replacing an earlier one at the same count:
    /// an undo changes the posterior without a new query).
    pub async fn record_alignment(&self, session_id: &str, a: AlignmentRow) -> Result<()> {
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "INSERT INTO alignments (session_id, queries, alignment, alignment_of_mean)
                 VALUES ($1, $2, $3, $4)
                 ON CONFLICT (session_id, queries) DO UPDATE SET
                   alignment = excluded.alignment,
                   alignment_of_mean = excluded.alignment_of_mean",
            )
            .bind(session_id)
            .bind(a.queries)
            .bind(a.alignment)
            .bind(a.alignment_of_mean)
            .execute(pool)
            .await?;
        });
        Ok(())
    }

    /// The curve, by query count.
    pub async fn alignment(&self, session_id: &str) -> Result<Vec<AlignmentRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT queries, alignment, alignment_of_mean FROM alignments
             WHERE session_id = $1 ORDER BY queries",
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| AlignmentRow {
            queries: r.get("queries"),
            alignment: r.get("alignment"),
            alignment_of_mean: r.get("alignment_of_mean"),
        })
        .collect()))
    }
}
