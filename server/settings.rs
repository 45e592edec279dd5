//! Every setting a run or a session takes by name, as one typed list: [`Settings`]. A launch
//! request's `params`, the CLI's `--set key=value` and `--config` TOML files all deserialise
//! into it (an unknown key or a value of the wrong type is refused by serde, with the list of
//! known keys); [`Settings::session`], [`Settings::evaluative`] and [`Settings::preference`]
//! check ranges and which task and method each setting applies to, once; `GET /api/tasks` and the dashboard's advanced form read
//! [`Settings::defaults`]. No IO.
//!
//! A setting left out keeps the published default (algorithms.md, tasks.md), so a stored
//! session's settings are exactly what its researcher gave.
//!
//! Here: the list, its session settings and defaults. `run_configs`: reading it into an
//! evaluative or a preference run's configuration and an env's options; `people`: the settings
//! of trainers and simulated teachers.

use serde::{Deserialize, Deserializer, Serialize};

use crate::guidance::drpl::acquisition::Acquisition;
use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::evaluative_run::{
    DEFAULT_CEILING, EvaluativeRunConfig, GraphAtEpisodeEnd, TimeLimitEnd,
};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::guidance::query_rule::UcbForm;
use crate::rl::ActorMix;
use crate::rl::kernels::KernelPath;
use crate::scene_graph::SceneGraph;
use crate::sim::{GripObservation, PlacingSuccess, Start, Task, Variant};

mod as_run;
mod people;
mod run_configs;

pub use crate::session::combine::Combine;
pub use as_run::{Profile, SceneGraphChoice};
pub use people::{NeverWord, RationalWord, TeacherBeta, TeacherSkip};

/// A human session's control rate when the researcher does not set `pace_hz`: the robot's own.
pub const DEFAULT_PACE_HZ: f64 = 20.0;
/// How long a query waits for a person before it counts as "no feedback" (or a skipped pair).
pub const DEFAULT_ANSWER_TIMEOUT_S: f64 = 60.0;
/// Environment steps between periodic checkpoints of evaluative sessions.
pub const DEFAULT_CHECKPOINT_EVERY: u64 = 5_000;
/// Frames of the clip that leads up to an evaluative query (1.5 s at 20 Hz).
pub const DEFAULT_CLIP_FRAMES: usize = 30;
/// Seconds a remote env may take to answer one request (a robot's reset included).
pub const DEFAULT_ENV_TIMEOUT_S: f64 = 30.0;

/// Which runs a setting shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// SAC, EF-p% and DREF (`dualrep train`, evaluative sessions).
    Evaluative,
    /// DRPL and its baselines (`dualrep prefs`, preference sessions).
    Preference,
}

/// SAC's target entropy: SB3's `-dim(A)` ("auto") or a number.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(untagged)]
pub enum TargetEntropy {
    Auto(AutoWord),
    Value(f32),
}

/// The word `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum AutoWord {
    Auto,
}

