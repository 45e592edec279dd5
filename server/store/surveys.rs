//! The `surveys` table: a trainer's answers to the paper's three 5-point questions.

use super::backend::StoreRow;
use super::{Result, Store, clock};
use serde::{Deserialize, Serialize};

/// Overall experience, perceived intelligence of the robot, cognitive ease: each 1 to 5.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Survey {
    pub overall_experience: u8,
    pub perceived_intelligence: u8,
    pub cognitive_ease: u8,
}

/// A survey answer out of its 1-to-5 scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{question} must be 1 to 5, got {value}")]
pub struct SurveyError {
    pub question: &'static str,
    pub value: u8,
}

impl Survey {
    pub fn validate(&self) -> std::result::Result<(), SurveyError> {
        for (name, v) in [
            ("overall_experience", self.overall_experience),
            ("perceived_intelligence", self.perceived_intelligence),
            ("cognitive_ease", self.cognitive_ease),
        ] {
            if !(1..=5).contains(&v) {
                return Err(SurveyError {
                    question: name,
                    value: v,
                });
            }
        }
        Ok(())
    }
}

impl Store {
    /// Store (or replace: a trainer may change their mind) the survey of a session.
    pub async fn save_survey(&self, session_id: &str, s: &Survey) -> Result<()> {
        let now = clock::now();
        on_db!(self.db, writer, |pool| {
            sqlx::query(
                "INSERT INTO surveys
                 (session_id, overall_experience, perceived_intelligence, cognitive_ease, answered_at)
                 VALUES ($1, $2, $3, $4, $5)
                 ON CONFLICT (session_id) DO UPDATE SET
                   overall_experience = excluded.overall_experience,
                   perceived_intelligence = excluded.perceived_intelligence,
                   cognitive_ease = excluded.cognitive_ease,
                   answered_at = excluded.answered_at",
            )
            .bind(session_id)
            .bind(i64::from(s.overall_experience))
            .bind(i64::from(s.perceived_intelligence))
            .bind(i64::from(s.cognitive_ease))
            .bind(&now)
            .execute(pool)
            .await?;
        });
        Ok(())
    }

    pub async fn survey(&self, session_id: &str) -> Result<Option<Survey>> {
        on_db!(self.db, reader, |pool| Ok(sqlx::query(
            "SELECT * FROM surveys WHERE session_id = $1"
        )
        .bind(session_id)
        .fetch_optional(pool)
        .await?
        .map(|r| Survey {
            overall_experience: r.get::<i64>("overall_experience") as u8,
            perceived_intelligence: r.get::<i64>("perceived_intelligence") as u8,
            cognitive_ease: r.get::<i64>("cognitive_ease") as u8,
        })))
    }
}
