//! What a session is: task, method, trainer kind, seed, budget and parameters, as launched over
//! REST and stored (as JSON) with the session. It is read and checked once, into a
//! [`SessionPlan`](super::plan::SessionPlan), so that a session that was accepted can always be
//! built again on resume.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::remote_env::RemoteTarget;
use crate::settings::Settings;
use crate::sim::Task;

use super::events::QueryKind;

pub use crate::settings::{
    DEFAULT_ANSWER_TIMEOUT_S, DEFAULT_CHECKPOINT_EVERY, DEFAULT_CLIP_FRAMES, DEFAULT_ENV_TIMEOUT_S,
    DEFAULT_PACE_HZ, SessionSettings,
};

/// What the store and the API call a session on a remote env's own task.
pub const REMOTE_TASK: &str = "remote";

/// Preference queries when the launch request names none (Figure 5's budget).
pub const DEFAULT_QUERIES: usize = 40;

/// Environment steps of an evaluative session whose launch names none: the paper's for the task
/// (a remote env's own task gets Reaching's).
pub fn default_steps(task: Option<Task>) -> u64 {
    match task {
        Some(Task::LunarLander) => 150_000,
        Some(Task::Reaching | Task::Placing) | None => 100_000,
    }
}

/// Who answers the session's queries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum TrainerKind {
    /// People in browsers, at a watchable pace.
    Human,
    /// The paper's synthetic trainers (expert oracle, theta_true oracle), at full speed.
    Synthetic,
}

/// The method: evaluative feedback (DREF, EF-p%, SAC) or preferences (DRPL and its baselines).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SessionMethod {
    Evaluative(EvaluativeMethod),
    Preference(QueryMethod),
}

impl SessionMethod {
    pub fn is_preference(self) -> bool {
        matches!(self, SessionMethod::Preference(_))
    }

    /// What the budget counts: environment steps or queries.
    pub fn budget_unit(self) -> &'static str {
        if self.is_preference() {
            "queries"
        } else {
            "steps"
        }
    }

    /// The kind of query this method asks, as the API and the database name it.
    pub fn query_kind(self) -> QueryKind {
        match self {
            SessionMethod::Evaluative(_) => QueryKind::Evaluative,
            SessionMethod::Preference(_) => QueryKind::Preference,
        }
    }
}

impl fmt::Display for SessionMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SessionMethod::Evaluative(m) => write!(f, "{m}"),
            SessionMethod::Preference(m) => f.write_str(m.id()),
        }
    }
}

/// A method name that is none of ours (the name as given).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown method {0:?}: expected dref, ef-<percent>, sac, drpl, drpl-mi, drpl-ss, fragment or full"
)]
pub struct UnknownMethod(pub String);

impl FromStr for SessionMethod {
    type Err = UnknownMethod;

    fn from_str(s: &str) -> Result<Self, UnknownMethod> {
        if let Ok(m) = s.parse::<QueryMethod>() {
            return Ok(SessionMethod::Preference(m));
        }
        s.parse::<EvaluativeMethod>()
            .map(SessionMethod::Evaluative)
            .map_err(|_| UnknownMethod(s.to_string()))
    }
}

