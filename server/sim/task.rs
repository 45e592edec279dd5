//! The three tasks by name: the one place that maps a task to its env and heuristic.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::{Env, EnvOptions, lunar_lander, placing, reaching};

#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    Serialize,
    Deserialize,
    utoipa::ToSchema,
)]
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
