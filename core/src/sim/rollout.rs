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

/// What chooses an episode's actions: a policy that needs no learning, or a learned one.
pub enum Actor<'a> {
    Simple(SimplePolicy),
    /// A learned policy (a learner's actor, say): writes its action for an observation.
    Learned(&'a mut dyn FnMut(&[f32], &mut [f32])),
}

impl Actor<'_> {
    /// The name a summary gives it: `random`, `heuristic` or `learned`.
    pub fn id(&self) -> &'static str {
        match self {
            Actor::Simple(policy) => policy.id(),
            Actor::Learned(_) => "learned",
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

    /// Move `drift`, the noise on each of `dim` action dimensions, one step on: drawn from the
    /// stationary law when it is empty (an episode's first step), else by the AR(1) rule.
    pub fn advance(self, drift: &mut Vec<f32>, dim: usize, rng: &mut impl Rng) {
        if drift.is_empty() {
            drift.extend((0..dim).map(|_| self.std * rng.sample::<f32, _>(StandardNormal)));
            return;
        }
        let innovation = (1.0 - self.correlation * self.correlation).sqrt() * self.std;
        for n in drift.iter_mut() {
            let e: f32 = rng.sample(StandardNormal);
            *n = self.correlation * *n + innovation * e;
        }
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
    /// The observation the action was chosen on.
    pub obs: &'a [f32],
    pub action: &'a [f32],
    pub next_obs: &'a [f32],
    pub reward: f32,
    /// Set on the episode's last step.
    pub outcome: Option<Outcome>,
}

/// Run one episode of `policy` from `seed`. Random actions come from their own generator,
/// seeded from `seed`, so an episode is reproducible from its seed alone.
pub fn run_episode(env: &mut dyn Env, task: Task, policy: SimplePolicy, seed: u64) -> Episode {
    let mut actor = Actor::Simple(policy);
    run_episode_watched(env, task, &mut actor, ActionNoise::NONE, seed, &mut |_| {})
}

/// As [`run_episode`], acted by `actor`, with `noise` added to each action (then clipped to
/// `[-1, 1]`) and `watch` shown every step. With a std of 0 no noise is drawn, so a simple
/// policy's episode is [`run_episode`]'s.
pub fn run_episode_watched(
    env: &mut dyn Env,
    task: Task,
    actor: &mut Actor<'_>,
    noise: ActionNoise,
    seed: u64,
    watch: &mut dyn FnMut(StepSeen<'_>),
) -> Episode {
    let mut obs = env.reset(seed);
    let action_dim = env.spec().action_space.dim();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_ac71_0000_0001);
    let mut action = vec![0.0f32; action_dim];
    let mut drift: Vec<f32> = Vec::new();
    let (mut episode_return, mut length) = (0.0f64, 0u32);
    loop {
        match actor {
            Actor::Simple(SimplePolicy::Random) => action
                .iter_mut()
                .for_each(|a| *a = rng.random_range(-1.0..=1.0)),
            Actor::Simple(SimplePolicy::Heuristic) => action.copy_from_slice(&task.heuristic(&obs)),
            Actor::Learned(act) => act(&obs, &mut action),
        }
        if noise.std > 0.0 {
            noise.advance(&mut drift, action_dim, &mut rng);
            for (a, n) in action.iter_mut().zip(&drift) {
                *a = (*a + n).clamp(-1.0, 1.0);
            }
        }
        let step = env.step(&action);
        watch(StepSeen {
            seed,
            t: length,
            obs: &obs,
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
    /// `random`, `heuristic` or `learned` ([`Actor::id`]).
    pub policy: String,
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
        &mut Actor::Simple(policy),
        ActionNoise::NONE,
        episodes,
        seed,
        &mut |_| {},
    )
}

/// As [`run_episodes_with`], acted by `actor`, each action with `noise`, and each step shown to
/// `watch` (see [`run_episode_watched`]).
pub fn run_episodes_watched(
    task: Task,
    options: &EnvOptions,
    actor: &mut Actor<'_>,
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
            run_episode_watched(env.as_mut(), task, actor, noise, episode_seed, watch)
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
        policy: actor.id().to_string(),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The noise's law: each step's standard deviation is `std` from the first step on, and one
    /// step's noise keeps `correlation` of the last's.
    #[test]
    fn action_noise_has_its_std_and_its_step_to_step_correlation() {
        for (std, correlation) in [(0.5f32, 0.95f32), (0.3, 0.0), (1.0, 0.6)] {
            let noise = ActionNoise { std, correlation };
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            let (mut first, mut pairs, mut lagged) = (Vec::new(), Vec::new(), Vec::new());
            for _ in 0..2_000 {
                let mut drift = Vec::new();
                noise.advance(&mut drift, 2, &mut rng);
                first.extend(drift.iter().copied());
                for _ in 0..20 {
                    let last = drift.clone();
                    noise.advance(&mut drift, 2, &mut rng);
                    pairs.extend(last.iter().zip(&drift).map(|(a, b)| (*a, *b)));
                }
                lagged.extend(drift.iter().copied());
            }
            let sd = |xs: &[f32]| {
                (xs.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>() / xs.len() as f64).sqrt()
            };
            for (name, xs) in [("first step", &first), ("twenty steps on", &lagged)] {
                let got = sd(xs);
                assert!(
                    (got / f64::from(std) - 1.0).abs() < 0.05,
                    "{name}: sd {got} for std {std} at correlation {correlation}"
                );
            }
            let product: f64 = pairs
                .iter()
                .map(|(a, b)| f64::from(*a) * f64::from(*b))
                .sum();
            let lag1 = product / pairs.len() as f64 / f64::from(std).powi(2);
            assert!(
                (lag1 - f64::from(correlation)).abs() < 0.02,
                "lag-1 correlation {lag1} for {correlation}"
            );
        }
    }

    #[test]
    fn no_noise_leaves_the_episode_as_it_was() {
        let mut env = Task::LunarLander.make_env_with(&EnvOptions::default());
        let plain = run_episode(env.as_mut(), Task::LunarLander, SimplePolicy::Random, 4);
        let mut seen = 0u32;
        let watched = run_episode_watched(
            env.as_mut(),
            Task::LunarLander,
            &mut Actor::Simple(SimplePolicy::Random),
            ActionNoise::NONE,
            4,
            &mut |_| seen += 1,
        );
        assert_eq!(plain, watched);
        assert_eq!(seen, plain.length);
    }
}
