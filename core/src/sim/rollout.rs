//! Run a simple policy for whole episodes and summarise them (the `dualrep sim` command, the
//! heuristic tests and the benchmarks share this). A policy may be made noisy, and each step
//! may be watched: `dualrep sim --noise 0.5 --noise-correlation 0.95 --steps steps.csv` gives a
//! population of episodes that end every way, step by step, to ask what the scene graph can
//! tell of how they end.

use std::fmt;
use std::str::FromStr;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
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

/// Gaussian noise on each action dimension, an AR(1) process in time: `n_t = correlation *
/// n_{t-1} + sqrt(1 - correlation^2) * std * e_t`, started from its stationary law, so each
/// `n_t` has standard deviation `std` and `correlation` 0 is white noise. A policy as good as
/// Lunar Lander's heuristic shrugs off white noise (it lands 99 of 100 episodes at a std of
/// 0.3); noise that persists for a few tenths of a second pushes it into the descents that fail.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ActionNoise {
    pub std: f32,
    /// In `[0, 1)`.
    pub correlation: f32,
}

impl ActionNoise {
    pub const NONE: Self = Self {
        std: 0.0,
        correlation: 0.0,
    };

    /// `self`, or why it is no noise process.
    pub fn check(self) -> Result<Self, NoiseError> {
        if !(self.std.is_finite() && self.std >= 0.0) {
            return Err(NoiseError::Std(self.std));
        }
        if !(0.0..1.0).contains(&self.correlation) {
            return Err(NoiseError::Correlation(self.correlation));
        }
        Ok(self)
    }
}

/// An [`ActionNoise`] that is no noise process.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum NoiseError {
    #[error("noise std {0}: give a finite number at least 0")]
    Std(f32),
    #[error("noise correlation {0}: give a number in [0, 1)")]
    Correlation(f32),
}

/// One step of an episode, as a watcher of [`run_episode_watched`] sees it: the action taken
/// (noise included, clipped) and what followed it.
#[derive(Clone, Copy, Debug)]
pub struct StepSeen<'a> {
    /// The episode's seed.
    pub seed: u64,
    /// The step's index in its episode, from 0.
    pub t: u32,
    pub action: &'a [f32],
    pub next_obs: &'a [f32],
    pub reward: f32,
    /// Set on the episode's last step.
    pub outcome: Option<Outcome>,
}

/// Run one episode of `policy` from `seed`. Random actions come from their own generator,
/// seeded from `seed`, so an episode is reproducible from its seed alone.
pub fn run_episode(env: &mut dyn Env, task: Task, policy: SimplePolicy, seed: u64) -> Episode {
    run_episode_watched(env, task, policy, ActionNoise::NONE, seed, &mut |_| {})
}

/// As [`run_episode`], with `noise` added to each action (then clipped to `[-1, 1]`) and `watch`
/// shown every step. With a std of 0 no noise is drawn, so the episode is [`run_episode`]'s.
pub fn run_episode_watched(
    env: &mut dyn Env,
    task: Task,
    policy: SimplePolicy,
    noise: ActionNoise,
    seed: u64,
    watch: &mut dyn FnMut(StepSeen<'_>),
) -> Episode {
    let mut obs = env.reset(seed);
    let action_dim = env.spec().action_space.dim();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_ac71_0000_0001);
    let mut action = vec![0.0f32; action_dim];
    let mut drift: Vec<f32> = Vec::new();
    let innovation = (1.0 - noise.correlation * noise.correlation).sqrt();
    let (mut episode_return, mut length) = (0.0f64, 0u32);
    loop {
        match policy {
            SimplePolicy::Random => action
                .iter_mut()
                .for_each(|a| *a = rng.random_range(-1.0..=1.0)),
            SimplePolicy::Heuristic => action.copy_from_slice(&task.heuristic(&obs)),
        }
        if noise.std > 0.0 {
            if drift.is_empty() {
                drift = (0..action_dim)
                    .map(|_| noise.std * rng.sample::<f32, _>(StandardNormal))
                    .collect();
            } else {
                for n in &mut drift {
                    let e: f32 = rng.sample(StandardNormal);
                    *n = noise.correlation * *n + innovation * noise.std * e;
                }
            }
            for (a, n) in action.iter_mut().zip(&drift) {
                *a = (*a + n).clamp(-1.0, 1.0);
            }
        }
        let step = env.step(&action);
        watch(StepSeen {
            seed,
            t: length,
            action: &action,
            next_obs: &step.obs,
            reward: step.reward,
            outcome: step.outcome,
        });
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
    /// The noise on each action (a std of 0: none).
    #[serde(default)]
    pub noise: ActionNoise,
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
    run_episodes_watched(
        task,
        options,
        policy,
        ActionNoise::NONE,
        episodes,
        seed,
        &mut |_| {},
    )
}

/// As [`run_episodes_with`], each action with `noise`, and each step shown to `watch` (see
/// [`run_episode_watched`]).
pub fn run_episodes_watched(
    task: Task,
    options: &EnvOptions,
    policy: SimplePolicy,
    noise: ActionNoise,
    episodes: u32,
    seed: u64,
    watch: &mut dyn FnMut(StepSeen<'_>),
) -> (SimSummary, Vec<Episode>) {
    assert!(episodes > 0, "need at least one episode");
    if let Err(e) = noise.check() {
        panic!("{e}");
    }
    let mut env = task.make_env_with(options);
    let start = Instant::now();
    let runs: Vec<Episode> = (0..u64::from(episodes))
        .map(|i| {
            let episode_seed = seed.wrapping_add(i);
            run_episode_watched(env.as_mut(), task, policy, noise, episode_seed, watch)
        })
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
        noise,
        episodes,
        mean_return,
        std_return: var.sqrt(),
        mean_length: total_steps / n,
        success_rate: successes as f64 / n,
        steps_per_second: total_steps / seconds.max(1e-9),
    };
    (summary, runs)
}
