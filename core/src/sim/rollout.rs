//! Run a simple policy for whole episodes and summarise them (the `dualrep sim` command, the
//! heuristic tests and the benchmarks share this).

use std::fmt;
use std::str::FromStr;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{Env, EnvOptions, Outcome, Task};

/// The policies that need no learning.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SimplePolicy {
    /// Uniform actions in `[-1, 1]^n`.
    Random,
    /// The task's scripted controller.
    Heuristic,
}

impl SimplePolicy {
    pub fn id(self) -> &'static str {
        match self {
            SimplePolicy::Random => "random",
            SimplePolicy::Heuristic => "heuristic",
        }
    }
}

impl fmt::Display for SimplePolicy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// A name that is no [`SimplePolicy`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown policy {0:?}: expected random or heuristic")]
pub struct UnknownPolicy(pub String);

impl FromStr for SimplePolicy {
    type Err = UnknownPolicy;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "random" => Ok(SimplePolicy::Random),
            "heuristic" => Ok(SimplePolicy::Heuristic),
            other => Err(UnknownPolicy(other.to_string())),
        }
    }
}

/// One finished episode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Episode {
    pub seed: u64,
    pub episode_return: f64,
    /// Steps the agent took (the env's reset steps not included).
    pub length: u32,
    pub outcome: Outcome,
}

/// Run one episode of `policy` from `seed`. Random actions come from their own generator,
/// seeded from `seed`, so an episode is reproducible from its seed alone.
pub fn run_episode(env: &mut dyn Env, task: Task, policy: SimplePolicy, seed: u64) -> Episode {
    let mut obs = env.reset(seed);
    let action_dim = env.spec().action_space.dim();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_ac71_0000_0001);
    let mut action = vec![0.0f32; action_dim];
    let (mut episode_return, mut length) = (0.0f64, 0u32);
    loop {
        match policy {
            SimplePolicy::Random => action
                .iter_mut()
                .for_each(|a| *a = rng.random_range(-1.0..=1.0)),
            SimplePolicy::Heuristic => action.copy_from_slice(&task.heuristic(&obs)),
        }
        let step = env.step(&action);
        episode_return += f64::from(step.reward);
        length += 1;
        if let Some(outcome) = step.outcome {
            return Episode {
                seed,
                episode_return,
                length,
                outcome,
            };
        }
        obs = step.obs;
    }
}

/// The summary `dualrep sim` prints.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimSummary {
    pub task: Task,
    /// The table-top task's version (none for Lunar Lander).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env: Option<EnvOptions>,
    pub policy: SimplePolicy,
    pub episodes: u32,
    pub mean_return: f64,
    pub std_return: f64,
    pub mean_length: f64,
    pub success_rate: f64,
    /// Agent steps per wall-clock second over the whole run, resets included.
    pub steps_per_second: f64,
}

/// Run `episodes` episodes of the task's default version with seeds `seed, seed + 1, ...` and
/// summarise them.
pub fn run_episodes(
    task: Task,
    policy: SimplePolicy,
    episodes: u32,
    seed: u64,
) -> (SimSummary, Vec<Episode>) {
    run_episodes_with(task, &EnvOptions::default(), policy, episodes, seed)
}

/// As [`run_episodes`], on the version of the task that `options` choose.
pub fn run_episodes_with(
    task: Task,
    options: &EnvOptions,
    policy: SimplePolicy,
    episodes: u32,
    seed: u64,
) -> (SimSummary, Vec<Episode>) {
    assert!(episodes > 0, "need at least one episode");
    let mut env = task.make_env_with(options);
    let start = Instant::now();
    let runs: Vec<Episode> = (0..u64::from(episodes))
        .map(|i| run_episode(env.as_mut(), task, policy, seed.wrapping_add(i)))
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    let n = f64::from(episodes);
    let mean_return = runs.iter().map(|e| e.episode_return).sum::<f64>() / n;
    let var = runs
        .iter()
        .map(|e| (e.episode_return - mean_return).powi(2))
        .sum::<f64>()
        / n;
    let total_steps: f64 = runs.iter().map(|e| f64::from(e.length)).sum();
    let successes = runs
        .iter()
        .filter(|e| e.outcome == Outcome::Success)
        .count();
    let summary = SimSummary {
        task,
        env: (task != Task::LunarLander).then_some(*options),
        policy,
        episodes,
        mean_return,
        std_return: var.sqrt(),
        mean_length: total_steps / n,
        success_rate: successes as f64 / n,
        steps_per_second: total_steps / seconds.max(1e-9),
    };
    (summary, runs)
}
