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

use super::ask_pacing::AskPacing;
use super::evaluative_trainer::{Evaluation, EvaluativeQuery, EvaluativeTrainer};
use super::expert_oracle::OracleConfig;
use super::feedback_schedule::{EvaluativeMethod, FeedbackSchedule};
use super::human_pace::HumanPace;
use super::query_rule::{QueryRule, UcbForm};
use super::teacher::TeacherFaults;
use crate::rl::replay::{ReplayBuffer, Transition};
use crate::rl::{HumanCriticConfig, Sac, SacConfig, UpdateStats};
use crate::scene_graph::{AbstractState, SceneGraph};
use crate::sim::{DeclaredTask, Env, EnvFault, EnvOptions, Outcome, RenderState, Task, TaskRef};

/// DREF's query-rule constants (algorithms.md section 2, from the authors' configs), and the
/// product rule's two changes (`docs/dref.md`), both off in the authors' rule.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct QueryRuleConfig {
    pub c: f64,
    pub k: usize,
    pub form: UcbForm,
    /// Rank among the states visited in the last `rank_window` steps; 0: among every state
    /// that has had feedback (the authors'). Configs written before it existed read as 0.
    #[serde(default)]
    pub rank_window: usize,
    /// A ceiling on the share of steps asked; `None`: none (the authors').
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ceiling: Option<FeedbackCeiling>,
    /// After this many steps without a query, rank among the states visited during the
    /// silence until the rule asks; 0: never (the authors'). Configs written before it existed
    /// read as 0.
    #[serde(default)]
    pub wake_after: u64,
}

/// At most `rate` of the steps asked in the long run, at most about `burst` in a row; with a
/// `floor`, the rate runs between it and `rate` by the share of recent "bad" answers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeedbackCeiling {
    pub rate: f64,
    pub burst: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<f64>,
}

/// The product DREF's window: about 1,000 steps is many Placing and Reaching episodes and one or
/// two of Lunar Lander's, so the ranked states are those of the learner's current behaviour
/// (docs/dref.md).
pub const DEFAULT_RANK_WINDOW: usize = 1_000;
/// The product DREF's ceiling: 10 % of the steps (the paper's DREF asked 1.6-8.4 %), at most
/// 20 queries in a row (one second of a human session at 20 Hz). At 5 % the masked critic had
/// too few answers: Reaching stalled on 4 seeds of 10 and Placing failed on seeds a 10 % ceiling
/// learns (docs/dref.md, docs/results/dref-ablation/).
pub const DEFAULT_CEILING: FeedbackCeiling = FeedbackCeiling {
    rate: 0.1,
    burst: 20,
    floor: None,
};

impl QueryRuleConfig {
    /// The authors' rule on `task` (algorithms.md section 2).
    pub fn for_task(task: Task) -> Self {
        let (c, k) = match task {
            Task::LunarLander => (0.2, 60),
            Task::Reaching => (0.1, 2),
            Task::Placing => (0.2, 4),
        };
        Self {
            c,
            k,
            form: UcbForm::Authors,
            rank_window: 0,
            ceiling: None,
            wake_after: 0,
        }
    }

    /// The rule `method` asks by on `task`: the product's for `dref`, the authors' otherwise.
    pub fn for_method(task: Task, method: EvaluativeMethod) -> Self {
        let authors = Self::for_task(task);
        match method {
            EvaluativeMethod::Dref => Self {
                rank_window: DEFAULT_RANK_WINDOW,
                ceiling: Some(DEFAULT_CEILING),
                ..authors
            },
            _ => authors,
        }
    }

    /// The running rule these constants describe.
    pub fn build(&self) -> QueryRule {
        let mut rule = QueryRule::new(self.c, self.k, self.form);
        if self.rank_window > 0 {
            rule = rule.ranked_among_recent(self.rank_window);
        }
        if let Some(ceiling) = self.ceiling {
            rule = rule.with_ceiling(ceiling.rate, ceiling.burst, ceiling.floor);
        }
        if self.wake_after > 0 {
            rule = rule.waking_after(self.wake_after);
        }
        rule
    }

