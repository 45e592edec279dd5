//! One run of SAC, EF-p% or DREF on a task, step by step (algorithms.md section 2), with an
//! evaluative trainer answering the queries. Headless: the CLI drives it to a step budget and
//! the server's session drives it at a watchable pace; both call [`EvaluativeRun::step`].
//!
//! Per environment step t:
//! 1. `a_t ~ pi(.|s_t)`; `H_hat = min_j H_j(s_t, a_t)` before this step's update.
//! 2. Step the env: `s_{t+1}, r_t, terminated, truncated`.
//! 3. `g` = the scene graph on `(s_{t+1}, a_t)` \[authors\].
//! 4. Ask iff the method's schedule says so (DREF: the UCB rank test on g; EF: a coin of p).
//! 5. If asked, H_t comes from the trainer and DREF's statistics learn `|H_t - H_hat|`.
//! 6. Store `(s_t, a_t, r_t, H_t, s_{t+1}, terminated)` and do the learner's gradient step.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

pub use super::evaluative_config::{
    DEFAULT_CEILING, EvaluativeRunConfig, FeedbackCeiling, GraphAtEpisodeEnd, QueryRuleConfig,
    TimeLimitEnd,
};

use super::ask_pacing::AskPacing;
use super::evaluative_trainer::{Evaluation, EvaluativeQuery, EvaluativeTrainer};
use super::feedback_schedule::FeedbackSchedule;
use super::mix_gate::{self, MixGate};
use crate::rl::replay::{ReplayBuffer, Transition};
use crate::rl::{Sac, UpdateStats};
use crate::scene_graph::AbstractState;
use crate::sim::{Env, EnvFault, EnvOptions, Outcome, RenderState, Task};

/// One finished episode, as a row of `metrics.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpisodeRecord {
    /// Environment steps of the run when the episode ended.
    pub step: u64,
    /// 0-based episode index.
    pub episode: u64,
    #[serde(rename = "return")]
    pub episode_return: f64,
    pub length: u32,
    /// Sum of the returns of every finished episode so far (the paper's Figure 3 axis).
    pub cumulative_return: f64,
    /// Queries asked so far (each answered by the trainer, "no feedback" included).
    pub feedback_count: u64,
    /// `feedback_count / step`.
    pub feedback_fraction: f64,
    pub outcome: Outcome,
    /// DREF: abstract states that have had feedback so far (while at most k + 1 have, its rule
    /// asks at every step); 0 for the other methods.
    #[serde(default)]
    pub states_with_feedback: u64,
    /// Steps since the last query when the episode ended (all steps if none yet): with the last
    /// 10 episodes failed, 10,000 or more marks the rule as frozen (docs/dref.md).
    #[serde(default)]
    pub steps_since_query: u64,
    /// The longest stretch of consecutive asked steps so far (a flood).
    #[serde(default)]
    pub longest_flood: u64,
}

/// What one call of [`EvaluativeRun::step`] did.
#[derive(Clone, Debug)]
pub struct StepReport {
    pub reward: f32,
    pub abstract_state: AbstractState,
    /// The trainer's answer if this step asked.
    pub evaluation: Option<Evaluation>,
    pub update: Option<UpdateStats>,
    /// Set when this step ended an episode (the env was reset for the next one).
    pub episode: Option<EpisodeRecord>,
    /// The episode's last state, rendered before the env reset (set with `episode`), so a
    /// viewer can show how it ended.
    pub final_state: Option<RenderState>,
}

pub struct EvaluativeRun {
    config: EvaluativeRunConfig,
    env: Box<dyn Env>,
    learner: Sac,
    replay: ReplayBuffer,
    schedule: FeedbackSchedule,
    /// Draws each episode's reset seed, so a run is reproducible from its own seed.
    episode_seeds: ChaCha8Rng,
    /// The reset seed of the episode under way: a checkpoint at an episode's start rebuilds
    /// the env from it.
    episode_seed: u64,
    obs: Vec<f32>,
    action: Vec<f32>,
    /// The action as the human critic is shown it for H_hat (scaled as run; a workspace).
    shown_action: Vec<f32>,
    steps: u64,
    episodes: u64,
    episode_return: f64,
    episode_length: u32,
    cumulative_return: f64,
    /// Episodes that ended in success (the gate of `answered_after`).
    successes: u64,
    /// The last episodes' outcomes, for the gate of `failure_window`.
    mix_gate: MixGate,
    feedback_count: u64,
    no_feedback_count: u64,
    /// Queries the method wanted that a person's pace held back.
    held_back: u64,
    /// Per query, in order: the step it judged and the replay slot of that transition, so an
    /// answer can be revised (a trainer's undo) after the run moved on. (A step taken in
    /// after a resume, `run_take_in`, counts at the step it was taken in at.)
    queried: Vec<(u64, usize)>,
    /// Rows pushed into the replay buffer besides one per step: answered steps taken in after
    /// a resume (`run_take_in`).
    taken_in: u64,
    /// Floods and silences of the rule.
    pacing: AskPacing,
    /// The next episode's first observation when the env was reset before the episode was
    /// counted (`graph_at_episode_end = reset`); `None` between steps.
    next_episode_obs: Option<Vec<f32>>,
}

