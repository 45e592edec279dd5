//! What a session's datasets are made of: every answered query with what the learner saw there
//! (`queries.data`) and the answer that stands, in the order asked, and the latest checkpoint's
//! file (the learner's weights, or a preference session's posterior).

use super::backend::StoreRow;
use super::queries::parse_value;
use super::{Result, Store};
use crate::session::{AnswerValue, Answerer, QueryData};

/// One answered query of a session, for datasets.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetRow {
    /// The session's query number.
    pub query_id: i64,
    pub step: i64,
    pub abstract_state: i64,
    /// What the learner saw (`None` for queries stored before it was kept).
    pub data: Option<QueryData>,
    pub value: AnswerValue,
    pub who: Answerer,
    /// The named trainer who gave it.
    pub trainer: Option<String>,
    pub latency_ms: i64,
}

impl Store {
    /// Every answered query of a session with what the learner saw, in the order asked: the
    /// rows of `GET .../answers`, one each.
    pub async fn dataset_rows(&self, session_id: &str) -> Result<Vec<DatasetRow>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT q.seq, q.step, q.abstract_state, q.data, a.value, a.who, a.latency_ms, t.name
             FROM answers a JOIN queries q ON q.id = a.query_id
             LEFT JOIN trainers t ON t.id = a.trainer_id
             WHERE a.session_id = $1 ORDER BY q.seq",
        )
        .bind(session_id)
        .fetch_all(pool)
        .await?
        .iter()
        .map(|r| DatasetRow {
            query_id: r.get("seq"),
            step: r.get("step"),
            abstract_state: r.get("abstract_state"),
            data: r
                .get::<Option<String>>("data")
                .and_then(|d| serde_json::from_str(&d).ok()),
            value: parse_value(&r.get::<String>("value")),
            who: r.get("who"),
            trainer: r.get("name"),
            latency_ms: r.get("latency_ms"),
        })
        .collect()))
    }
}
