//! A session as it will run: its spec with every setting read and checked, once, when the
//! session is launched or resumed. The hub's owner holds the plan, the session thread gets it
//! by move, and the trainer's `hello` is read from it: nothing after launch reads the spec's
//! settings again, and nothing can disagree about them.
//!
//! The walk of one setting, `learning_rate` in a launch's `params`, to the learner (11 files,
//! one validation): `http/sessions.rs` (serde reads it into the SAC section of `Settings`; an
//! unknown key or a wrong type is refused there, by name) -> `hub/mod.rs` (`launch` makes the
//! plan) -> here (`SessionPlan::new`, the one check) -> `settings/run_configs.rs` (each section
//! onto the run's config) -> `settings/sac.rs` (`learning_rate > 0`, into `SacConfig`) ->
//! `hub/thread.rs` (the owner's plan, moved into the session's thread) -> `session/runner.rs`
//! -> `session/evaluative_loop.rs` -> `guidance/evaluative_run.rs` (`Sac::new`) ->
//! `rl/sac/mod.rs` (Adam's step size) -> `rl/sac/update.rs` (Adam's step). Past the check the
//! value travels inside the plan's run config by move; nothing re-reads `params`.

use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::guidance::human_pace::{HumanPace, PEOPLE_QUERIES_PER_MINUTE};
use crate::remote_env::RemoteDescription;
use crate::scene_graph::SceneGraph;
use crate::settings::{Combine, SettingsError};
use crate::sim::{DeclaredTask, EnvFault};

use super::events::QueryKind;
use super::spec::{SessionMethod, SessionSettings, SessionSpec, TrainerKind};

/// Why a spec cannot become a plan: what a launch is refused with (a 422), and what a stored
/// session that no longer reads fails with.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// A setting that does not read or does not apply to the session's task and method.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    #[error("the budget (steps or queries) must be at least 1")]
    NoBudget,
    #[error("budget {0} is above the limit of 10,000,000")]
    BudgetTooLarge(u64),
    /// Neither a task of ours nor a remote env.
    #[error("give a task, an env ({{\"url\": ...}}), or both")]
    NoTask,
    /// The remote env's URL is not of the form the protocol takes.
    #[error("env: {0}")]
    Env(EnvFault),
    /// `env_timeout_s` on a session without a remote env.
    #[error("env_timeout_s applies to sessions on a remote env (env: {{\"url\": ...}})")]
    EnvTimeoutWithoutEnv,
    /// A combine rule of the other kind of query.
    #[error(
        "combine: {} does not combine {} answers (evaluative: majority or mean; preference: each)",
        .combine.as_str(),
        .kind.as_str()
    )]
    CombineDoesNotFit { combine: Combine, kind: QueryKind },
    /// Several answers per query on a session whose trainer is synthetic.
    #[error(
        "answers_per_query = {0}: several answers per query come from people; this session's trainer is synthetic"
    )]
    SeveralAnswersNeedPeople(usize),
    /// Teacher faults on a session that people answer.
    #[error(
        "teacher_* settings give the synthetic trainer faults; this session's trainer is human"
    )]
    FaultsOnPeople,
}

/// A validated session: the spec, its session settings, the algorithm's configuration, the
/// scene graph its queries are phrased in and the kind of query it asks.
#[derive(Clone, Debug)]
pub struct SessionPlan {
    pub spec: SessionSpec,
    pub settings: SessionSettings,
    /// The run's configuration. On a remote env's own task its defaults are the task's the env
    /// declares, known once it is reached: see [`SessionPlan::on_remote`].
    pub run: RunConfig,
    /// The scene graph (on a remote env's own task: none until it is reached).
    pub graph: SceneGraph,
    pub kind: QueryKind,
}

impl SessionPlan {
    /// Reads and checks everything a session needs; the one validation of its settings.
    pub fn new(spec: SessionSpec) -> Result<Self, PlanError> {
        spec.check_outline()?;
        let settings = spec.params.session()?;
        let run = spec.run_config_on(None)?;
        spec.check_people(&settings, &run)?;
        let graph = run.scene_graph();
        let kind = spec.method.query_kind();
        Ok(Self {
            spec,
            settings,
            run,
            graph,
            kind,
        })
    }

    /// The plan on a remote env that described itself as `declared`: the same settings over
    /// the defaults of the task it declares when the spec names none of ours (checked at
    /// launch against a task with no predicates, so they apply here as they did there).
    pub fn on_remote(mut self, declared: &RemoteDescription) -> Result<Self, PlanError> {
        if self.spec.task.is_none() {
            self.run = self.spec.run_config_on(Some(declared))?;
            self.graph = self.run.scene_graph();
        }
        Ok(self)
    }
}

