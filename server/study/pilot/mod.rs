//! `dualrep study pilot`: a power estimate before anyone is recruited. The study's design is
//! run with simulated participants instead of people, and for each study size n (default 4, 6,
//! 8, 12, 16) the report says in what share of simulated studies the main contrast comes out
//! significant.
//!
//! 1. A [`PilotSpec`] (a TOML or JSON file): the study exactly as a researcher launches it
//!    (`study`, a [`StudySpec`] inline or the path of its file), the ranges each simulated
//!    teacher's settings are drawn from (`teachers`: `teacher_beta = [0.5, 5.0]` draws uniformly,
//!    `teacher_error = 0.1` fixes a value; [`teachers`]), the pool's size (`participants`,
//!    default the largest n), the sizes `ns`, `studies` per size (default 1000), `alpha`
//!    (default 0.05) and a `seed` (default the study's).
//! 2. A pool of simulated participants, each with a teacher drawn for them, trains every
//!    condition: the session a person would have ([`StudySpec::session_spec`]: the study's
//!    budget, one seed per participant), answered by the synthetic teacher with the drawn
//!    settings added to the condition's (which, being a study's, has no teacher settings). A DREF condition keeps the pace of a person's
//!    session (`max_queries_per_minute`), so that what is simulated is what people will do.
//!    Each participant's order (Williams by default) is recorded; it changes nothing in a
//!    simulation, where no one learns or tires. ([`simulate`]; training is all the cost.)
//! 3. Power by resampling the pool ([`power`]): the bootstrap (with replacement, any n,
//!    optimistic when the pool is small) and the subsample (n distinct participants, n <= pool).
//!    The test is the two-sided Wilcoxon signed-rank test on the main contrast's paired scores
//!    (the cumulative reward of Figure 4, or the alignment of Figure 6 for preference
//!    studies), p < alpha; Friedman's share too with three or more conditions.
//! 4. The report ([`report`]): `pilot.json`, `pilot.md` and `participants.csv` (every
//!    participant's teacher, order and scores).
//!
//! Everything here is pure but for the threads that train; the command (`cli::study`) reads
//! the file, loads the experts and writes the report.

pub mod power;
pub mod report;
pub mod simulate;
pub mod teachers;

use serde::Deserialize;
use serde_json::{Map, Value};

use crate::session::plan::{RunConfig, SessionPlan};
use crate::session::spec::TrainerKind;
use crate::settings::Settings;

use self::simulate::PilotRun;
use self::teachers::{RangeError, TeacherRanges};
use super::{StudySpec, StudySpecError};

/// The study sizes a pilot reports when the file and the command name none.
pub const DEFAULT_NS: [usize; 5] = [4, 6, 8, 12, 16];
/// Simulated studies per size.
pub const DEFAULT_STUDIES: usize = 1000;
pub const DEFAULT_ALPHA: f64 = 0.05;
/// The largest pool and study size a pilot takes (each participant trains every condition).
pub const MAX_PARTICIPANTS: usize = 1000;
pub const MAX_STUDIES: usize = 1_000_000;

/// How a pilot file is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Json,
    Toml,
}

impl Format {
    /// The format a file's extension names (`.json`, `.toml`).
    pub fn of_extension(extension: &str) -> Option<Format> {
        match extension.to_ascii_lowercase().as_str() {
            "json" => Some(Format::Json),
            "toml" => Some(Format::Toml),
            _ => None,
        }
    }
}

