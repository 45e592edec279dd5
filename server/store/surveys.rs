//! The `surveys` table: a trainer's answers to the paper's three 5-point questions.

use serde::{Deserialize, Serialize};
use sqlx::Row;

use super::{Result, Store};

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
        sqlx::query(concat!(
            "INSERT OR REPLACE INTO surveys
             (session_id, overall_experience, perceived_intelligence, cognitive_ease, answered_at)
             VALUES (?, ?, ?, ?, ",
            now!(),
            ")"
        ))
        .bind(session_id)
        .bind(i64::from(s.overall_experience))
        .bind(i64::from(s.perceived_intelligence))
        .bind(i64::from(s.cognitive_ease))
        .execute(self.writer())
        .await?;
        Ok(())
    }

    pub async fn survey(&self, session_id: &str) -> Result<Option<Survey>> {
        let row = sqlx::query("SELECT * FROM surveys WHERE session_id = ?")
            .bind(session_id)
            .fetch_optional(self.pool())
            .await?;
        Ok(row.map(|r| Survey {
            overall_experience: r.get::<i64, _>("overall_experience") as u8,
            perceived_intelligence: r.get::<i64, _>("perceived_intelligence") as u8,
            cognitive_ease: r.get::<i64, _>("cognitive_ease") as u8,
        }))
    }
}