    /// A task an env declared: Placing's constants (c 0.2, k 4), the authors' largest c with a
    /// k for a graph of a handful of predicates; set `c` and `k` for another.
    pub fn for_declared() -> Self {
        Self::for_task(Task::Placing)
    }
}

/// Everything that defines a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvaluativeRunConfig {
    pub task: TaskRef,
    pub method: EvaluativeMethod,
    pub seed: u64,
    pub sac: SacConfig,
    pub query_rule: QueryRuleConfig,
    pub scene_graph: SceneGraph,
    /// Which version of the task (tasks.md); configs written before it existed read as the
    /// default.
    #[serde(default)]
    pub env: EnvOptions,
    /// The learner stores `reward_scale * r` (the authors ran Reaching's SAC baseline at reward
    /// 10, i.e. 0.1); episode returns and the cumulative reward stay on the env's scale.
    #[serde(default = "unit_scale")]
    pub reward_scale: f32,
    /// At most N queries a minute (people); `None`: the method asks as it likes (the paper).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub human_pace: Option<HumanPace>,
    /// The synthetic teacher's faults (none: the paper's oracle).
    #[serde(default, skip_serializing_if = "TeacherFaults::is_perfect")]
    pub teacher: TeacherFaults,
    /// The synthetic oracle's alpha start and the scale of the actions its critic is shown
    /// (the authors' head: 0.999 and 1).
    #[serde(default, skip_serializing_if = "OracleConfig::is_default")]
    pub oracle: OracleConfig,
    /// Which observation the scene graph reads on an episode's last step.
    #[serde(default, skip_serializing_if = "is_default")]
    pub graph_at_episode_end: GraphAtEpisodeEnd,
    /// How a time limit's end is stored for the learner.
    #[serde(default, skip_serializing_if = "is_default")]
    pub time_limit: TimeLimitEnd,
}

fn is_default<T: Default + PartialEq>(value: &T) -> bool {
    *value == T::default()
}

/// The observation the scene graph reads on an episode's last step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum GraphAtEpisodeEnd {
    /// The episode's last observation s_{t+1} (the graph of what the robot did).
    #[default]
    Step,
    /// The next episode's first observation, as the authors' runs had it: stable-baselines3's
    /// vectorised env resets before it returns, so their `new_obs` at an episode's end was the
    /// reset observation, and the graph (and so the query rule) read that.
    Reset,
}

/// How an episode's end at the time limit is stored for the learner.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum TimeLimitEnd {
    /// As a truncation: the bootstrap goes on through it (algorithms.md section 1).
    #[default]
    Truncation,
    /// As a termination, as the authors' robosuite runs stored it (their wrapper set `done`
    /// at the horizon and no `TimeLimit.truncated`), so the bootstrap stops there.
    Terminal,
}

fn unit_scale() -> f32 {
    1.0
}

/// The human critic `method` learns with: none for plain SAC; the authors' (H regressed on every
/// sampled step, the unasked ones as 0) for EF and the authors' DREF; regressed on answered
/// steps only for the product's DREF, whose answers would otherwise be outnumbered by zeros
/// 30 to 1 at a few percent of feedback (docs/dref.md).
fn human_critic_for(method: EvaluativeMethod) -> Option<HumanCriticConfig> {
    match method {
        EvaluativeMethod::Sac => None,
        EvaluativeMethod::Dref => Some(HumanCriticConfig {
            mask: true,
            ..HumanCriticConfig::default()
        }),
        EvaluativeMethod::Ef { .. } | EvaluativeMethod::DrefAuthors => {
            Some(HumanCriticConfig::default())
        }
    }
}