/// Every setting by name. `None` keeps the default for the run's task and method.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Settings {
    // ---- the session (the server's human and synthetic sessions) -------------------------
    /// Steps per second of a human session while people watch [default 20, at most 1000].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pace_hz: Option<f64>,
    /// Seconds a query waits for a person before it counts as "no feedback" [default 60].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub answer_timeout_s: Option<f64>,
    /// Steps (or queries) between a session's checkpoints [default 5000].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_every: Option<u64>,
    /// Frames of the clip before an evaluative query [default 30].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clip_frames: Option<usize>,
    /// Write the session's Rerun recording [default true].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub record: Option<bool>,
    /// Also stream the session to a running Rerun viewer at this URL.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rerun_connect: Option<String>,
    /// Seconds a remote env (`env: {"url": ...}`) may take to answer one request [default 30].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub env_timeout_s: Option<f64>,
    /// The kernels the session's networks compute with: `portable`, `avx2` or `avx512` [default
    /// the server's, recorded at launch so that a resume replays with the same numerics].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kernels: Option<KernelPath>,
    /// Answers each query takes from different named trainers [default 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub answers_per_query: Option<usize>,
    /// How a query's answers combine: `first` (one answer, the first), `majority` or `mean`
    /// (evaluative), `each` (preference: every answer its own observation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub combine: Option<Combine>,

    // ---- the synthetic teacher's faults (algorithms.md section 4, after B-Pref) ------------
    /// Boltzmann rationality: a number, or `rational` (never errs by chance) [default].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teacher_beta: Option<TeacherBeta>,
    /// Myopic discount in (0, 1] [default 1: not myopic].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teacher_gamma: Option<f64>,
    /// Probability that an answer is flipped [default 0].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teacher_error: Option<f64>,
    /// Skip what is worth less than this: a number, or `never` [default].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teacher_skip: Option<TeacherSkip>,
    /// Answer "about equal" (evaluative: 0) below this margin [default 0].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teacher_equal: Option<f64>,

    // ---- SAC (algorithms.md section 1) ---------------------------------------------------
    /// Hidden layer sizes of the actor and every critic, e.g. `[256, 256]` or `"256,256"`.
    #[serde(
        default,
        deserialize_with = "layer_sizes",
        skip_serializing_if = "Option::is_none"
    )]
    pub hidden: Option<Vec<usize>>,
    /// Adam's learning rate (actor, critics, temperature).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learning_rate: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub batch_size: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub buffer_size: Option<usize>,
    /// Polyak coefficient, in [0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau: Option<f32>,
    /// Discount, in [0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gamma: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learning_starts: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gradient_steps: Option<usize>,
    /// Initial entropy temperature.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init_ent_coef: Option<f32>,
    /// `"auto"` (-dim(A)) or a number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_entropy: Option<TargetEntropy>,
    /// DREF's human critic on or off (on for DREF and EF, off for SAC).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub human_critic: Option<bool>,
    /// Weight of the human critic against Q in the actor loss (the authors: 9).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f32>,
    /// How the actor mixes Q and H: `authors` (head-wise) or `paper` (Eq. 5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mix: Option<ActorMix>,
    /// Regress the human critic only on transitions that had feedback.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub human_critic_mask: Option<bool>,

    // ---- DREF (algorithms.md section 2) --------------------------------------------------
    /// The query rule's exploration constant c.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c: Option<f64>,
    /// The query rule asks iff at most k ranked states score higher.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<usize>,
    /// The UCB form: `authors` or `paper`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ucb: Option<UcbForm>,
    /// Rank the current state among those visited in the last N steps; 0: among every state
    /// with feedback, the authors' [default 1000 for `dref`, 0 for `dref-authors`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rank_window: Option<usize>,
    /// Ask on at most this share of steps, in (0, 1]; 0: no ceiling, the authors' [default 0.05
    /// for `dref`, 0 for `dref-authors`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_feedback_rate: Option<f64>,
    /// With a ceiling: at most about this many queries in a row [default 20].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feedback_burst: Option<u32>,
    /// With a ceiling: let the rate run from this floor (recent answers all "good") up to
    /// `max_feedback_rate` (all "bad"); 0: a fixed rate [default 0].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_feedback_rate: Option<f64>,
    /// After this many steps without a query, rank the current state among the states visited
    /// during that silence instead of among every state with feedback, until the rule asks
    /// again; 0: never, the authors' [default 0].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wake_after: Option<u64>,
    /// The learner stores `reward_scale * r`; reported returns keep the env's scale.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reward_scale: Option<f32>,
    /// A person's pace: at most this many queries in any minute at `pace_hz` (0: no limit,
    /// the paper's behaviour) [default 0].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_queries_per_minute: Option<u32>,

    // ---- the authors' published runs (issue 33, `settings/as_run.rs`) --------------------
    /// `head` (the authors' repository at its head, algorithms.md) or `as-run` (what their
    /// published runs ran, per task; the settings below, given, override it) [default head].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<Profile>,
    /// The synthetic oracle's alpha at step 0 (it grows 1e-8 a step) [default 0.999].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub oracle_alpha0: Option<f64>,
    /// Factor on both actions the oracle's critic and H_hat are shown [default 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub oracle_action_scale: Option<f32>,
    /// Which observation the scene graph reads on an episode's last step: `step` or `reset`
    /// [default step].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub graph_at_episode_end: Option<GraphAtEpisodeEnd>,
    /// How a time limit's end is stored: `truncation` or `terminal` [default truncation].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_limit: Option<TimeLimitEnd>,

    // ---- the scene graph -----------------------------------------------------------------
    /// Lunar Lander: test both side engines on a0, as the authors' code does.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side_engines_on_a0: Option<bool>,
    /// Placing: `head` (36 cells) or `as-run` (the published runs' 12 cells).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_graph: Option<SceneGraphChoice>,

    // ---- the task's version (tasks.md; Reaching and Placing) -----------------------------
    /// `authors` (home pose, 1.2 cm steps, gradual gripper) or `uniform` (the first version).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variant: Option<Variant>,
    /// Where episodes start: `home` (the authors' variant) or `uniform` (anywhere over the
    /// table; the first version, and DRPL's random trajectories as in the paper).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<Start>,
    /// Placing: `over` (released over the opening) or `through` (fallen through it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub success: Option<PlacingSuccess>,
    /// Placing: the observation's fourth entry is the last command's `sign` or the `level`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observe_grip: Option<GripObservation>,
    /// Placing (authors' variant): the ball drops once the gripper's level is at or below this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub release_at: Option<f32>,

    // ---- DRPL (algorithms.md section 3) --------------------------------------------------
    /// Random trajectories recorded for the query pool.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trajectories: Option<usize>,
    /// Step limit per trajectory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<usize>,
    /// Runs of one abstract state shorter than this merge into the previous segment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_run: Option<usize>,
    /// The final pick among candidate pairs: `uniform` or `mutual_information`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub acquisition: Option<Acquisition>,
    /// Rationality of the softmax user model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta: Option<f64>,
    /// The weak-comparison model's perceivable difference ("about equal").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delta: Option<f64>,
    /// Metropolis-Hastings proposal step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub proposal_std: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub burn_in: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thinning: Option<usize>,
    /// Posterior samples kept per update.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
}