/// Why a pilot cannot run; the text names the field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PilotError {
    #[error("{0}")]
    Syntax(String),
    #[error("study.{0}")]
    Study(StudySpecError),
    #[error(transparent)]
    Teachers(#[from] RangeError),
    #[error("{field}: {reason}")]
    Field { field: &'static str, reason: String },
    /// A session of the study that does not build with the synthetic teacher.
    #[error("study.conditions[{index}] ({name}), simulated participant {participant}: {reason}")]
    Session {
        index: usize,
        name: String,
        participant: usize,
        reason: String,
    },
}

fn field(field: &'static str, reason: impl Into<String>) -> PilotError {
    PilotError::Field {
        field,
        reason: reason.into(),
    }
}

/// A pilot file as written: the study inline or as a path, the rest optional.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PilotFile {
    /// The study as a researcher POSTs it, or the path of its JSON or TOML file (relative to
    /// the pilot file).
    pub study: Value,
    #[serde(default)]
    pub teachers: Map<String, Value>,
    pub participants: Option<usize>,
    pub ns: Option<Vec<usize>>,
    pub studies: Option<usize>,
    pub alpha: Option<f64>,
    pub seed: Option<u64>,
}

/// What the command line puts over the file.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    pub participants: Option<usize>,
    pub ns: Option<Vec<usize>>,
    pub studies: Option<usize>,
    pub seed: Option<u64>,
}

/// Parse a JSON or TOML text as a JSON value (errors name where it went wrong).
pub fn parse_value(text: &str, format: Format) -> Result<Value, PilotError> {
    match format {
        Format::Json => {
            crate::json_input::from_str(text).map_err(|e| PilotError::Syntax(e.to_string()))
        }
        Format::Toml => {
            let table: toml::Table = text
                .parse()
                .map_err(|e: toml::de::Error| PilotError::Syntax(e.to_string()))?;
            serde_json::to_value(table).map_err(|e| PilotError::Syntax(e.to_string()))
        }
    }
}

/// `value` read as a `T`, an error naming the field under `prefix` (`study.budget.steps: ...`).
fn read<T: serde::de::DeserializeOwned>(value: Value, prefix: &str) -> Result<T, PilotError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let at = match (prefix, path.as_str()) {
            ("", ".") => String::new(),
            ("", path) => format!("{path}: "),
            (prefix, ".") => format!("{prefix}: "),
            (prefix, path) => format!("{prefix}.{path}: "),
        };
        PilotError::Syntax(format!("{at}{}", e.into_inner()))
    })
}

impl PilotFile {
    pub fn parse(text: &str, format: Format) -> Result<PilotFile, PilotError> {
        Self::from_value(parse_value(text, format)?)
    }

    /// A pilot file already read as JSON.
    pub fn from_value(value: Value) -> Result<PilotFile, PilotError> {
        read(value, "")
    }

    /// The study's file, when `study` names one instead of holding it.
    pub fn study_path(&self) -> Option<&str> {
        self.study.as_str()
    }
}

/// A pilot, checked: what [`PilotSpec::runs`] trains and [`power::estimate`] resamples.
#[derive(Clone, Debug, PartialEq)]
pub struct PilotSpec {
    pub study: StudySpec,
    pub teachers: TeacherRanges,
    /// The pool's size P: simulated participants who train every condition.
    pub participants: usize,
    /// Study sizes, ascending, each once.
    pub ns: Vec<usize>,
    /// Simulated studies per size.
    pub studies: usize,
    pub alpha: f64,
    /// Seeds the teachers' draws and the resampling.
    pub seed: u64,
}