impl EvaluativeRunConfig {
    /// The published defaults for `task` and `method`: plain SAC has no human critic, EF and
    /// DREF have one with the authors' actor mix; the product's `dref` regresses it on answered
    /// steps only and asks by its own rule (`docs/dref.md`).
    pub fn new(task: Task, method: EvaluativeMethod, seed: u64) -> Self {
        let mut sac = SacConfig::for_task(task);
        sac.human_critic = human_critic_for(method);
        Self {
            task: task.into(),
            method,
            seed,
            sac,
            query_rule: QueryRuleConfig::for_method(task, method),
            scene_graph: SceneGraph::for_task(task),
            env: EnvOptions::default(),
            reward_scale: 1.0,
            human_pace: None,
            teacher: TeacherFaults::default(),
            oracle: OracleConfig::default(),
            graph_at_episode_end: GraphAtEpisodeEnd::Step,
            time_limit: TimeLimitEnd::Truncation,
        }
    }

    /// The defaults for a task an env in another process declared, with its `graph`:
    /// stable-baselines3's SAC (two layers of 256, learning rate 3e-4, batch 256, tau 0.005)
    /// and [`QueryRuleConfig::for_declared`].
    pub fn declared(
        task: DeclaredTask,
        graph: SceneGraph,
        method: EvaluativeMethod,
        seed: u64,
    ) -> Self {
        let sac = SacConfig {
            hidden: vec![256, 256],
            learning_rate: 3e-4,
            batch_size: 256,
            buffer_size: 1_000_000,
            tau: 0.005,
            gamma: 0.99,
            learning_starts: 0,
            gradient_steps: 1,
            init_ent_coef: 1.0,
            target_entropy: None,
            human_critic: human_critic_for(method),
        };
        let query_rule = match method {
            EvaluativeMethod::Dref => QueryRuleConfig {
                rank_window: DEFAULT_RANK_WINDOW,
                ceiling: Some(DEFAULT_CEILING),
                ..QueryRuleConfig::for_declared()
            },
            _ => QueryRuleConfig::for_declared(),
        };
        Self {
            task: TaskRef::Declared(task),
            method,
            seed,
            sac,
            query_rule,
            scene_graph: graph,
            env: EnvOptions::default(),
            reward_scale: 1.0,
            human_pace: None,
            teacher: TeacherFaults::default(),
            oracle: OracleConfig::default(),
            graph_at_episode_end: GraphAtEpisodeEnd::Step,
            time_limit: TimeLimitEnd::Truncation,
        }
    }

    /// Build the run's env on our simulator. Panics for a declared task, whose env lives in
    /// another process: build that run with [`EvaluativeRun::with_env`].
    pub fn make_env(&self) -> Box<dyn Env> {
        match &self.task {
            TaskRef::Builtin(task) => task.make_env_with(&self.env),
            TaskRef::Declared(d) => panic!(
                "task {} lives in another process: give its env to EvaluativeRun::with_env",
                d.env
            ),
        }
    }
}

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
    feedback_count: u64,
    no_feedback_count: u64,
    /// Queries the method wanted that a person's pace held back.
    held_back: u64,
    /// Per query, in order: the step it judged and the replay slot of that transition, so an
    /// answer can be revised (a trainer's undo) after the run moved on.
    queried: Vec<(u64, usize)>,
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
        let capacity = (config.sac.buffer_size as u64).min(steps.max(1)) as usize;
        let replay = ReplayBuffer::new(capacity, obs_dim, act_dim);
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
            feedback_count: 0,
            no_feedback_count: 0,
            held_back: 0,
            queried: Vec::new(),
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

        // The schedule decides first (EF's coin is drawn every step either way); a person's
        // pace may then hold the query back.
        let wanted = self.schedule.should_ask(g);
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
            terminated: step.terminated
                || (self.config.time_limit == TimeLimitEnd::Terminal
                    && step.outcome == Some(Outcome::TimeLimit)),
        });
        if evaluation.is_some() {
            self.queried.push((self.steps, slot));
        }
        self.pacing.step(self.steps, evaluation.is_some());
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
        if self.steps - step > self.replay.capacity() as u64 {
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

#[path = "run_checkpoint.rs"]
mod run_checkpoint;
pub use run_checkpoint::RunCheckpointError;

#[cfg(test)]
#[path = "evaluative_run_tests.rs"]
mod tests;