/// `hidden` as a list of layer sizes, the CLI's comma-separated text, or one number.
fn layer_sizes<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<usize>>, D::Error> {
    use serde_json::Value;
    let value = Value::deserialize(d)?;
    let size = |v: &Value| v.as_u64().map(|n| n as usize);
    let sizes = match &value {
        Value::Array(items) => items.iter().map(size).collect::<Option<Vec<_>>>(),
        Value::String(text) => text
            .split(',')
            .map(|s| s.trim().parse::<usize>().ok())
            .collect(),
        Value::Number(_) => size(&value).map(|n| vec![n]),
        _ => None,
    };
    sizes.map(Some).ok_or_else(|| {
        serde::de::Error::custom(format!(
            "hidden: expected layer sizes such as [256, 256] or \"256,256\", got {value}"
        ))
    })
}

/// The session's own settings, with their defaults filled in.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SessionSettings {
    pub pace_hz: f64,
    pub answer_timeout_s: f64,
    pub checkpoint_every: u64,
    pub clip_frames: usize,
    /// Write the session's Rerun recording (`<data dir>/recordings/<id>.rrd`).
    pub record: bool,
    /// Also stream to a running Rerun viewer at this URL (else the server's `--rerun-connect`).
    pub rerun_connect: Option<String>,
    /// Seconds a remote env may take to answer one request.
    pub env_timeout_s: f64,
    /// The kernels the session computes with; `None` for sessions stored before they were
    /// recorded (the server's then).
    pub kernels: Option<KernelPath>,
    /// Answers each query takes (from different named trainers).
    pub answers_per_query: usize,
    /// How they combine.
    pub combine: Combine,
}

impl Settings {
    /// Settings from `key=value` pairs (the CLI's `--set`, in order; a later key wins). A value
    /// is read as JSON where it is JSON (`0.3`, `true`, `[64, 64]`) and as text otherwise
    /// (`paper`, `256,256`).
    pub fn from_pairs<'a>(
        pairs: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> Result<Self, String> {
        let mut map = serde_json::Map::new();
        for (key, text) in pairs {
            let value = serde_json::from_str::<serde_json::Value>(text)
                .ok()
                .filter(|v| !v.is_object() && !v.is_string())
                .unwrap_or_else(|| serde_json::Value::String(text.to_string()));
            map.insert(key.to_string(), value);
        }
        Self::from_json(serde_json::Value::Object(map))
    }