impl EvaluativeRun {
    /// A fresh run whose replay buffer holds at most `min(buffer_size, steps)` transitions:
    /// a short run does not preallocate the full million rows.
    pub fn new(config: EvaluativeRunConfig, steps: u64) -> Self {
        let env = config.make_env();
        Self::with_env(config, env, steps).expect("the built-in tasks never fail")
    }

    /// A fresh run on `env` (an env in another process, or any other `Env`); the first reset
    /// can fail for an env that can.
    pub fn with_env(
        config: EvaluativeRunConfig,
        mut env: Box<dyn Env>,
        steps: u64,
    ) -> Result<Self, EnvFault> {
        let (obs_dim, act_dim) = (
            env.spec().observation_space.dim(),
            env.spec().action_space.dim(),
        );
        let learner = Sac::new(obs_dim, act_dim, config.sac.clone(), config.seed);
        let replay = ReplayBuffer::new(replay_capacity(&config, steps), obs_dim, act_dim);
        let schedule = FeedbackSchedule::new(config.method, config.query_rule.build(), config.seed);
        let mut episode_seeds = ChaCha8Rng::seed_from_u64(config.seed ^ 0xe915_0de5_eed5_0000);
        let episode_seed = episode_seeds.random();
        let obs = env.try_reset(episode_seed)?;
        Ok(Self {
            config,
            env,
            learner,
            replay,
            schedule,
            episode_seeds,
            episode_seed,
            obs,
            action: vec![0.0; act_dim],
            shown_action: vec![0.0; act_dim],
            steps: 0,
            episodes: 0,
            episode_return: 0.0,
            episode_length: 0,
            cumulative_return: 0.0,
            successes: 0,
            mix_gate: MixGate::default(),
            feedback_count: 0,
            no_feedback_count: 0,
            held_back: 0,
            queried: Vec::new(),
            taken_in: 0,
            pacing: AskPacing::default(),
            next_episode_obs: None,
        })
    }

    pub fn config(&self) -> &EvaluativeRunConfig {
        &self.config
    }

