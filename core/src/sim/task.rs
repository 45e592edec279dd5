//! The three tasks by name: the one place that maps a task to its env and heuristic.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::{Env, EnvOptions, lunar_lander, placing, reaching};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
#[serde(rename_all = "kebab-case")]
pub enum Task {
    Reaching,
    Placing,
    LunarLander,
}

impl Task {
    pub const ALL: [Task; 3] = [Task::Reaching, Task::Placing, Task::LunarLander];

    /// The identifier the CLI, the API and file names use.
    pub fn id(self) -> &'static str {
        match self {
            Task::Reaching => "reaching",
            Task::Placing => "placing",
            Task::LunarLander => "lunar-lander",
        }
    }

    /// The task's default env (the authors' version of each table-top task).
    pub fn make_env(self) -> Box<dyn Env> {
        self.make_env_with(&EnvOptions::default())
    }

    /// The task's env built with `options` (Lunar Lander has none and ignores them).
    pub fn make_env_with(self, options: &EnvOptions) -> Box<dyn Env> {
        match self {
            Task::Reaching => Box::new(reaching::Reaching::with_options(options)),
            Task::Placing => Box::new(placing::Placing::with_options(*options)),
            Task::LunarLander => Box::new(lunar_lander::LunarLander::new()),
        }
    }

    /// The task's scripted controller: an action in `[-1, 1]^n` for the observation `obs`.
    pub fn heuristic(self, obs: &[f32]) -> Vec<f32> {
        match self {
            Task::Reaching => reaching::heuristic(obs).to_vec(),
            Task::Placing => placing::heuristic(obs).to_vec(),
            Task::LunarLander => lunar_lander::heuristic(obs).to_vec(),
        }
    }
}

impl fmt::Display for Task {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// Which task a run trains on: one of ours (on our simulator, or on a copy of it in another
/// process), or one that an environment in another process declared about itself. Written as
/// the task's name for ours (so configs and checkpoints read as before) and as an object for a
/// declared one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum TaskRef {
    Builtin(Task),
    Declared(DeclaredTask),
}

/// What a run needs to know of a task an environment declared (`docs/env-protocol.md`); its
/// predicates are in the run's `SceneGraph::Declared`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeclaredTask {
    /// The id the env declared (`Pendulum-v1`, `my-robot`).
    pub env: String,
    /// DRPL's feature names: the env's own features, or its observation's entries when it
    /// declares none.
    pub features: Vec<String>,
    /// Whether the env computes the features (else they are the observation).
    #[serde(default)]
    pub env_features: bool,
}

impl TaskRef {
    /// One of ours, if it is.
    pub fn builtin(&self) -> Option<Task> {
        match self {
            TaskRef::Builtin(t) => Some(*t),
            TaskRef::Declared(_) => None,
        }
    }

    /// The name files, logs and the API use: ours by name, a declared one by its env's id.
    pub fn id(&self) -> &str {
        match self {
            TaskRef::Builtin(t) => t.id(),
            TaskRef::Declared(d) => &d.env,
        }
    }
}

impl From<Task> for TaskRef {
    fn from(task: Task) -> Self {
        TaskRef::Builtin(task)
    }
}

impl fmt::Display for TaskRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// A task name that is not one of ours.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown task {0:?}: expected one of reaching, placing, lunar-lander")]
pub struct UnknownTask(pub String);

impl FromStr for Task {
    type Err = UnknownTask;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Task::ALL
            .into_iter()
            .find(|t| t.id() == s)
            .ok_or_else(|| UnknownTask(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_through_from_str_and_serde() {
        for task in Task::ALL {
            assert_eq!(task.id().parse::<Task>().unwrap(), task);
            let json = serde_json::to_string(&task).unwrap();
            assert_eq!(json, format!("\"{}\"", task.id()));
        }
        assert!("lunar_lander".parse::<Task>().is_err());
    }
}
