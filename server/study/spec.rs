//! What a researcher launches as a study: the conditions (task, method, settings), the budget of
//! each session, the survey asked after each condition, the consent text and the ordering.
//!
//! A study is validated once, when it is created: a bad condition is refused then, not when a
//! participant reaches it. [`StudySpec::session_spec`] is the one place a condition becomes a
//! session launch, so the study's sessions are launched exactly as a researcher's would be.

use serde::{Deserialize, Serialize};

use crate::session::spec::{
    DEFAULT_QUERIES, SessionMethod, SessionSpec, TrainerKind, default_steps,
};
use crate::settings::Settings;
use crate::sim::Task;

use super::{DesignError, Ordering, StudyDesign};

/// One condition a participant trains with: a task, a method and its settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Condition {
    /// How results and the researcher's pages name it (e.g. `dref`, `ef-50`, `sac`); unique
    /// within the study.
    pub name: String,
    /// What participants see instead of the name, so that a method's name cannot sway them
    /// [default: "Method A", "Method B", ... in the study's order].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    pub task: Task,
    #[schema(value_type = String, example = "dref")]
    pub method: SessionMethod,
    /// Session settings and hyper-parameters by name, as in a launch request (read into
    /// [`Settings`] when the study is validated).
    #[serde(default)]
    #[schema(value_type = Option<Object>)]
    pub params: serde_json::Value,
}

/// How long each session of the study runs: environment steps for evaluative methods, queries
/// for preference methods (the task's and Figure 5's defaults where not given).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Budget {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub queries: Option<u64>,
}

/// A survey question with a Likert scale of `points` (1 = `low`, `points` = `high`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Question {
    /// A short key for tables and exports (letters, digits, `_`).
    pub id: String,
    pub text: String,
    #[serde(default = "five")]
    pub points: u8,
    #[serde(default = "low_label")]
    pub low: String,
    #[serde(default = "high_label")]
    pub high: String,
}

impl Condition {
    /// The condition's settings, read as a launch request's are.
    fn settings(&self, index: usize) -> Result<Settings, StudySpecError> {
        match &self.params {
            serde_json::Value::Null => Ok(Settings::default()),
            params => Settings::from_json(params.clone()).map_err(|e| StudySpecError::Params {
                index,
                reason: e.to_string(),
            }),
        }
    }
}

fn five() -> u8 {
    5
}
fn low_label() -> String {
    "strongly disagree".into()
}
fn high_label() -> String {
    "strongly agree".into()
}

impl Question {
    fn likert(id: &str, text: &str) -> Self {
        Question {
            id: id.into(),
            text: text.into(),
            points: five(),
            low: low_label(),
            high: high_label(),
        }
    }
}

/// The paper's survey (Section 5.1): overall experience E, perceived intelligence I, cognitive
/// ease C, each on a 5-point scale.
pub fn paper_survey() -> Vec<Question> {
    vec![
        Question::likert(
            "E",
            "Overall, training the robot this way was a good experience.",
        ),
        Question::likert(
            "I",
            "The robot seemed intelligent: it asked at the right moments.",
        ),
        Question::likert(
            "C",
            "Training the robot this way was easy: it took little effort.",
        ),
    ]
}

/// The text a participant agrees to before anything else, when the study gives none.
pub const DEFAULT_CONSENT: &str = "You will train a simulated robot with several methods, one \
after the other, and answer a short survey after each. Your answers are stored under a \
pseudonymous participant id, never your name. You may stop at any time.";

/// A study as a researcher launches it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    pub title: String,
    pub conditions: Vec<Condition>,
    /// `williams` (balanced Latin square, first-order carry-over balanced; the default),
    /// `random` or `fixed`.
    #[serde(default)]
    #[schema(value_type = String, example = "williams")]
    pub ordering: Ordering,
    /// Seeds the `random` ordering and, with the participant's number, each session's seed.
    #[serde(default)]
    pub seed: u64,
    #[serde(default)]
    pub budget: Budget,
    /// The questions after each condition [default: the paper's E, I, C].
    #[serde(default = "paper_survey")]
    pub survey: Vec<Question>,
    #[serde(default = "default_consent")]
    pub consent: String,
    /// The two conditions whose difference the study is about (the pilot's power estimate
    /// and the results page lead with it) [default: the first two].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub main_contrast: Option<[String; 2]>,
}

fn default_consent() -> String {
    DEFAULT_CONSENT.into()
}

