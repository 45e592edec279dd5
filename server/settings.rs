//! Every setting a run or a session takes by name, as one typed list: [`Settings`]. A launch
//! request's `params`, the CLI's `--set key=value` and `--config` TOML files all deserialise
//! into it (an unknown key or a value of the wrong type is refused by serde, with the list of
//! known keys); [`Settings::validate`] checks ranges and which task and method each setting
//! applies to, once; `GET /api/tasks` and the dashboard's advanced form read
//! [`Settings::defaults`]. No IO.
//!
//! A setting left out keeps the published default (algorithms.md, tasks.md), so a stored
//! session's settings are exactly what its researcher gave.

use serde::{Deserialize, Deserializer, Serialize};

use crate::guidance::drpl::acquisition::Acquisition;
use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::guidance::human_pace::HumanPace;
use crate::guidance::query_rule::UcbForm;
use crate::rl::kernels::KernelPath;
use crate::rl::{ActorMix, HumanCriticConfig, SacConfig};
use crate::scene_graph::SceneGraph;
use crate::sim::{EnvOptions, GripObservation, PlacingSuccess, Start, Task, TaskRef, Variant};

mod people;

pub use crate::session::combine::Combine;
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
    /// The learner stores `reward_scale * r`; reported returns keep the env's scale.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reward_scale: Option<f32>,
    /// A person's pace: at most this many queries in any minute at `pace_hz` (0: no limit,
    /// the paper's behaviour) [default 0].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_queries_per_minute: Option<u32>,

    // ---- the scene graph -----------------------------------------------------------------
    /// Lunar Lander: test both side engines on a0, as the authors' code does.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side_engines_on_a0: Option<bool>,

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

    /// An evaluative run's configuration: the published defaults for `task` and `method`, then
    /// every setting given. Refuses settings of preference runs, of other tasks, and values out
    /// of range. Session settings are not the algorithm's and are left to [`Settings::session`].
    pub fn evaluative(
        &self,
        task: Task,
        method: EvaluativeMethod,
        seed: u64,
    ) -> Result<EvaluativeRunConfig, String> {
        self.apply_evaluative(EvaluativeRunConfig::new(task, method, seed))
    }

    /// [`Settings::evaluative`] over given defaults (a declared task's, see
    /// [`EvaluativeRunConfig::declared`]).
    pub fn apply_evaluative(
        &self,
        mut config: EvaluativeRunConfig,
    ) -> Result<EvaluativeRunConfig, String> {
        let method = config.method;
        let task = config.task.clone();
        let Settings {
            pace_hz: _,
            answer_timeout_s: _,
            checkpoint_every: _,
            clip_frames: _,
            record: _,
            rerun_connect: _,
            env_timeout_s: _,
            kernels: _,
            answers_per_query: _,
            combine: _,
            teacher_beta: _,
            teacher_gamma: _,
            teacher_error: _,
            teacher_skip: _,
            teacher_equal: _,
            hidden,
            learning_rate,
            batch_size,
            buffer_size,
            tau,
            gamma,
            learning_starts,
            gradient_steps,
            init_ent_coef,
            target_entropy,
            human_critic,
            lambda,
            mix,
            human_critic_mask,
            c,
            k,
            ucb,
            reward_scale,
            max_queries_per_minute,
            side_engines_on_a0,
            variant,
            start,
            success,
            observe_grip,
            release_at,
            trajectories,
            max_steps,
            min_run,
            acquisition,
            beta,
            delta,
            proposal_std,
            burn_in,
            thinning,
            samples,
        } = self;
        let preference_only = [
            ("trajectories", trajectories.is_some()),
            ("max_steps", max_steps.is_some()),
            ("min_run", min_run.is_some()),
            ("acquisition", acquisition.is_some()),
            ("beta", beta.is_some()),
            ("delta", delta.is_some()),
            ("proposal_std", proposal_std.is_some()),
            ("burn_in", burn_in.is_some()),
            ("thinning", thinning.is_some()),
            ("samples", samples.is_some()),
        ];
        if let Some((key, _)) = preference_only.iter().find(|(_, set)| *set) {
            return Err(format!(
                "{key} is a setting of preference methods (drpl, drpl-ss, fragment, full), not {method}"
            ));
        }
        let sac = &mut config.sac;
        if let Some(h) = hidden {
            if h.is_empty() || h.contains(&0) {
                return Err(format!("hidden: expected positive layer sizes, got {h:?}"));
            }
            sac.hidden = h.clone();
        }
        set_positive(&mut sac.learning_rate, *learning_rate, "learning_rate")?;
        set_count(&mut sac.batch_size, *batch_size, "batch_size")?;
        set_count(&mut sac.buffer_size, *buffer_size, "buffer_size")?;
        set_unit(&mut sac.tau, *tau, "tau")?;
        set_unit(&mut sac.gamma, *gamma, "gamma")?;
        if let Some(n) = learning_starts {
            sac.learning_starts = *n;
        }
        if let Some(n) = gradient_steps {
            sac.gradient_steps = *n;
        }
        set_positive(&mut sac.init_ent_coef, *init_ent_coef, "init_ent_coef")?;
        match target_entropy {
            None => {}
            Some(TargetEntropy::Auto(_)) => sac.target_entropy = None,
            Some(TargetEntropy::Value(v)) if v.is_finite() => sac.target_entropy = Some(*v),
            Some(TargetEntropy::Value(v)) => {
                return Err(format!("target_entropy: expected a finite number, got {v}"));
            }
        }
        if let Some(on) = human_critic {
            sac.human_critic = on.then(|| sac.human_critic.clone().unwrap_or_default());
        }
        // Any of the human critic's own settings switches it on (with defaults for the rest).
        if let Some(l) = lambda {
            if !(l.is_finite() && *l >= 0.0) {
                return Err(format!("lambda: expected a number >= 0, got {l}"));
            }
            critic(sac).lambda = *l;
        }
        if let Some(m) = mix {
            critic(sac).mix = *m;
        }
        if let Some(m) = human_critic_mask {
            critic(sac).mask = *m;
        }
        if let Some(c) = c {
            if !c.is_finite() || *c < 0.0 {
                return Err(format!("c: expected a number >= 0, got {c}"));
            }
            config.query_rule.c = *c;
        }
        if let Some(k) = k {
            config.query_rule.k = *k;
        }
        if let Some(form) = ucb {
            config.query_rule.form = *form;
        }
        set_positive(&mut config.reward_scale, *reward_scale, "reward_scale")?;
        if let Some(n) = max_queries_per_minute.filter(|n| *n > 0) {
            let pace_hz = self.session()?.pace_hz;
            config.human_pace = Some(HumanPace::new(n, pace_hz));
        }
        config.teacher = people::teacher_faults(self)?;
        apply_scene_graph(&mut config.scene_graph, *side_engines_on_a0)?;
        apply_env(
            &mut config.env,
            &task,
            EnvSettings {
                variant: *variant,
                start: *start,
                success: *success,
                observe_grip: *observe_grip,
                release_at: *release_at,
            },
        )?;
        Ok(config)
    }

    /// A preference run's configuration: defaults, then every setting given; refuses settings
    /// of evaluative runs and of other tasks.
    pub fn preference(
        &self,
        task: Task,
        method: QueryMethod,
        seed: u64,
    ) -> Result<PreferenceRunConfig, String> {
        self.apply_preference(PreferenceRunConfig::new(task, method, seed))
    }

    /// [`Settings::preference`] over given defaults (a declared task's, see
    /// [`PreferenceRunConfig::declared`]).
    pub fn apply_preference(
        &self,
        mut config: PreferenceRunConfig,
    ) -> Result<PreferenceRunConfig, String> {
        let method = config.method;
        let task = config.task.clone();
        let Settings {
            pace_hz: _,
            answer_timeout_s: _,
            checkpoint_every: _,
            clip_frames: _,
            record: _,
            rerun_connect: _,
            env_timeout_s: _,
            kernels: _,
            answers_per_query: _,
            combine: _,
            teacher_beta: _,
            teacher_gamma: _,
            teacher_error: _,
            teacher_skip: _,
            teacher_equal: _,
            hidden,
            learning_rate,
            batch_size,
            buffer_size,
            tau,
            gamma,
            learning_starts,
            gradient_steps,
            init_ent_coef,
            target_entropy,
            human_critic,
            lambda,
            mix,
            human_critic_mask,
            c,
            k,
            ucb,
            reward_scale,
            max_queries_per_minute,
            side_engines_on_a0,
            variant,
            start,
            success,
            observe_grip,
            release_at,
            trajectories,
            max_steps,
            min_run,
            acquisition,
            beta,
            delta,
            proposal_std,
            burn_in,
            thinning,
            samples,
        } = self;
        let evaluative_only = [
            ("hidden", hidden.is_some()),
            ("learning_rate", learning_rate.is_some()),
            ("batch_size", batch_size.is_some()),
            ("buffer_size", buffer_size.is_some()),
            ("tau", tau.is_some()),
            ("gamma", gamma.is_some()),
            ("learning_starts", learning_starts.is_some()),
            ("gradient_steps", gradient_steps.is_some()),
            ("init_ent_coef", init_ent_coef.is_some()),
            ("target_entropy", target_entropy.is_some()),
            ("human_critic", human_critic.is_some()),
            ("lambda", lambda.is_some()),
            ("mix", mix.is_some()),
            ("human_critic_mask", human_critic_mask.is_some()),
            ("c", c.is_some()),
            ("k", k.is_some()),
            ("ucb", ucb.is_some()),
            ("reward_scale", reward_scale.is_some()),
            ("max_queries_per_minute", max_queries_per_minute.is_some()),
        ];
        if let Some((key, _)) = evaluative_only.iter().find(|(_, set)| *set) {
            return Err(format!(
                "{key} is a setting of evaluative methods (dref, ef-<p>, sac), not {}",
                method.id()
            ));
        }
        let at_least = |key: &str, v: Option<usize>, min: usize| -> Result<Option<usize>, String> {
            match v {
                Some(n) if n < min => Err(format!("{key}: expected an integer >= {min}, got {n}")),
                other => Ok(other),
            }
        };
        if let Some(n) = at_least("trajectories", *trajectories, 2)? {
            config.trajectories = n;
        }
        if let Some(n) = at_least("max_steps", *max_steps, 1)? {
            config.max_steps = n;
        }
        if let Some(n) = at_least("min_run", *min_run, 1)? {
            config.min_run = n;
        }
        if let Some(a) = acquisition {
            config.acquisition = *a;
        }
        let belief = &mut config.belief;
        for (key, value, slot) in [
            ("beta", beta, &mut belief.beta),
            ("delta", delta, &mut belief.delta),
            ("proposal_std", proposal_std, &mut belief.proposal_std),
        ] {
            if let Some(x) = value {
                if !x.is_finite() {
                    return Err(format!("{key}: expected a finite number, got {x}"));
                }
                *slot = *x;
            }
        }
        if let Some(n) = burn_in {
            belief.burn_in = *n;
        }
        if let Some(n) = at_least("thinning", *thinning, 1)? {
            belief.thinning = n;
        }
        if let Some(n) = at_least("samples", *samples, 1)? {
            belief.samples = n;
        }
        config.teacher = people::teacher_faults(self)?;
        apply_scene_graph(&mut config.scene_graph, *side_engines_on_a0)?;
        apply_env(
            &mut config.env,
            &task,
            EnvSettings {
                variant: *variant,
                start: *start,
                success: *success,
                observe_grip: *observe_grip,
                release_at: *release_at,
            },
        )?;
        Ok(config)
    }

    /// The task's version alone (`dualrep sim`): refuses every setting but the env's.
    pub fn env_options(&self, task: Task) -> Result<EnvOptions, String> {
        let env_only = Settings {
            variant: self.variant,
            start: self.start,
            success: self.success,
            observe_grip: self.observe_grip,
            release_at: self.release_at,
            ..Settings::default()
        };
        if &env_only != self {
            return Err(
                "only the task's version can be set here: variant, start, success, observe_grip, release_at"
                    .into(),
            );
        }
        let mut options = EnvOptions::default();
        apply_env(
            &mut options,
            &task.into(),
            EnvSettings {
                variant: self.variant,
                start: self.start,
                success: self.success,
                observe_grip: self.observe_grip,
                release_at: self.release_at,
            },
        )?;
        Ok(options)
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
                    reward_scale: Some(c.reward_scale),
                    max_queries_per_minute: Some(0),
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

/// The human critic's config, switched on (with defaults) if it was off.
fn critic(sac: &mut SacConfig) -> &mut HumanCriticConfig {
    sac.human_critic.get_or_insert_default()
}

fn set_positive(slot: &mut f32, value: Option<f32>, key: &str) -> Result<(), String> {
    match value {
        None => Ok(()),
        Some(v) if v.is_finite() && v > 0.0 => {
            *slot = v;
            Ok(())
        }
        Some(v) => Err(format!("{key}: expected a positive number, got {v}")),
    }
}

fn set_unit(slot: &mut f32, value: Option<f32>, key: &str) -> Result<(), String> {
    match value {
        None => Ok(()),
        Some(v) if (0.0..=1.0).contains(&v) => {
            *slot = v;
            Ok(())
        }
        Some(v) => Err(format!("{key}: expected a number in [0, 1], got {v}")),
    }
}

fn set_count(slot: &mut usize, value: Option<usize>, key: &str) -> Result<(), String> {
    match value {
        None => Ok(()),
        Some(0) => Err(format!("{key}: expected at least 1")),
        Some(n) => {
            *slot = n;
            Ok(())
        }
    }
}

fn apply_scene_graph(
    graph: &mut SceneGraph,
    side_engines_on_a0: Option<bool>,
) -> Result<(), String> {
    match (side_engines_on_a0, graph) {
        (None, _) => Ok(()),
        (Some(on), SceneGraph::LunarLander { side_engines_on_a0 }) => {
            *side_engines_on_a0 = on;
            Ok(())
        }
        (Some(_), _) => Err("side_engines_on_a0 applies to lunar-lander only".into()),
    }
}

/// The settings of the task's version, as [`apply_env`] takes them.
struct EnvSettings {
    variant: Option<Variant>,
    start: Option<Start>,
    success: Option<PlacingSuccess>,
    observe_grip: Option<GripObservation>,
    release_at: Option<f32>,
}

fn apply_env(env: &mut EnvOptions, task: &TaskRef, given: EnvSettings) -> Result<(), String> {
    let builtin = task.builtin();
    let EnvSettings {
        variant,
        start,
        success,
        observe_grip,
        release_at,
    } = given;
    let table_top_only = |key: &str| -> Result<(), String> {
        if !matches!(builtin, Some(Task::Reaching | Task::Placing)) {
            Err(format!("{key} applies to reaching and placing, not {task}"))
        } else {
            Ok(())
        }
    };
    if let Some(v) = variant {
        table_top_only("variant")?;
        env.variant = v;
    }
    if let Some(s) = start {
        table_top_only("start")?;
        env.start = Some(s);
    }
    let placing_only = |key: &str| -> Result<(), String> {
        if builtin == Some(Task::Placing) {
            Ok(())
        } else {
            Err(format!("{key} applies to placing only, not {task}"))
        }
    };
    if let Some(s) = success {
        placing_only("success")?;
        env.success = Some(s);
    }
    if let Some(g) = observe_grip {
        placing_only("observe_grip")?;
        env.observe_grip = g;
    }
    if let Some(r) = release_at {
        placing_only("release_at")?;
        if !(-1.0..1.0).contains(&r) {
            return Err(format!("release_at: expected a number in [-1, 1), got {r}"));
        }
        env.release_at = r;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