    /// Settings from a JSON object (a launch request's `params`, a TOML file read as JSON).
    pub fn from_json(value: serde_json::Value) -> Result<Self, String> {
        // The path names the setting in type errors ("beta: invalid type: string ...").
        serde_path_to_error::deserialize(value).map_err(|e| match e.path().to_string() {
            path if path == "." => e.into_inner().to_string(),
            path => format!("{path}: {}", e.into_inner()),
        })
    }

    /// `other`'s settings over ours.
    pub fn merged(self, other: Settings) -> Result<Self, String> {
        let mut base = serde_json::to_value(self).map_err(|e| e.to_string())?;
        let over = serde_json::to_value(other).map_err(|e| e.to_string())?;
        if let (Some(base), Some(over)) = (base.as_object_mut(), over.as_object()) {
            for (k, v) in over {
                base.insert(k.clone(), v.clone());
            }
        }
        Self::from_json(base)
    }

    /// The session settings with defaults, checked.
    pub fn session(&self) -> Result<SessionSettings, String> {
        let positive = |key: &str, v: Option<f64>, default: f64| -> Result<f64, String> {
            match v {
                None => Ok(default),
                Some(x) if x.is_finite() && x > 0.0 => Ok(x),
                Some(x) => Err(format!("{key}: expected a positive number, got {x}")),
            }
        };
        let pace_hz = positive("pace_hz", self.pace_hz, DEFAULT_PACE_HZ)?;
        if pace_hz > 1000.0 {
            return Err(format!("pace_hz: at most 1000, got {pace_hz}"));
        }
        let at_least_one = |key: &str, v: Option<u64>, default: u64| -> Result<u64, String> {
            match v {
                None => Ok(default),
                Some(0) => Err(format!("{key}: expected at least 1")),
                Some(n) => Ok(n),
            }
        };
        if self.rerun_connect.as_deref() == Some("") {
            return Err("rerun_connect: expected a viewer URL, got an empty string".into());
        }
        let (answers_per_query, combine) = people::answers(self.answers_per_query, self.combine)?;
        Ok(SessionSettings {
            pace_hz,
            answer_timeout_s: positive(
                "answer_timeout_s",
                self.answer_timeout_s,
                DEFAULT_ANSWER_TIMEOUT_S,
            )?,
            checkpoint_every: at_least_one(
                "checkpoint_every",
                self.checkpoint_every,
                DEFAULT_CHECKPOINT_EVERY,
            )?,
            clip_frames: at_least_one(
                "clip_frames",
                self.clip_frames.map(|n| n as u64),
                DEFAULT_CLIP_FRAMES as u64,
            )? as usize,
            record: self.record.unwrap_or(true),
            rerun_connect: self.rerun_connect.clone(),
            env_timeout_s: positive("env_timeout_s", self.env_timeout_s, DEFAULT_ENV_TIMEOUT_S)?,
            kernels: self.kernels,
            answers_per_query,
            combine,
        })
    }