/// The algorithm's configuration, built from the spec. Both are boxed: they differ in size by
/// about 200 bytes, which grows with every setting, and a plan is built once a session.
#[derive(Clone, Debug)]
pub enum RunConfig {
    Evaluative(Box<EvaluativeRunConfig>),
    Preference(Box<PreferenceRunConfig>),
}

impl RunConfig {
    /// The scene graph the session's queries are phrased in (its `side_engines_on_a0` override
    /// included).
    pub fn scene_graph(&self) -> SceneGraph {
        match self {
            RunConfig::Evaluative(c) => c.scene_graph,
            RunConfig::Preference(c) => c.scene_graph,
        }
    }
}

/// What a plan reads from its spec, in the order [`SessionPlan::new`] checks it.
impl SessionSpec {
    /// The algorithm's configuration with every setting applied, on a remote env that described
    /// itself as `declared` (used when the spec has no task of ours). A remote env's own task is
    /// known only once it is reached: until then (validation) its predicates are none.
    pub(super) fn run_config_on(
        &self,
        declared: Option<&RemoteDescription>,
    ) -> Result<RunConfig, PlanError> {
        let (task, graph, max_steps) = match (self.task, declared) {
            (Some(task), _) => {
                return Ok(match self.method {
                    SessionMethod::Evaluative(method) => RunConfig::Evaluative(Box::new(
                        self.paced_for_people(self.params.evaluative(task, method, self.seed)?)?,
                    )),
                    SessionMethod::Preference(method) => RunConfig::Preference(Box::new(
                        self.params.preference(task, method, self.seed)?,
                    )),
                });
            }
            (None, Some(d)) => (
                d.declared_task(),
                d.graph,
                d.spec.max_episode_steps as usize,
            ),
            (None, None) => (DeclaredTask::default(), SceneGraph::Declared(&[]), 1000),
        };
        Ok(match self.method {
            SessionMethod::Evaluative(method) => RunConfig::Evaluative(Box::new(
                self.paced_for_people(self.params.apply_evaluative(
                    EvaluativeRunConfig::declared(task, graph, method, self.seed),
                )?)?,
            )),
            SessionMethod::Preference(method) => {
                RunConfig::Preference(Box::new(self.params.apply_preference(
                    PreferenceRunConfig::declared(task, graph, method, self.seed, max_steps),
                )?))
            }
        })
    }

    /// A DREF session answered by a person asks at a person's pace unless the launch set one
    /// (`max_queries_per_minute`, 0 for none): the rule's ceiling is a share of steps, and a
    /// person answers fewer a minute than a fast robot takes steps. Synthetic trainers and EF
    /// (whose schedule is its definition) keep the rule's own pace.
    fn paced_for_people(
        &self,
        mut config: EvaluativeRunConfig,
    ) -> Result<EvaluativeRunConfig, SettingsError> {
        let unset = self.params.evaluative.max_queries_per_minute.is_none();
        if self.trainer == TrainerKind::Human && config.method == EvaluativeMethod::Dref && unset {
            let pace_hz = self.params.session()?.pace_hz;
            config.human_pace = Some(HumanPace::new(PEOPLE_QUERIES_PER_MINUTE, pace_hz));
        }
        Ok(config)
    }

    /// The budget and where the env is. A remote env is not reached here: it may start later
    /// than the session is queued.
    pub(super) fn check_outline(&self) -> Result<(), PlanError> {
        if self.budget == 0 {
            return Err(PlanError::NoBudget);
        }
        if self.budget > 10_000_000 {
            return Err(PlanError::BudgetTooLarge(self.budget));
        }
        match (&self.env, self.task) {
            (None, None) => return Err(PlanError::NoTask),
            (Some(env), _) => env.validate().map_err(PlanError::Env)?,
            (None, Some(_)) => {}
        }
        if self.env.is_none() && self.params.session.env_timeout_s.is_some() {
            return Err(PlanError::EnvTimeoutWithoutEnv);
        }
        Ok(())
    }

    /// Who answers, against how the answers combine and whether the teacher has faults.
    pub(super) fn check_people(
        &self,
        settings: &SessionSettings,
        run: &RunConfig,
    ) -> Result<(), PlanError> {
        let kind = self.method.query_kind();
        if !settings.combine.fits(kind) {
            return Err(PlanError::CombineDoesNotFit {
                combine: settings.combine,
                kind,
            });
        }
        if settings.answers_per_query > 1 && self.trainer != TrainerKind::Human {
            return Err(PlanError::SeveralAnswersNeedPeople(
                settings.answers_per_query,
            ));
        }
        let teacher = match run {
            RunConfig::Evaluative(c) => &c.teacher,
            RunConfig::Preference(c) => &c.teacher,
        };
        if !teacher.is_perfect() && self.trainer == TrainerKind::Human {
            return Err(PlanError::FaultsOnPeople);
        }
        Ok(())
    }
}
