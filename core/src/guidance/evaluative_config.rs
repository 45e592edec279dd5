//! What defines an evaluative run (`EvaluativeRunConfig`): the task, the method, the learner's
//! and the query rule's constants, the trainer and the env's behaviours at an episode's end.
//! Plain data, serialised as every run's `config.json` and into checkpoints; the run itself is
//! `evaluative_run.rs`.

use serde::{Deserialize, Serialize};

// The ceiling's fields serialise as the bucket's own do.
use super::ask_budget::{AskBudget, is_false, is_whole, is_zero, whole};
use super::expert_oracle::OracleConfig;
use super::feedback_schedule::EvaluativeMethod;
use super::human_pace::HumanPace;
use super::query_rule::{QueryRule, UcbForm};
use super::teacher::TeacherFaults;
use super::visit_share::OpeningPlacement;
use crate::rl::{ActorMix, CriticLoss, HumanCriticConfig, SacConfig};
use crate::scene_graph::SceneGraph;
use crate::sim::{DeclaredTask, Env, EnvOptions, Task, TaskRef};

/// DREF's query-rule constants (algorithms.md section 2, from the authors' configs), and the
/// product rule's changes to the query rule (`docs/dref.md`), all off in the authors' rule.
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
    /// For the run's first `opening` steps the rule asks as it would without the ceiling and
    /// repays what it borrowed afterwards (0: off; configs written before it read as 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub opening: u64,
    /// The bucket starts empty, so a run stays within `rate` of its steps once its opening is
    /// repaid (full, the default: `burst` more). Configs written before it read as full.
    #[serde(default, skip_serializing_if = "is_false")]
    pub start_empty: bool,
    /// The share of each step's earnings that repays the opening; the rest may be asked while
    /// it repays (1, the default: all, silent until repaid; configs before it read as 1).
    #[serde(default = "whole", skip_serializing_if = "is_whole")]
    pub repay_share: f64,
    /// The share of the opening's steps it may ask, ranked as a woken rule ranks (`None`, the
    /// default: every step the authors' ranking asks; configs before it read as `None`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opening_rate: Option<f64>,
    /// Where a paced opening asks: ranked (the default; configs before it read so), or each
    /// abstract state its share of its own visits.
    #[serde(default, skip_serializing_if = "is_ranked")]
    pub opening_placement: OpeningPlacement,
    /// Where the spare is asked while an opening's debt is repaid: ranked (the default, the
    /// best-ranked state only; configs before it read so), or each abstract state its share of
    /// its own visits since the repayment began.
    #[serde(default, skip_serializing_if = "is_ranked")]
    pub repayment_placement: OpeningPlacement,
    /// A paced opening's rate falls in a straight line from `opening_rate` at its first step to
    /// nothing after its last, so it asks about half as many and its answers thin out instead of
    /// stopping at once (false, the default: a flat rate; configs before it read so).
    #[serde(default, skip_serializing_if = "is_false")]
    pub opening_taper: bool,
}

fn is_ranked(placement: &OpeningPlacement) -> bool {
    *placement == OpeningPlacement::Ranked
}

impl FeedbackCeiling {
    /// The same ceiling with no opening: the opening's pace, placement, taper and repayment go
    /// with it (as [`DEFAULT_CEILING`] has them), so a config never carries settings of an
    /// opening that does not run; the rate, burst, floor and empty start stay. The opening's
    /// length is set to 0 here, not taken from the default, which a task may one day open.
    pub fn without_opening(self) -> Self {
        Self {
            rate: self.rate,
            burst: self.burst,
            floor: self.floor,
            start_empty: self.start_empty,
            opening: 0,
            ..DEFAULT_CEILING
        }
    }

    /// The same ceiling with its opening unpaced (every step the authors' ranking asks): the
    /// pace's placement and taper go with it (as [`DEFAULT_CEILING`] has them), so a config
    /// never carries a placement of a pace that does not run; the opening and its repayment stay.
    pub fn without_pace(self) -> Self {
        Self {
            opening_rate: None,
            opening_placement: DEFAULT_CEILING.opening_placement,
            opening_taper: DEFAULT_CEILING.opening_taper,
            ..self
        }
    }