/// Why a [`StudySpec`] cannot be run; each names what was wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StudySpecError {
    #[error("title: must not be empty")]
    EmptyTitle,
    #[error("conditions: {0}")]
    Design(#[from] DesignError),
    #[error("conditions[{index}].name: must not be empty")]
    EmptyConditionName { index: usize },
    #[error("conditions[{index}].label: must not be empty")]
    EmptyConditionLabel { index: usize },
    #[error(
        "conditions: all must have the same kind of budget, but {evaluative:?} counts steps and {preference:?} queries"
    )]
    MixedBudgets {
        evaluative: String,
        preference: String,
    },
    #[error("survey: needs at least one question")]
    EmptySurvey,
    #[error("survey[{index}].id: {reason}")]
    QuestionId { index: usize, reason: String },
    #[error("survey[{index}].points: a scale has 2 to 11 points, got {points}")]
    QuestionPoints { index: usize, points: u8 },
    #[error("survey[{index}].text: must not be empty")]
    EmptyQuestion { index: usize },
    #[error("main_contrast: {0:?} is not a condition of the study")]
    UnknownContrast(String),
    #[error("main_contrast: names the same condition twice")]
    ContrastWithItself,
    #[error("budget.{0}: must be at least 1")]
    ZeroBudget(&'static str),
    #[error("conditions[{index}].params: {reason}")]
    Params { index: usize, reason: String },
}

impl StudySpec {
    /// The checks a study passes before it is stored.
    pub fn validate(&self) -> Result<(), StudySpecError> {
        if self.title.trim().is_empty() {
            return Err(StudySpecError::EmptyTitle);
        }
        for (index, c) in self.conditions.iter().enumerate() {
            if c.name.trim().is_empty() {
                return Err(StudySpecError::EmptyConditionName { index });
            }
            if c.label.as_ref().is_some_and(|l| l.trim().is_empty()) {
                return Err(StudySpecError::EmptyConditionLabel { index });
            }
            c.settings(index)?;
        }
        self.design().validate()?;
        let evaluative = self.conditions.iter().find(|c| !c.method.is_preference());
        let preference = self.conditions.iter().find(|c| c.method.is_preference());
        if let (Some(e), Some(p)) = (evaluative, preference) {
            return Err(StudySpecError::MixedBudgets {
                evaluative: e.name.clone(),
                preference: p.name.clone(),
            });
        }
        if self.budget.steps == Some(0) {
            return Err(StudySpecError::ZeroBudget("steps"));
        }
        if self.budget.queries == Some(0) {
            return Err(StudySpecError::ZeroBudget("queries"));
        }
        self.validate_survey()?;
        if let Some([a, b]) = &self.main_contrast {
            for name in [a, b] {
                if !self.conditions.iter().any(|c| &c.name == name) {
                    return Err(StudySpecError::UnknownContrast(name.clone()));
                }
            }
            if a == b {
                return Err(StudySpecError::ContrastWithItself);
            }
        }
        Ok(())
    }

    fn validate_survey(&self) -> Result<(), StudySpecError> {
        if self.survey.is_empty() {
            return Err(StudySpecError::EmptySurvey);
        }
        for (index, q) in self.survey.iter().enumerate() {
            let id_ok = !q.id.is_empty()
                && q.id.len() <= 32
                && q.id.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !id_ok {
                return Err(StudySpecError::QuestionId {
                    index,
                    reason: format!("{:?} must be 1-32 letters, digits or _", q.id),
                });
            }
            if self.survey[..index].iter().any(|p| p.id == q.id) {
                return Err(StudySpecError::QuestionId {
                    index,
                    reason: format!("{:?} appears twice", q.id),
                });
            }
            if !(2..=11).contains(&q.points) {
                return Err(StudySpecError::QuestionPoints {
                    index,
                    points: q.points,
                });
            }
            if q.text.trim().is_empty() {
                return Err(StudySpecError::EmptyQuestion { index });
            }
        }
        Ok(())
    }

    /// The conditions' names and the ordering, for [`StudyDesign::order_for`].
    pub fn design(&self) -> StudyDesign {
        StudyDesign {
            conditions: self.conditions.iter().map(|c| c.name.clone()).collect(),
            ordering: self.ordering,
            seed: self.seed,
        }
    }

    /// What participants see for the condition named `name` (its label, or "Method A", "Method
    /// B", ... by its place in the study); the name itself for a condition not in the study.
    pub fn label_of(&self, name: &str) -> String {
        match self.conditions.iter().position(|c| c.name == name) {
            Some(i) => self.conditions[i].label.clone().unwrap_or_else(|| {
                // Past Z, "Method 27", "Method 28", ...: studies rarely have more than a handful.
                match u8::try_from(i).ok().filter(|&i| i < 26) {
                    Some(i) => format!("Method {}", char::from(b'A' + i)),
                    None => format!("Method {}", i + 1),
                }
            }),
            None => name.to_string(),
        }
    }

    /// The condition named `name`.
    pub fn condition(&self, name: &str) -> Option<&Condition> {
        self.conditions.iter().find(|c| c.name == name)
    }

    /// The main contrast's two condition names: the given pair, else the first two.
    pub fn contrast(&self) -> [&str; 2] {
        match &self.main_contrast {
            Some([a, b]) => [a, b],
            None => [&self.conditions[0].name, &self.conditions[1].name],
        }
    }

