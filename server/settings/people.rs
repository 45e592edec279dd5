//! The settings about who answers: how many answers a query takes and how they combine, and
//! the synthetic teacher's faults (`guidance::teacher`), a section of [`Settings`](super::Settings)
//! that both families take.

use serde::{Deserialize, Serialize};

use super::{Combine, SettingsError};
use crate::guidance::teacher::TeacherFaults;

/// `teacher_beta`: a rationality, or the word `rational` (a teacher that never errs by chance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(untagged)]
pub enum TeacherBeta {
    Rational(RationalWord),
    Value(f64),
}

/// The word `rational`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum RationalWord {
    Rational,
}

/// `teacher_skip`: a threshold, or the word `never`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(untagged)]
pub enum TeacherSkip {
    Never(NeverWord),
    Value(f64),
}

/// The word `never`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum NeverWord {
    Never,
}

/// The synthetic teacher's faults (algorithms.md section 4, after B-Pref).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct TeacherSection {
    /// Boltzmann rationality: a number, or `rational` (never errs by chance) [default].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teacher_beta: Option<TeacherBeta>,
    /// Myopic discount in (0, 1] [default 1: not myopic].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teacher_gamma: Option<f64>,
    /// Probability that an answer is flipped [default 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teacher_error: Option<f64>,
    /// Skip what is worth less than this: a number, or `never` [default].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teacher_skip: Option<TeacherSkip>,
    /// Answer "about equal" (evaluative: 0) below this margin [default 0].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teacher_equal: Option<f64>,
}

impl TeacherSection {
    /// The teacher settings at their defaults (a perfect teacher), as `GET /api/tasks` offers
    /// them.
    pub(super) fn offered() -> Self {
        Self {
            teacher_beta: Some(TeacherBeta::Rational(RationalWord::Rational)),
            teacher_gamma: Some(1.0),
            teacher_error: Some(0.0),
            teacher_skip: Some(TeacherSkip::Never(NeverWord::Never)),
            teacher_equal: Some(0.0),
        }
    }

    /// The teacher's faults, checked.
    pub(super) fn faults(&self) -> Result<TeacherFaults, SettingsError> {
        teacher_faults(self)
    }
}

fn teacher_faults(s: &TeacherSection) -> Result<TeacherFaults, SettingsError> {
    let faults = TeacherFaults {
        beta: match s.teacher_beta {
            None | Some(TeacherBeta::Rational(_)) => None,
            Some(TeacherBeta::Value(b)) => Some(b),
        },
        gamma: s.teacher_gamma.filter(|g| *g != 1.0),
        error: s.teacher_error.unwrap_or(0.0),
        skip: match s.teacher_skip {
            None | Some(TeacherSkip::Never(_)) => None,
            Some(TeacherSkip::Value(x)) => Some(x),
        },
        equal: s.teacher_equal.unwrap_or(0.0),
    };
    // gamma = 1 is "not myopic": checked like any value, then left out.
    if let Some(g) = s.teacher_gamma {
        TeacherFaults {
            gamma: Some(g),
            ..TeacherFaults::default()
        }
        .validate()
        .map_err(SettingsError::Teacher)?;
    }
    faults.validate().map_err(SettingsError::Teacher)?;
    Ok(faults)
}

/// `answers_per_query` and `combine` with their defaults: one answer, the first. More than one
/// answer needs a rule that combines them, named (`majority` or `mean` for evaluative sessions,
/// `each` for preference sessions; which family a rule fits is checked with the method).
pub(super) fn answers(
    k: Option<usize>,
    combine: Option<Combine>,
) -> Result<(usize, Combine), SettingsError> {
    let k = k.unwrap_or(1);
    if k == 0 {
        return Err(SettingsError::bad(
            "answers_per_query",
            "expected at least 1",
        ));
    }
    if k > 32 {
        return Err(SettingsError::bad(
            "answers_per_query",
            format!("at most 32, got {k}"),
        ));
    }
    match (k, combine) {
        (1, None | Some(Combine::First)) => Ok((1, Combine::First)),
        (1, Some(c)) => Err(SettingsError::bad(
            "combine",
            format!(
                "{} combines several answers; set answers_per_query above 1, or combine first",
                c.as_str()
            ),
        )),
        (_, Some(Combine::First)) => Err(SettingsError::bad(
            "combine",
            format!(
                "first takes one answer per query; with answers_per_query = {k} choose majority or mean (evaluative) or each (preference)"
            ),
        )),
        (_, None) => Err(SettingsError::NoCombineRule {
            answers_per_query: k,
        }),
        (_, Some(c)) => Ok((k, c)),
    }
}
