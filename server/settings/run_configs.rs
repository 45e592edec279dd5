//! Reading the settings into a run's configuration: the published defaults for the task and
//! method, then every setting given, each checked once against its range and against the
//! task and method family it belongs to.

use super::{Profile, SceneGraphChoice, Settings, TargetEntropy, as_run, people};
use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::evaluative_run::{
    DEFAULT_CEILING, EvaluativeRunConfig, FeedbackCeiling, QueryRuleConfig,
};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::guidance::human_pace::HumanPace;
use crate::rl::{HumanCriticConfig, SacConfig};
use crate::scene_graph::SceneGraph;
use crate::sim::{EnvOptions, GripObservation, PlacingSuccess, Start, Task, TaskRef, Variant};

impl Settings {
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
            rank_window,
            max_feedback_rate,
            feedback_burst,
            min_feedback_rate,
            wake_after,
            reward_scale,
            max_queries_per_minute,
            profile,
            oracle_alpha0,
            oracle_action_scale,
            graph_at_episode_end,
            time_limit,
            side_engines_on_a0,
            scene_graph,
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
        if *profile == Some(Profile::AsRun) {
            as_run::apply(&mut config)?;
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
        apply_query_pacing(
            &mut config.query_rule,
            *rank_window,
            *max_feedback_rate,
            *feedback_burst,
            *min_feedback_rate,
        )?;
        if let Some(steps) = wake_after {
            config.query_rule.wake_after = *steps;
        }
        set_positive(&mut config.reward_scale, *reward_scale, "reward_scale")?;
        if let Some(n) = max_queries_per_minute.filter(|n| *n > 0) {
            let pace_hz = self.session()?.pace_hz;
            config.human_pace = Some(HumanPace::new(n, pace_hz));
        }
        config.teacher = people::teacher_faults(self)?;
        if let Some(a) = oracle_alpha0 {
            if !(a.is_finite() && *a > 0.0 && *a <= 1.0) {
                return Err(format!(
                    "oracle_alpha0: expected a number in (0, 1], got {a}"
                ));
            }
            config.oracle.alpha0 = *a;
        }
        if let Some(s) = oracle_action_scale {
            if !(s.is_finite() && *s > 0.0) {
                return Err(format!(
                    "oracle_action_scale: expected a positive number, got {s}"
                ));
            }
            config.oracle.action_scale = *s;
        }
        if let Some(g) = graph_at_episode_end {
            config.graph_at_episode_end = *g;
        }
        if let Some(t) = time_limit {
            config.time_limit = *t;
        }
        apply_scene_graph(&mut config.scene_graph, *side_engines_on_a0, *scene_graph)?;
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
            rank_window,
            max_feedback_rate,
            feedback_burst,
            min_feedback_rate,
            wake_after,
            reward_scale,
            max_queries_per_minute,
            profile,
            oracle_alpha0,
            oracle_action_scale,
            graph_at_episode_end,
            time_limit,
            side_engines_on_a0,
            scene_graph,
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
            ("rank_window", rank_window.is_some()),
            ("max_feedback_rate", max_feedback_rate.is_some()),
            ("feedback_burst", feedback_burst.is_some()),
            ("min_feedback_rate", min_feedback_rate.is_some()),
            ("wake_after", wake_after.is_some()),
            ("reward_scale", reward_scale.is_some()),
            ("max_queries_per_minute", max_queries_per_minute.is_some()),
            ("profile", profile.is_some()),
            ("oracle_alpha0", oracle_alpha0.is_some()),
            ("oracle_action_scale", oracle_action_scale.is_some()),
            ("graph_at_episode_end", graph_at_episode_end.is_some()),
            ("time_limit", time_limit.is_some()),
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
        apply_scene_graph(&mut config.scene_graph, *side_engines_on_a0, *scene_graph)?;
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
}

/// The product rule's window and ceiling (docs/dref.md), on any DREF: 0 switches either off.
fn apply_query_pacing(
    rule: &mut QueryRuleConfig,
    rank_window: Option<usize>,
    max_feedback_rate: Option<f64>,
    feedback_burst: Option<u32>,
    min_feedback_rate: Option<f64>,
) -> Result<(), String> {
    if let Some(w) = rank_window {
        rule.rank_window = w;
    }
    match max_feedback_rate {
        None => {}
        Some(0.0) => rule.ceiling = None,
        Some(r) if r.is_finite() && r > 0.0 && r <= 1.0 => {
            let (burst, floor) = rule
                .ceiling
                .map_or((DEFAULT_CEILING.burst, None), |c| (c.burst, c.floor));
            rule.ceiling = Some(FeedbackCeiling {
                rate: r,
                burst,
                floor,
            });
        }
        Some(r) => {
            return Err(format!(
                "max_feedback_rate: expected a share of steps in (0, 1], or 0 for no ceiling, got {r}"
            ));
        }
    }
    match (min_feedback_rate, &mut rule.ceiling) {
        (None, _) => {}
        (Some(0.0), Some(c)) => c.floor = None,
        (Some(0.0), None) => {}
        (Some(f), Some(c)) if f.is_finite() && f > 0.0 && f <= c.rate => c.floor = Some(f),
        (Some(f), Some(c)) => {
            return Err(format!(
                "min_feedback_rate: expected a share of steps in (0, max_feedback_rate = {}], or 0 for a fixed rate, got {f}",
                c.rate
            ));
        }
        (Some(_), None) => {
            return Err(
                "min_feedback_rate: the rule has no ceiling; set max_feedback_rate too".into(),
            );
        }
    }
    if let Some(b) = feedback_burst {
        if b == 0 {
            return Err("feedback_burst: expected at least 1".into());
        }
        match &mut rule.ceiling {
            Some(c) => c.burst = b,
            None => {
                return Err(
                    "feedback_burst: the rule has no ceiling; set max_feedback_rate too".into(),
                );
            }
        }
    }
    Ok(())
}

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
    choice: Option<SceneGraphChoice>,
) -> Result<(), String> {
    match (side_engines_on_a0, &mut *graph) {
        (None, _) => {}
        (Some(on), SceneGraph::LunarLander { side_engines_on_a0 }) => *side_engines_on_a0 = on,
        (Some(_), _) => return Err("side_engines_on_a0 applies to lunar-lander only".into()),
    }
    match (choice, *graph) {
        (None, _) => Ok(()),
        (Some(SceneGraphChoice::Head), SceneGraph::Placing | SceneGraph::PlacingAsRun) => {
            *graph = SceneGraph::Placing;
            Ok(())
        }
        (Some(SceneGraphChoice::AsRun), SceneGraph::Placing | SceneGraph::PlacingAsRun) => {
            *graph = SceneGraph::PlacingAsRun;
            Ok(())
        }
        (Some(_), _) => Err("scene_graph applies to placing only".into()),
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
