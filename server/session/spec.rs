//! What a session is: task, method, trainer kind, seed, budget and parameters, as launched over
//! REST and stored (as JSON) with the session. Validation happens here, once, so that a session
//! that was accepted can always be built again on resume.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::rl::kernels::KernelPath;
use crate::sim::Task;

use super::events::QueryKind;

/// A human session's control rate when the researcher does not set `pace_hz`: the robot's own.
pub const DEFAULT_PACE_HZ: f64 = 20.0;
/// How long a query waits for a person before it counts as "no feedback" (or a skipped pair).
pub const DEFAULT_ANSWER_TIMEOUT_S: f64 = 60.0;
/// Environment steps between periodic checkpoints of evaluative sessions.
pub const DEFAULT_CHECKPOINT_EVERY: u64 = 5_000;
/// Frames of the clip that leads up to an evaluative query (1.5 s at 20 Hz).
pub const DEFAULT_CLIP_FRAMES: usize = 30;
/// Preference queries when the launch request names none (Figure 5's budget).
pub const DEFAULT_QUERIES: usize = 40;

/// Who answers the session's queries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
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

impl FromStr for SessionMethod {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if let Ok(m) = s.parse::<QueryMethod>() {
            return Ok(SessionMethod::Preference(m));
        }
        s.parse::<EvaluativeMethod>()
            .map(SessionMethod::Evaluative)
            .map_err(|_| {
                format!(
                    "unknown method {s:?}: expected dref, ef-<percent>, sac, drpl, drpl-ss, fragment or full"
                )
            })
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
    pub task: Task,
    pub method: SessionMethod,
    pub trainer: TrainerKind,
    pub seed: u64,
    /// Environment steps (evaluative methods) or queries (preference methods).
    pub budget: u64,
    /// Session settings (`pace_hz`, `answer_timeout_s`, `checkpoint_every`, `clip_frames`) and
    /// hyper-parameter overrides by name, as given.
    #[serde(default)]
    pub params: BTreeMap<String, serde_json::Value>,
}

/// Settings that shape the session rather than the algorithm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SessionSettings {
    pub pace_hz: f64,
    pub answer_timeout_s: f64,
    pub checkpoint_every: u64,
    pub clip_frames: usize,
    /// Write the session's Rerun recording (`<data dir>/recordings/<id>.rrd`); on by default.
    pub record: bool,
    /// Also stream to a running Rerun viewer at this URL (else the server's `--rerun-connect`).
    pub rerun_connect: Option<String>,
    /// The kernels the session computes with (the server's, recorded at launch, so that a
    /// resumed session replays with the same numerics); `None` for sessions stored before.
    pub kernels: Option<KernelPath>,
}

/// The algorithm's configuration, built from the spec.
#[derive(Clone, Debug)]
pub enum RunConfig {
    Evaluative(EvaluativeRunConfig),
    Preference(PreferenceRunConfig),
}

const SETTING_KEYS: [&str; 7] = [
    "kernels",
    "record",
    "rerun_connect",
    "pace_hz",
    "answer_timeout_s",
    "checkpoint_every",
    "clip_frames",
];

/// A JSON parameter as the string form the CLI's `--set` takes (`[256, 256]` -> `256,256`).
fn param_text(key: &str, value: &serde_json::Value) -> Result<String, String> {
    use serde_json::Value;
    match value {
        Value::String(s) => Ok(s.clone()),
        Value::Number(n) => Ok(n.to_string()),
        Value::Bool(b) => Ok(b.to_string()),
        Value::Array(items) => items
            .iter()
            .map(|v| match v {
                Value::Number(n) => Ok(n.to_string()),
                _ => Err(format!("{key}: a list may hold numbers only")),
            })
            .collect::<Result<Vec<_>, _>>()
            .map(|v| v.join(",")),
        Value::Null | Value::Object(_) => Err(format!(
            "{key}: expected a number, string, boolean or list of numbers"
        )),
    }
}

impl SessionSpec {
    /// The session settings, with defaults for those not given.
    pub fn settings(&self) -> Result<SessionSettings, String> {
        let number = |key: &str, default: f64| -> Result<f64, String> {
            match self.params.get(key) {
                None => Ok(default),
                Some(v) => v
                    .as_f64()
                    .filter(|x| x.is_finite() && *x > 0.0)
                    .ok_or_else(|| format!("{key}: expected a positive number, got {v}")),
            }
        };
        let pace_hz = number("pace_hz", DEFAULT_PACE_HZ)?;
        if pace_hz > 1000.0 {
            return Err(format!("pace_hz: at most 1000, got {pace_hz}"));
        }
        Ok(SessionSettings {
            pace_hz,
            answer_timeout_s: number("answer_timeout_s", DEFAULT_ANSWER_TIMEOUT_S)?,
            checkpoint_every: number("checkpoint_every", DEFAULT_CHECKPOINT_EVERY as f64)?.round()
                as u64,
            clip_frames: number("clip_frames", DEFAULT_CLIP_FRAMES as f64)?.round() as usize,
            record: match self.params.get("record") {
                None => true,
                Some(v) => v
                    .as_bool()
                    .ok_or_else(|| format!("record: expected true or false, got {v}"))?,
            },
            rerun_connect: match self.params.get("rerun_connect") {
                None => None,
                Some(v) => Some(
                    v.as_str()
                        .filter(|s| !s.is_empty())
                        .ok_or_else(|| format!("rerun_connect: expected a viewer URL, got {v}"))?
                        .to_string(),
                ),
            },
            kernels: match self.params.get("kernels") {
                None => None,
                Some(v) => Some(
                    v.as_str()
                        .ok_or_else(|| {
                            format!("kernels: expected avx512, avx2 or portable, got {v}")
                        })?
                        .parse()
                        .map_err(|e| format!("kernels: {e}"))?,
                ),
            },
        })
    }