impl Serialize for SessionMethod {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for SessionMethod {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// A session as launched, after defaults: everything needed to build it again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionSpec {
    /// The built-in task; with `env`, the task the remote env stands in for (its scene graph,
    /// features and expert). `None` with `env`: the task the env declares about itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<Task>,
    /// An environment in another process (`docs/env-protocol.md`) instead of our simulator.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub env: Option<RemoteTarget>,
    pub method: SessionMethod,
    pub trainer: TrainerKind,
    pub seed: u64,
    /// Environment steps (evaluative methods) or queries (preference methods).
    pub budget: u64,
    /// Session settings and hyper-parameters, as given (the rest keep their defaults).
    #[serde(default)]
    pub params: Settings,
}

impl SessionSpec {
    /// The task's name as the store and the API show it: ours, or `remote` for a remote env's
    /// own task.
    pub fn task_name(&self) -> &'static str {
        self.task.map_or(REMOTE_TASK, Task::id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guidance::human_pace::{HumanPace, PEOPLE_QUERIES_PER_MINUTE};
    use crate::session::plan::{PlanError, RunConfig, SessionPlan};
    use crate::settings::SettingsError;
    use serde_json::json;

    fn spec(method: &str, params: serde_json::Value) -> SessionSpec {
        SessionSpec {
            task: Some(Task::Reaching),
            env: None,
            method: method.parse().unwrap(),
            trainer: TrainerKind::Human,
            seed: 1,
            budget: 100,
            params: Settings::from_json(params).unwrap(),
        }
    }

    impl SessionSpec {
        fn plan(&self) -> Result<SessionPlan, crate::session::plan::PlanError> {
            SessionPlan::new(self.clone())
        }
    }

    #[test]
    fn a_persons_dref_session_asks_at_a_persons_pace_unless_told_otherwise() {
        let pace = |method: &str, trainer: TrainerKind, params: serde_json::Value| {
            let mut s = spec(method, params);
            s.trainer = trainer;
            match s.run_config_on(None).unwrap() {
                RunConfig::Evaluative(c) => c.human_pace,
                RunConfig::Preference(_) => unreachable!(),
            }
        };
        let person = Some(HumanPace::new(PEOPLE_QUERIES_PER_MINUTE, 20.0));
        assert_eq!(pace("dref", TrainerKind::Human, json!({})), person);
        assert_eq!(
            pace("dref", TrainerKind::Human, json!({"pace_hz": 10})),
            Some(HumanPace::new(30, 10.0))
        );
        assert_eq!(
            pace(
                "dref",
                TrainerKind::Human,
                json!({"max_queries_per_minute": 12})
            ),
            Some(HumanPace::new(12, 20.0))
        );
        // Told otherwise: no pace at all, as the paper ran.
        assert_eq!(
            pace(
                "dref",
                TrainerKind::Human,
                json!({"max_queries_per_minute": 0})
            ),
            None
        );
        // The synthetic trainer, the authors' rule and EF keep their own pace.
        assert_eq!(pace("dref", TrainerKind::Synthetic, json!({})), None);
        assert_eq!(pace("dref-authors", TrainerKind::Human, json!({})), None);
        assert_eq!(pace("ef-100", TrainerKind::Human, json!({})), None);
    }

    #[test]
    fn methods_parse_into_their_family() {
        assert!("drpl-ss".parse::<SessionMethod>().unwrap().is_preference());
        assert!(!"ef-12.5".parse::<SessionMethod>().unwrap().is_preference());
        assert_eq!(
            "ef-50".parse::<SessionMethod>().unwrap().to_string(),
            "ef-50"
        );
        let e = "best".parse::<SessionMethod>().unwrap_err();
        assert_eq!(e, UnknownMethod("best".into()));
        assert!(e.to_string().contains("dref"));
    }

    #[test]
    fn a_spec_validates_its_settings_for_its_method() {
        assert_eq!(
            SessionPlan::new(spec("dref", json!({})))
                .unwrap()
                .settings
                .pace_hz,
            DEFAULT_PACE_HZ
        );
        assert!(
            spec("dref", json!({"pace_hz": -1}))
                .plan()
                .unwrap_err()
                .to_string()
                .contains("pace_hz")
        );
        assert!(matches!(
            spec("dref", json!({"pace_hz": -1})).plan(),
            Err(PlanError::Settings(SettingsError::BadValue {
                key: "pace_hz",
                ..
            }))
        ));
        // Recording settings are session settings, not hyper-parameters (the README documents
        // both for every method).
        for method in ["dref", "drpl"] {
            let s = spec(
                method,
                json!({"record": false, "rerun_connect": "rerun+http://127.0.0.1:9876/proxy"}),
            );
            assert!(!s.plan().unwrap().settings.record);
        }
        assert!(spec("drpl", json!({"c": 0.3})).plan().is_err());
        assert!(spec("dref", json!({"trajectories": 10})).plan().is_err());
        assert!(spec("drpl", json!({"trajectories": 10})).plan().is_ok());
        let RunConfig::Evaluative(config) = spec("dref", json!({"variant": "uniform", "c": 0.5}))
            .plan()
            .unwrap()
            .run
        else {
            panic!("dref is evaluative")
        };
        assert_eq!(config.env.variant, crate::sim::Variant::Uniform);
        assert_eq!(config.query_rule.c, 0.5);
        assert_eq!(config.seed, 1);
    }

    #[test]
    fn several_answers_and_teacher_faults_go_with_the_right_trainer_and_family() {
        let synthetic = |method: &str, params| SessionSpec {
            trainer: TrainerKind::Synthetic,
            ..spec(method, params)
        };
        spec(
            "dref",
            json!({"answers_per_query": 2, "combine": "majority"}),
        )
        .plan()
        .unwrap();
        spec("drpl", json!({"answers_per_query": 3, "combine": "each"}))
            .plan()
            .unwrap();
        for (method, params) in [
            ("dref", json!({"answers_per_query": 2, "combine": "each"})),
            ("drpl", json!({"answers_per_query": 2, "combine": "mean"})),
            ("dref", json!({"answers_per_query": 2})),
            ("dref", json!({"combine": "majority"})),
            ("dref", json!({"teacher_error": 0.1})),
        ] {
            assert!(
                spec(method, params.clone()).plan().is_err(),
                "{method} {params}"
            );
        }
        assert!(
            synthetic("dref", json!({"answers_per_query": 2, "combine": "mean"}))
                .plan()
                .is_err()
        );
        synthetic("dref", json!({"teacher_error": 0.1, "teacher_beta": 5}))
            .plan()
            .unwrap();
        synthetic("drpl", json!({"teacher_beta": 2, "teacher_gamma": 0.9}))
            .plan()
            .unwrap();
        // The offered defaults (a perfect teacher) are fine for people too.
        spec(
            "dref",
            json!({"teacher_beta": "rational", "teacher_error": 0, "teacher_skip": "never"}),
        )
        .plan()
        .unwrap();
    }

    #[test]
    fn a_stored_spec_reads_back_with_its_settings() {
        let s = spec("dref", json!({"hidden": [32, 32], "record": false}));
        let text = serde_json::to_string(&s).unwrap();
        assert!(
            text.contains(r#""params":{"record":false,"hidden":[32,32]}"#),
            "{text}"
        );
        assert_eq!(serde_json::from_str::<SessionSpec>(&text).unwrap(), s);
    }
}