impl PilotSpec {
    /// The pilot of `file`, whose study is `study` (the file's own, or the one its path
    /// names), with the command line's `overrides` over it; every field checked.
    pub fn new(file: PilotFile, study: Value, overrides: Overrides) -> Result<Self, PilotError> {
        let study: StudySpec = read(study, "study")?;
        study.validate().map_err(PilotError::Study)?;
        let teachers = TeacherRanges::from_json(&file.teachers)?;
        let mut ns = overrides
            .ns
            .or(file.ns)
            .unwrap_or_else(|| DEFAULT_NS.to_vec());
        if ns.is_empty() {
            return Err(field("ns", "give at least one study size"));
        }
        if let Some(n) = ns.iter().find(|n| !(2..=MAX_PARTICIPANTS).contains(*n)) {
            return Err(field(
                "ns",
                format!("a study has 2 to {MAX_PARTICIPANTS} participants, got {n}"),
            ));
        }
        ns.sort_unstable();
        ns.dedup();
        let largest = *ns.last().expect("not empty");
        let participants = overrides
            .participants
            .or(file.participants)
            .unwrap_or(largest);
        if !(2..=MAX_PARTICIPANTS).contains(&participants) {
            return Err(field(
                "participants",
                format!(
                    "the pool has 2 to {MAX_PARTICIPANTS} simulated participants, got {participants}"
                ),
            ));
        }
        let studies = overrides
            .studies
            .or(file.studies)
            .unwrap_or(DEFAULT_STUDIES);
        if !(1..=MAX_STUDIES).contains(&studies) {
            return Err(field(
                "studies",
                format!("1 to {MAX_STUDIES} simulated studies per size, got {studies}"),
            ));
        }
        let alpha = file.alpha.unwrap_or(DEFAULT_ALPHA);
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(field(
                "alpha",
                format!("expected a level in (0, 1), got {alpha}"),
            ));
        }
        let seed = overrides.seed.or(file.seed).unwrap_or(study.seed);
        Ok(PilotSpec {
            study,
            teachers,
            participants,
            ns,
            studies,
            alpha,
            seed,
        })
    }

    /// The main contrast's two condition indices.
    pub fn contrast(&self) -> [usize; 2] {
        self.study.contrast().map(|name| {
            self.study
                .conditions
                .iter()
                .position(|c| c.name == name)
                .expect("validated: the contrast names conditions")
        })
    }

    /// Participant `participant`'s teacher settings.
    pub fn teacher(&self, participant: usize) -> Map<String, Value> {
        self.teachers.draw(self.seed, participant)
    }

    /// Every session of the pool, participant by participant, each participant's conditions
    /// in their order; each checked as a launch is.
    pub fn runs(&self) -> Result<Vec<PilotRun>, PilotError> {
        let design = self.study.design();
        let mut runs = Vec::new();
        for participant in 0..self.participants {
            let teacher = Settings::from_json(Value::Object(self.teacher(participant)))
                .expect("each end of each range was checked");
            for (position, name) in design.order_for(participant).into_iter().enumerate() {
                let index = design
                    .conditions
                    .iter()
                    .position(|c| c == name)
                    .expect("the order names the design's conditions");
                runs.push(self.run(index, participant, position, &teacher)?);
            }
        }
        Ok(runs)
    }

    fn run(
        &self,
        index: usize,
        participant: usize,
        position: usize,
        teacher: &Settings,
    ) -> Result<PilotRun, PilotError> {
        let refusal = |reason: String| PilotError::Session {
            index,
            name: self.study.conditions[index].name.clone(),
            participant,
            reason,
        };
        let person = self
            .study
            .session_spec(index, participant)
            .map_err(|e| refusal(e.to_string()))?;
        // The person's own session, for the pace DREF would ask at.
        let paced = SessionPlan::new(person.clone()).map_err(|e| refusal(e.to_string()))?;
        let mut simulated = person;
        simulated.trainer = TrainerKind::Synthetic;
        simulated.params = simulated
            .params
            .merged(teacher.clone())
            .map_err(|e| refusal(e.to_string()))?;
        let budget = simulated.budget;
        let seed = simulated.seed;
        let mut config = SessionPlan::new(simulated)
            .map_err(|e| refusal(e.to_string()))?
            .run;
        if let (RunConfig::Evaluative(c), RunConfig::Evaluative(p)) = (&mut config, &paced.run) {
            c.human_pace = p.human_pace;
        }
        Ok(PilotRun {
            participant,
            condition: index,
            position,
            seed,
            budget,
            config,
        })
    }
}

#[cfg(test)]
#[path = "tests.rs"]
mod tests;