    /// Environment steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    pub fn episodes(&self) -> u64 {
        self.episodes
    }

    pub fn cumulative_return(&self) -> f64 {
        self.cumulative_return
    }

    /// Episodes that ended in success so far.
    pub fn successes(&self) -> u64 {
        self.successes
    }

    /// Whether the answered mix's gate is open: the human critic has `answered_after` set and
    /// the run has had fewer successful episodes than that, so the actor still reads H on
    /// unanswered rows at full weight.
    pub fn reads_h_everywhere(&self) -> bool {
        mix_gate::reads_h_everywhere(self.successes, self.config.sac.human_critic.as_ref())
    }

    /// Queries asked so far.
    pub fn feedback_count(&self) -> u64 {
        self.feedback_count
    }

    /// Queries the method wanted to ask that a person's pace (`human_pace`) held back.
    pub fn queries_held_back(&self) -> u64 {
        self.held_back
    }

    /// Floods and silences of the rule so far.
    pub fn pacing(&self) -> AskPacing {
        self.pacing
    }

    /// Queries answered "no feedback" (the paper's NFC for human trainers).
    pub fn no_feedback_count(&self) -> u64 {
        self.no_feedback_count
    }

    pub fn learner(&self) -> &Sac {
        &self.learner
    }

    pub fn env(&self) -> &dyn Env {
        self.env.as_ref()
    }

    /// The env, to change how it renders (a remote env sends frames only when asked).
    pub fn env_mut(&mut self) -> &mut dyn Env {
        self.env.as_mut()
    }

    /// Take one environment step and one learning step (on an env that cannot fail: the
    /// built-in tasks; use [`EvaluativeRun::try_step`] with any other).
    pub fn step(&mut self, trainer: &mut dyn EvaluativeTrainer) -> StepReport {
        self.try_step(trainer)
            .unwrap_or_else(|fault| panic!("the environment failed: {fault}"))
    }

    /// Take one environment step and one learning step. When the env fails, the run is left
    /// mid-step (its policy's random stream has moved on): resume from a checkpoint.
    pub fn try_step(
        &mut self,
        trainer: &mut dyn EvaluativeTrainer,
    ) -> Result<StepReport, EnvFault> {
        let uses_human_critic = self.config.sac.human_critic.is_some();
        self.learner.act(&self.obs, false, &mut self.action);
        let predicted = if uses_human_critic {
            self.human_estimate()
        } else {
            0.0
        };
        let step = self.env.try_step(&self.action)?;
        // Rendered before any reset, so a viewer sees how the episode ended.
        let final_state = step.outcome.map(|_| self.env.render());
        let graph_reads_reset =
            step.outcome.is_some() && self.config.graph_at_episode_end == GraphAtEpisodeEnd::Reset;
        if graph_reads_reset {
            self.reset_early()?;
        }
        let graph_obs = match &self.next_episode_obs {
            Some(reset) if graph_reads_reset => reset.as_slice(),
            _ => step.obs.as_slice(),
        };
        let g = self
            .config
            .scene_graph
            .after_step(self.env.as_ref(), graph_obs, &self.action);

        // The schedule decides first (EF's coin is drawn every step either way); past
        // `feedback_until` nothing is asked, and a person's pace may hold the query back.
        let terminated = step.terminated
            || (self.config.time_limit == TimeLimitEnd::Terminal
                && step.outcome == Some(Outcome::TimeLimit));
        let wanted = self.schedule.should_ask(g)
            && self.config.feedback_until.is_none_or(|n| self.steps < n);
        let asks = wanted
            && self
                .config
                .human_pace
                .is_none_or(|p| p.allows(self.steps, &self.queried));
        self.held_back += u64::from(wanted && !asks);
        let evaluation = if asks {
            let query = EvaluativeQuery {
                step: self.steps,
                obs: &self.obs,
                action: &self.action,
                next_obs: &step.obs,
                reward: step.reward,
                terminated,
                abstract_state: g,
                predicted,
            };
            let answer = trainer.evaluate(&query);
            self.schedule.record(g, answer.value(), predicted);
            self.feedback_count += 1;
            if answer == Evaluation::NoFeedback {
                self.no_feedback_count += 1;
            }
            Some(answer)
        } else {
            None
        };

        let slot = self.replay.push(Transition {
            obs: &self.obs,
            action: &self.action,
            reward: step.reward * self.config.reward_scale,
            human: evaluation.map_or(0.0, Evaluation::value),
            next_obs: &step.obs,
            terminated,
        });
        if evaluation.is_some() {
            self.queried.push((self.steps, slot));
        }
        self.pacing.step(self.steps, evaluation.is_some());
        let critic = self.config.sac.human_critic.as_ref();
        let gate = self
            .mix_gate
            .unanswered_weight(self.steps, self.successes, critic);
        self.learner.set_unanswered_override(gate);
        let update = self.learner.update(&self.replay);

        self.steps += 1;
        self.episode_return += f64::from(step.reward);
        self.episode_length += 1;
        let episode = match step.outcome {
            Some(outcome) => Some(self.finish_episode(outcome)?),
            None => {
                self.obs.copy_from_slice(&step.obs);
                None
            }
        };
        Ok(StepReport {
            reward: step.reward,
            abstract_state: g,
            evaluation,
            update,
            episode,
            final_state,
        })
    }

    /// Change the answer to query `query` (0-based, in the order asked) to `new`
    /// (`NoFeedback` for an undone answer): the stored transition's H is relabelled, so the
    /// human critic learns the new label from the next update on. The query rule keeps its
    /// count (the query was asked). Returns false if the run has no such query, or its
    /// transition has left the replay buffer.
    pub fn relabel(&mut self, query: usize, new: Evaluation) -> bool {
        let Some(&(step, slot)) = self.queried.get(query) else {
            return false;
        };
        // Rows pushed since, at most (rows taken in after a resume may have come between).
        if self.steps + self.taken_in - step > self.replay.capacity() as u64 {
            return false;
        }
        let old = Evaluation::from_value(self.replay.human(slot) as i64);
        self.replay.set_human(slot, new.value());
        let old = old.unwrap_or(Evaluation::NoFeedback);
        self.no_feedback_count = self.no_feedback_count + u64::from(new == Evaluation::NoFeedback)
            - u64::from(old == Evaluation::NoFeedback);
        true
    }

    /// The human label H stored with query `query`'s transition (tests and checks).
    pub fn human_label(&self, query: usize) -> Option<f32> {
        let &(_, slot) = self.queried.get(query)?;
        Some(self.replay.human(slot))
    }

    /// Count the finished episode and reset for the next. A failed reset leaves the run counted
    /// up to the episode's end but with no episode under way: resume from a checkpoint.
    fn finish_episode(&mut self, outcome: Outcome) -> Result<EpisodeRecord, EnvFault> {
        self.cumulative_return += self.episode_return;
        self.successes += u64::from(outcome == Outcome::Success);
        let critic = self.config.sac.human_critic.as_ref();
        self.mix_gate.record(outcome == Outcome::Success, critic);
        let record = EpisodeRecord {
            step: self.steps,
            episode: self.episodes,
            episode_return: self.episode_return,
            length: self.episode_length,
            cumulative_return: self.cumulative_return,
            feedback_count: self.feedback_count,
            feedback_fraction: self.feedback_count as f64 / self.steps as f64,
            outcome,
            states_with_feedback: self.schedule.states_with_feedback() as u64,
            steps_since_query: self.pacing.steps_since_query(self.steps),
            longest_flood: self.pacing.longest_flood,
        };
        self.episodes += 1;
        self.episode_return = 0.0;
        self.episode_length = 0;
        match self.next_episode_obs.take() {
            Some(obs) => self.obs = obs,
            None => {
                self.episode_seed = self.episode_seeds.random();
                self.obs = self.env.try_reset(self.episode_seed)?;
            }
        }
        Ok(record)
    }

    /// Reset the env for the next episode now, keeping its first observation for
    /// [`Self::finish_episode`] (the same seed and the same reset as there, only earlier).
    fn reset_early(&mut self) -> Result<(), EnvFault> {
        self.episode_seed = self.episode_seeds.random();
        self.next_episode_obs = Some(self.env.try_reset(self.episode_seed)?);
        Ok(())
    }

    /// H_hat for this step's action, shown to the human critic as the authors' runs showed it
    /// (scaled by the oracle's action scale, 1 but for Reaching as run).
    fn human_estimate(&mut self) -> f32 {
        let scale = self.config.oracle.action_scale;
        if scale == 1.0 {
            return self.learner.human_estimate(&self.obs, &self.action);
        }
        for (shown, a) in self.shown_action.iter_mut().zip(&self.action) {
            *shown = a * scale;
        }
        self.learner.human_estimate(&self.obs, &self.shown_action)
    }
}

