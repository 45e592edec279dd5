//! Why settings are refused: [`SettingsError`], each variant naming the key and what was wrong.
//! Its text is what users read (`--set`, a launch's 422, a stored session that no longer reads),
//! so it does not change with the type.

use serde::de;

use super::Family;
use crate::guidance::teacher::TeacherError;

/// Why settings do not read or do not apply to a run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// The settings are not a JSON object.
    #[error("invalid type: {found}, expected struct Settings")]
    NotAnObject {
        /// How serde names what was given (`integer `3``).
        found: String,
    },
    /// A key no section reads, refused with the list of known keys as serde words it.
    #[error("{key}: {}", unknown_field(.key, .known))]
    UnknownKey {
        key: String,
        known: &'static [&'static str],
    },
    /// A value that does not read as its key's type, in serde's words (no key: the object as
    /// a whole).
    #[error("{}{reason}", .key.as_deref().map(|k| format!("{k}: ")).unwrap_or_default())]
    Unreadable { key: Option<String>, reason: String },
    /// A value out of its key's range, or that contradicts another setting.
    #[error("{key}: {problem}")]
    BadValue { key: &'static str, problem: String },
    /// A setting of the other family's methods.
    #[error("{key} is a setting of {}, not {method}", .family.methods())]
    WrongFamily {
        key: &'static str,
        /// The family the key belongs to.
        family: Family,
        /// The run's method.
        method: String,
    },
    /// A setting of other tasks than the run's.
    #[error("{key} applies to {applies_to}{}", .task.as_deref().map(|t| format!(", not {t}")).unwrap_or_default())]
    WrongTask {
        key: &'static str,
        /// The tasks it applies to (`placing only`).
        applies_to: &'static str,
        /// The run's task, where the message names it.
        task: Option<String>,
    },
    /// A setting other than the task's version where only the version can be set (`dualrep
    /// sim`).
    #[error("only the task's version can be set here: {}", .allowed.join(", "))]
    OnlyEnv { allowed: &'static [&'static str] },
    /// Several answers per query and no rule to combine them.
    #[error(
        "answers_per_query = {answers_per_query} needs a combine rule: majority or mean (evaluative), each (preference)"
    )]
    NoCombineRule { answers_per_query: usize },
    /// The synthetic teacher's faults out of range, in the teacher's own words (they name the
    /// key).
    #[error("{0}")]
    Teacher(TeacherError),
    /// Settings that did not serialize for merging.
    #[error("{0}")]
    Serialize(String),
}

impl SettingsError {
    /// `key: problem`.
    pub(super) fn bad(key: &'static str, problem: impl Into<String>) -> Self {
        SettingsError::BadValue {
            key,
            problem: problem.into(),
        }
    }

    /// The key the error names, where it names one.
    pub fn key(&self) -> Option<&str> {
        match self {
            SettingsError::UnknownKey { key, .. } => Some(key),
            SettingsError::Unreadable { key, .. } => key.as_deref(),
            SettingsError::BadValue { key, .. }
            | SettingsError::WrongFamily { key, .. }
            | SettingsError::WrongTask { key, .. } => Some(key),
            SettingsError::NoCombineRule { .. } => Some("answers_per_query"),
            SettingsError::NotAnObject { .. }
            | SettingsError::OnlyEnv { .. }
            | SettingsError::Teacher(_)
            | SettingsError::Serialize(_) => None,
        }
    }
}

impl Family {
    /// The family's methods, as a refusal names them.
    fn methods(self) -> &'static str {
        match self {
            Family::Evaluative => "evaluative methods (dref, ef-<p>, sac)",
            Family::Preference => "preference methods (drpl, drpl-mi, drpl-ss, fragment, full)",
        }
    }
}

/// serde's words for an unknown field.
fn unknown_field(key: &str, known: &'static [&'static str]) -> String {
    <serde_json::Error as de::Error>::unknown_field(key, known).to_string()
}