    /// The bucket that holds the rule to this ceiling.
    pub fn budget(&self) -> AskBudget {
        let mut budget = AskBudget::new(self.rate, self.burst)
            .opening_for(self.opening)
            .repaying(self.repay_share);
        if let Some(rate) = self.opening_rate {
            budget = budget.opening_at(rate);
        }
        if self.opening_taper {
            budget = budget.tapering();
        }
        if self.start_empty {
            budget = budget.starting_empty();
        }
        match self.floor {
            Some(floor) => budget.following_answers(floor),
            None => budget,
        }
    }
}

/// A ceiling on the rate, the product DREF's and the one `max_feedback_rate` sets on any rule:
/// 10 % of the steps (the paper's DREF asked 1.6-8.4 %), at most 20 queries in a row (one second
/// of a human session at 20 Hz). At 5 % the masked critic had too few answers: Reaching stalled
/// on 4 seeds of 10 and Placing failed on seeds a 10 % ceiling learns (docs/dref.md,
/// docs/results/dref-ablation/).
pub const DEFAULT_CEILING: FeedbackCeiling = FeedbackCeiling {
    rate: 0.1,
    burst: 20,
    floor: None,
    opening: 0,
    start_empty: false,
    repay_share: 1.0,
    opening_rate: None,
    opening_placement: OpeningPlacement::Ranked,
    repayment_placement: OpeningPlacement::Ranked,
    opening_taper: false,
};
/// The product DREF's silence wake: after 1,000 steps without a query the rule ranks the current
/// state among the states of that silence, so it cannot freeze, and otherwise ranks as the
/// authors do, among every state with feedback (docs/dref.md).
pub const DEFAULT_WAKE_AFTER: u64 = 1_000;
/// The product DREF's opening: the run's first 2,000 steps ask as the authors' rule would (its
/// first answers are what teach Placing's learner the way), and what they borrow from the
/// ceiling is repaid from later earnings, so no flood passes the 2k grace (docs/dref.md).
/// The bucket starts empty, so a run that has repaid has asked at most 10 % of its steps.
pub const DEFAULT_OPENING: u64 = 2_000;
/// The share of each step's earnings that repays the product's opening: the rest stays askable,
/// so the rule is not silent for the whole repayment (12k-18k steps on Placing, where a silence
/// of a failing learner is a freeze; docs/dref.md).
pub const DEFAULT_REPAY_SHARE: f64 = 0.9;

/// Lunar Lander's product opening: its first 30,000 steps (the stretch in which EF-100 takes off),
/// asked at [`LUNAR_LANDER_OPENING_RATE`] of each abstract state's visits. Five seeds at 150k:
/// 66.6k +- 14.2k at 9.06 %, 4 of 5 learn, 0.89 of EF-100, against -8.5k +- 20.0k at 1.76 %, none
/// learns, with the 2,000-step opening (docs/results/fig3-lunar-lander-150k/lunar-lander/dref/).
pub const LUNAR_LANDER_OPENING: u64 = 30_000;
/// The share of each state's visits Lunar Lander's opening asks: 13,500 answers in 30k steps,
/// repaid by about 150k steps so a run stays near 9 % of its steps.
pub const LUNAR_LANDER_OPENING_RATE: f64 = 0.45;