    /// The names of the session's own settings that are set (a headless run has no session).
    pub fn session_keys_set(&self) -> Vec<&'static str> {
        let Settings {
            pace_hz,
            answer_timeout_s,
            checkpoint_every,
            clip_frames,
            record,
            rerun_connect,
            env_timeout_s,
            kernels,
            answers_per_query,
            combine,
            ..
        } = self;
        [
            ("pace_hz", pace_hz.is_some()),
            ("answer_timeout_s", answer_timeout_s.is_some()),
            ("checkpoint_every", checkpoint_every.is_some()),
            ("clip_frames", clip_frames.is_some()),
            ("record", record.is_some()),
            ("rerun_connect", rerun_connect.is_some()),
            ("env_timeout_s", env_timeout_s.is_some()),
            ("kernels", kernels.is_some()),
            ("answers_per_query", answers_per_query.is_some()),
            ("combine", combine.is_some()),
        ]
        .into_iter()
        .filter(|(_, set)| *set)
        .map(|(k, _)| k)
        .collect()
    }

    /// Every setting that applies to `task` and `family`, at its default: what `GET /api/tasks`
    /// offers and the dashboard's advanced form shows. Session settings are included.
    pub fn defaults(task: Task, family: Family) -> Settings {
        let session = Settings {
            pace_hz: Some(DEFAULT_PACE_HZ),
            answer_timeout_s: Some(DEFAULT_ANSWER_TIMEOUT_S),
            checkpoint_every: Some(DEFAULT_CHECKPOINT_EVERY),
            clip_frames: Some(DEFAULT_CLIP_FRAMES),
            record: Some(true),
            env_timeout_s: Some(DEFAULT_ENV_TIMEOUT_S),
            answers_per_query: Some(1),
            combine: Some(Combine::First),
            ..people::teacher_defaults()
        };
        let table_top = task != Task::LunarLander;
        let placing = task == Task::Placing;
        let side_engines_on_a0 = match SceneGraph::for_task(task) {
            SceneGraph::LunarLander { side_engines_on_a0 } => Some(side_engines_on_a0),
            _ => None,
        };
        match family {
            Family::Evaluative => {
                let c = EvaluativeRunConfig::new(task, EvaluativeMethod::Dref, 0);
                let critic = c.sac.human_critic.clone().unwrap_or_default();
                Settings {
                    hidden: Some(c.sac.hidden.clone()),
                    learning_rate: Some(c.sac.learning_rate),
                    batch_size: Some(c.sac.batch_size),
                    buffer_size: Some(c.sac.buffer_size),
                    tau: Some(c.sac.tau),
                    gamma: Some(c.sac.gamma),
                    learning_starts: Some(c.sac.learning_starts),
                    gradient_steps: Some(c.sac.gradient_steps),
                    init_ent_coef: Some(c.sac.init_ent_coef),
                    target_entropy: Some(
                        c.sac
                            .target_entropy
                            .map_or(TargetEntropy::Auto(AutoWord::Auto), TargetEntropy::Value),
                    ),
                    human_critic: Some(true),
                    lambda: Some(critic.lambda),
                    mix: Some(critic.mix),
                    human_critic_mask: Some(critic.mask),
                    c: Some(c.query_rule.c),
                    k: Some(c.query_rule.k),
                    ucb: Some(c.query_rule.form),
                    rank_window: Some(c.query_rule.rank_window),
                    max_feedback_rate: Some(c.query_rule.ceiling.map_or(0.0, |x| x.rate)),
                    feedback_burst: Some(
                        c.query_rule
                            .ceiling
                            .map_or(DEFAULT_CEILING.burst, |x| x.burst),
                    ),
                    min_feedback_rate: Some(
                        c.query_rule.ceiling.and_then(|x| x.floor).unwrap_or(0.0),
                    ),
                    wake_after: Some(c.query_rule.wake_after),
                    reward_scale: Some(c.reward_scale),
                    max_queries_per_minute: Some(0),
                    profile: Some(Profile::Head),
                    oracle_alpha0: Some(c.oracle.alpha0),
                    oracle_action_scale: Some(c.oracle.action_scale),
                    graph_at_episode_end: Some(c.graph_at_episode_end),
                    time_limit: Some(c.time_limit),
                    scene_graph: placing.then_some(SceneGraphChoice::Head),
                    side_engines_on_a0,
                    variant: table_top.then_some(c.env.variant),
                    start: table_top.then(|| c.env.start_pose()),
                    success: placing.then(|| c.env.placing_success()),
                    observe_grip: placing.then_some(c.env.observe_grip),
                    release_at: placing.then_some(c.env.release_at),
                    ..session
                }
            }
            Family::Preference => {
                let c = PreferenceRunConfig::new(task, QueryMethod::Drpl, 0);
                Settings {
                    trajectories: Some(c.trajectories),
                    max_steps: Some(c.max_steps),
                    min_run: Some(c.min_run),
                    acquisition: Some(c.acquisition),
                    beta: Some(c.belief.beta),
                    delta: Some(c.belief.delta),
                    proposal_std: Some(c.belief.proposal_std),
                    burn_in: Some(c.belief.burn_in),
                    thinning: Some(c.belief.thinning),
                    samples: Some(c.belief.samples),
                    side_engines_on_a0,
                    variant: table_top.then_some(c.env.variant),
                    start: table_top.then(|| c.env.start_pose()),
                    success: placing.then(|| c.env.placing_success()),
                    observe_grip: placing.then_some(c.env.observe_grip),
                    release_at: placing.then_some(c.env.release_at),
                    ..session
                }
            }
        }
    }
}

#[cfg(test)]
mod pinned;
#[cfg(test)]
mod tests;