impl EvaluativeRun {
    /// The trained learner, for saving or evaluation.
    pub fn into_learner(self) -> Sac {
        self.learner
    }
}

/// Mean return and success rate of `learner`'s deterministic policy (tanh of the mean) over
/// `episodes` episodes with reset seeds `seed, seed + 1, ...`.
pub fn evaluate_policy(
    task: Task,
    options: &EnvOptions,
    learner: &mut Sac,
    episodes: u32,
    seed: u64,
) -> (f64, f64) {
    let mut env = task.make_env_with(options);
    evaluate_policy_on(env.as_mut(), learner, episodes, seed)
        .expect("the built-in tasks never fail")
}

/// [`evaluate_policy`] on a given env (one in another process, say).
pub fn evaluate_policy_on(
    env: &mut dyn Env,
    learner: &mut Sac,
    episodes: u32,
    seed: u64,
) -> Result<(f64, f64), EnvFault> {
    let mut action = vec![0.0; env.spec().action_space.dim()];
    let (mut total, mut successes) = (0.0f64, 0u32);
    for i in 0..u64::from(episodes) {
        let mut obs = env.try_reset(seed.wrapping_add(i))?;
        loop {
            learner.act(&obs, true, &mut action);
            let step = env.try_step(&action)?;
            total += f64::from(step.reward);
            if let Some(outcome) = step.outcome {
                successes += u32::from(outcome == Outcome::Success);
                break;
            }
            obs = step.obs;
        }
    }
    let n = f64::from(episodes.max(1));
    Ok((total / n, f64::from(successes) / n))
}

/// The rows a run of `steps` steps keeps in its replay: all of them, up to the buffer's size.
fn replay_capacity(config: &EvaluativeRunConfig, steps: u64) -> usize {
    (config.sac.buffer_size as u64).min(steps.max(1)) as usize
}

#[path = "run_checkpoint.rs"]
mod run_checkpoint;
pub use run_checkpoint::RunCheckpointError;

#[path = "run_branch.rs"]
mod run_branch;
pub use run_branch::{BranchError, branch_check};

#[path = "run_take_in.rs"]
mod run_take_in;
pub use run_take_in::{AskedStep, TakeInError};

#[cfg(test)]
#[path = "evaluative_run_tests.rs"]
mod tests;