/// The product's opening on `task`, a per-task constant as c and k are: the authors' asking for
/// the run's first [`DEFAULT_OPENING`] steps (their first answers are what teach Placing's learner
/// the way), but on Lunar Lander, whose learner takes off only with some thousands of answers in
/// its first 30k steps (EF-100 takes off at 9-31k steps; the 2,000-step opening gave 935-1,306
/// answers by 15k and no seed of five learnt), [`LUNAR_LANDER_OPENING`] steps asked at
/// [`LUNAR_LANDER_OPENING_RATE`] of each abstract state's own visits (docs/dref.md, "Lunar
/// Lander's opening").
fn products_opening(task: Task) -> FeedbackCeiling {
    match task {
        Task::LunarLander => FeedbackCeiling {
            opening: LUNAR_LANDER_OPENING,
            opening_rate: Some(LUNAR_LANDER_OPENING_RATE),
            opening_placement: OpeningPlacement::ByVisits,
            ..DEFAULT_CEILING
        },
        Task::Reaching | Task::Placing => FeedbackCeiling {
            opening: DEFAULT_OPENING,
            ..DEFAULT_CEILING
        },
    }
}

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
        match method {
            EvaluativeMethod::Dref => Self::for_task(task).products(task),
            _ => Self::for_task(task),
        }
    }

    /// The product's rule on these constants (docs/dref.md): the authors' ranking, woken after a
    /// silence, under a 10 % ceiling that opens with the task's opening and repays it from 90 % of
    /// its earnings.
    fn products(self, task: Task) -> Self {
        Self {
            rank_window: 0,
            ceiling: Some(FeedbackCeiling {
                start_empty: true,
                repay_share: DEFAULT_REPAY_SHARE,
                ..products_opening(task)
            }),
            wake_after: DEFAULT_WAKE_AFTER,
            ..self
        }
    }

    /// The running rule these constants describe.
    pub fn build(&self) -> QueryRule {
        let mut rule = QueryRule::new(self.c, self.k, self.form);
        if self.rank_window > 0 {
            rule = rule.ranked_among_recent(self.rank_window);
        }
        if let Some(ceiling) = self.ceiling {
            rule = rule.with_ceiling(ceiling.budget());
            if ceiling.opening_placement == OpeningPlacement::ByVisits {
                rule = rule.opening_by_visits();
            }
            if ceiling.repayment_placement == OpeningPlacement::ByVisits {
                rule = rule.repayment_by_visits();
            }
        }
        if self.wake_after > 0 {
            rule = rule.waking_after(self.wake_after);
        }
        rule
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
    /// No query from this step on (`None`: the method asks to the run's end, as the paper's
    /// do). A probe of when answers matter: EF-100 until a tenth of the steps spends a 10 %
    /// budget as densely and as early as any rule could.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feedback_until: Option<u64>,
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

pub(crate) fn is_default<T: Default + PartialEq>(value: &T) -> bool {
    *value == T::default()
}

/// The observation the scene graph reads on an episode's last step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
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
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(utoipa::ToSchema))]
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
/// 30 to 1 at a few percent of feedback, and read by the actor with `products_mix`
/// (docs/dref.md).
fn human_critic_for(method: EvaluativeMethod, products_mix: ActorMix) -> Option<HumanCriticConfig> {
    match method {
        EvaluativeMethod::Sac => None,
        EvaluativeMethod::Dref => Some(HumanCriticConfig {
            mask: true,
            mix: products_mix,
            ..HumanCriticConfig::default()
        }),
        EvaluativeMethod::Ef { .. } | EvaluativeMethod::DrefAuthors => {
            Some(HumanCriticConfig::default())
        }
    }
}

/// How the product DREF's actor reads the masked human critic on `task`: a per-task constant,
/// as the paper's c, k and network sizes are (docs/dref.md, "The rule", change 4). Where
/// the environment's reward leads the learner without a person (SAC alone learns Reaching;
/// Lunar Lander's shaping rewards every step), H's extrapolation to steps nobody answered costs
/// reward, so the actor reads H only where a person answered. Where it does not (Placing, which
/// SAC alone never learns), that extrapolation is what carries the learner to the hoop, so the
/// actor reads H everywhere, as the authors' code does. A declared task gets the authors' mix
/// with Placing's c and k.
fn products_mix(task: Task) -> ActorMix {
    match task {
        Task::Reaching | Task::LunarLander => ActorMix::Answered,
        Task::Placing => ActorMix::Authors,
    }
}

impl EvaluativeRunConfig {
    /// The published defaults for `task` and `method`: plain SAC has no human critic, EF and
    /// DREF have one with the authors' actor mix; the product's `dref` regresses it on answered
    /// steps only, has the actor read it by the task's mix and asks by its own rule
    /// (`docs/dref.md`).
    pub fn new(task: Task, method: EvaluativeMethod, seed: u64) -> Self {
        let mut sac = SacConfig::for_task(task);
        sac.human_critic = human_critic_for(method, products_mix(task));
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
            feedback_until: None,
            teacher: TeacherFaults::default(),
            oracle: OracleConfig::default(),
            graph_at_episode_end: GraphAtEpisodeEnd::Step,
            time_limit: TimeLimitEnd::Truncation,
        }
    }

    /// The defaults for a task an env in another process declared, with its `graph`:
    /// stable-baselines3's SAC (two layers of 256, learning rate 3e-4, batch 256, tau 0.005)
    /// and Placing's query rule (c 0.2, k 4: the authors' largest c with a k for a graph of a
    /// handful of predicates; set `c` and `k` for another).
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
            human_critic: human_critic_for(method, ActorMix::Authors),
            critic_loss: CriticLoss::Mse,
            critic_layer_norm: false,
        };
        // A declared task is asked as Placing is, its opening included.
        let query_rule = QueryRuleConfig::for_method(Task::Placing, method);
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
            feedback_until: None,
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