    /// The human session participant `participant` (counted from 0) trains in condition
    /// number `index`: the condition's task, method and settings, the study's budget, and a
    /// seed of the study's own per participant (the same in all of a participant's conditions,
    /// so that the conditions differ in method only).
    pub fn session_spec(
        &self,
        index: usize,
        participant: usize,
    ) -> Result<SessionSpec, StudySpecError> {
        let condition = &self.conditions[index];
        let budget = if condition.method.is_preference() {
            self.budget.queries.unwrap_or(DEFAULT_QUERIES as u64)
        } else {
            self.budget
                .steps
                .unwrap_or_else(|| default_steps(Some(condition.task)))
        };
        Ok(SessionSpec {
            task: Some(condition.task),
            env: None,
            method: condition.method,
            trainer: TrainerKind::Human,
            seed: self
                .seed
                .wrapping_mul(1_000_003)
                .wrapping_add(participant as u64),
            budget,
            params: condition.settings(index)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn spec(value: serde_json::Value) -> Result<StudySpec, String> {
        let s: StudySpec = serde_json::from_value(value).map_err(|e| e.to_string())?;
        s.validate().map_err(|e| e.to_string())?;
        Ok(s)
    }

    fn figure4() -> serde_json::Value {
        json!({
            "title": "Reaching with people",
            "conditions": [
                {"name": "dref", "task": "reaching", "method": "dref"},
                {"name": "ef-50", "task": "reaching", "method": "ef-50"},
                {"name": "sac", "task": "reaching", "method": "sac"}
            ],
            "budget": {"steps": 3000}
        })
    }

    #[test]
    fn a_minimal_study_gets_the_papers_survey_williams_and_the_first_two_as_contrast() {
        let s = spec(figure4()).unwrap();
        assert_eq!(s.ordering, Ordering::Williams);
        let ids: Vec<&str> = s.survey.iter().map(|q| q.id.as_str()).collect();
        assert_eq!(ids, ["E", "I", "C"]);
        assert!(s.survey.iter().all(|q| q.points == 5));
        assert_eq!(s.contrast(), ["dref", "ef-50"]);
        assert_eq!(s.consent, DEFAULT_CONSENT);
        assert_eq!(s.label_of("ef-50"), "Method B");
        let session = s.session_spec(1, 4).unwrap();
        assert_eq!(session.budget, 3000);
        assert_eq!(session.trainer, TrainerKind::Human);
        assert_eq!(session.method.to_string(), "ef-50");
        // One seed per participant, the same in every condition.
        assert_eq!(session.seed, s.session_spec(0, 4).unwrap().seed);
        assert_ne!(session.seed, s.session_spec(0, 5).unwrap().seed);
    }

    #[test]
    fn participants_see_a_conditions_label_not_its_name() {
        let mut v = figure4();
        v["conditions"][2]["label"] = json!("The blue robot");
        let s = spec(v).unwrap();
        assert_eq!(s.label_of("dref"), "Method A");
        assert_eq!(s.label_of("sac"), "The blue robot");
        v = figure4();
        v["conditions"][0]["label"] = json!("  ");
        assert_eq!(
            spec(v).unwrap_err(),
            "conditions[0].label: must not be empty"
        );
    }

    #[test]
    fn each_refusal_names_what_was_wrong() {
        let mut v = figure4();
        v["conditions"][2]["name"] = json!("dref");
        assert_eq!(
            spec(v).unwrap_err(),
            "conditions: condition \"dref\" appears more than once"
        );
        let mut v = figure4();
        v["conditions"][1] = json!({"name": "drpl", "task": "reaching", "method": "drpl"});
        assert!(
            spec(v)
                .unwrap_err()
                .contains("\"dref\" counts steps and \"drpl\" queries")
        );
        let mut v = figure4();
        v["survey"] = json!([{"id": "E", "text": "ok", "points": 1}]);
        assert_eq!(
            spec(v).unwrap_err(),
            "survey[0].points: a scale has 2 to 11 points, got 1"
        );
        let mut v = figure4();
        v["survey"] = json!([{"id": "a b", "text": "ok"}]);
        assert!(spec(v).unwrap_err().starts_with("survey[0].id:"));
        let mut v = figure4();
        v["main_contrast"] = json!(["dref", "ef-25"]);
        assert_eq!(
            spec(v).unwrap_err(),
            "main_contrast: \"ef-25\" is not a condition of the study"
        );
        let mut v = figure4();
        v["conditions"][0]["params"] = json!({"no_such_setting": 1});
        assert!(spec(v).unwrap_err().contains("no_such_setting"));
        let mut v = figure4();
        v["budget"] = json!({"steps": 0});
        assert_eq!(spec(v).unwrap_err(), "budget.steps: must be at least 1");
    }

    #[test]
    fn a_researchers_own_questions_keep_their_scales() {
        let mut v = figure4();
        v["survey"] = json!([
            {"id": "trust", "text": "I trust the robot.", "points": 7,
             "low": "not at all", "high": "completely"}
        ]);
        let s = spec(v).unwrap();
        assert_eq!(s.survey[0].points, 7);
        assert_eq!(s.survey[0].low, "not at all");
    }
}
