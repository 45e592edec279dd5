//! The rule a session combines several trainers' answers to one query by, as a setting
//! (`combine`). What each rule does with the answers is `session::combine`'s, beside the
//! session's answer types.

use serde::{Deserialize, Serialize};

/// The rule a session combines its trainers' answers by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// One answer per query: the first committed wins (the others get `already_answered`).
    #[default]
    First,
    /// Evaluative: the value most trainers gave; a tie is 0 ("no feedback").
    Majority,
    /// Evaluative: the mean of the +1 / 0 / -1 answers (a fraction when they differ).
    Mean,
    /// Preference: every answer is its own observation of the belief.
    Each,
}

impl Combine {
    pub fn as_str(self) -> &'static str {
        match self {
            Combine::First => "first",
            Combine::Majority => "majority",
            Combine::Mean => "mean",
            Combine::Each => "each",
        }
    }
}