    /// The algorithm's configuration with every hyper-parameter override applied.
    pub fn run_config(&self) -> Result<RunConfig, String> {
        let overrides = self
            .params
            .iter()
            .filter(|(k, _)| !SETTING_KEYS.contains(&k.as_str()))
            .map(|(k, v)| param_text(k, v).map(|text| (k.as_str(), text)));
        match self.method {
            SessionMethod::Evaluative(method) => {
                let mut config = EvaluativeRunConfig::new(self.task, method, self.seed);
                for pair in overrides {
                    let (k, v) = pair?;
                    config.set(k, &v)?;
                }
                Ok(RunConfig::Evaluative(config))
            }
            SessionMethod::Preference(method) => {
                let mut config = PreferenceRunConfig::new(self.task, method, self.seed);
                for pair in overrides {
                    let (k, v) = pair?;
                    config.set(k, &v)?;
                }
                Ok(RunConfig::Preference(config))
            }
        }
    }

    /// The scene graph the session's queries are phrased in (its `side_engines_on_a0` override
    /// included).
    pub fn scene_graph(&self) -> Result<crate::scene_graph::SceneGraph, String> {
        Ok(match self.run_config()? {
            RunConfig::Evaluative(c) => c.scene_graph,
            RunConfig::Preference(c) => c.scene_graph,
        })
    }

    /// Everything a launch must get right, checked before the session is stored.
    pub fn validate(&self) -> Result<(), String> {
        if self.budget == 0 {
            return Err("the budget (steps or queries) must be at least 1".into());
        }
        if self.budget > 10_000_000 {
            return Err(format!(
                "budget {} is above the limit of 10,000,000",
                self.budget
            ));
        }
        self.settings()?;
        self.run_config()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn spec(method: &str, params: serde_json::Value) -> SessionSpec {
        SessionSpec {
            task: Task::Reaching,
            method: method.parse().unwrap(),
            trainer: TrainerKind::Human,
            seed: 1,
            budget: 100,
            params: serde_json::from_value(params).unwrap(),
        }
    }

    #[test]
    fn methods_parse_into_their_family() {
        assert!("drpl-ss".parse::<SessionMethod>().unwrap().is_preference());
        assert!(!"ef-12.5".parse::<SessionMethod>().unwrap().is_preference());
        assert_eq!(
            "ef-50".parse::<SessionMethod>().unwrap().to_string(),
            "ef-50"
        );
        assert!(
            "best"
                .parse::<SessionMethod>()
                .unwrap_err()
                .contains("dref")
        );
    }

    #[test]
    fn settings_default_and_validate() {
        let s = spec("dref", json!({}));
        assert_eq!(s.settings().unwrap().pace_hz, DEFAULT_PACE_HZ);
        let s = spec("dref", json!({"pace_hz": 5, "answer_timeout_s": 2.5}));
        let settings = s.settings().unwrap();
        assert_eq!((settings.pace_hz, settings.answer_timeout_s), (5.0, 2.5));
        assert!(
            spec("dref", json!({"pace_hz": -1}))
                .validate()
                .unwrap_err()
                .contains("pace_hz")
        );
        assert!(spec("dref", json!({"pace_hz": "fast"})).validate().is_err());
    }

    #[test]
    fn recording_settings_are_session_settings_not_hyper_parameters() {
        // The README documents both; they must not reach the algorithm's `set`.
        for method in ["dref", "drpl"] {
            let s = spec(
                method,
                json!({"record": false, "rerun_connect": "rerun+http://127.0.0.1:9876/proxy"}),
            );
            s.validate().unwrap();
            assert!(!s.settings().unwrap().record);
        }
        assert!(spec("dref", json!({"record": "no"})).validate().is_err());
    }

    #[test]
    fn kernels_are_a_session_setting_and_nonsense_is_refused() {
        let s = spec("dref", json!({"kernels": "portable"}));
        s.validate().unwrap();
        assert_eq!(s.settings().unwrap().kernels, Some(KernelPath::Portable));
        assert_eq!(spec("dref", json!({})).settings().unwrap().kernels, None);
        for bad in [json!({"kernels": "fast"}), json!({"kernels": 2})] {
            assert!(
                spec("dref", bad)
                    .validate()
                    .unwrap_err()
                    .contains("kernels")
            );
        }
    }

    #[test]
    fn task_variants_reach_the_env() {
        let s = spec("dref", json!({"variant": "uniform", "reward_scale": 0.1}));
        let RunConfig::Evaluative(config) = s.run_config().unwrap() else {
            panic!("dref is evaluative")
        };
        assert_eq!(config.env.variant, crate::sim::Variant::Uniform);
        assert_eq!(config.reward_scale, 0.1);
        assert!(
            spec("dref", json!({"variant": "robosuite"}))
                .validate()
                .is_err()
        );
        assert!(spec("drpl", json!({"release_at": 0.9})).validate().is_err());
    }

    #[test]
    fn hyper_parameters_reach_the_algorithm_and_nonsense_is_refused() {
        let s = spec(
            "dref",
            json!({"hidden": [32, 32], "c": 0.5, "batch_size": 64}),
        );
        let RunConfig::Evaluative(config) = s.run_config().unwrap() else {
            panic!("dref is evaluative")
        };
        assert_eq!(config.query_rule.c, 0.5);
        assert_eq!(config.sac.batch_size, 64);
        assert!(spec("dref", json!({"no_such_key": 1})).validate().is_err());
        assert!(spec("drpl", json!({"trajectories": 10})).validate().is_ok());
        assert!(
            spec("drpl", json!({"trajectories": {"a": 1}}))
                .validate()
                .is_err()
        );
    }
}
