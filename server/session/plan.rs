//! A session as it will run: its spec with every setting read and checked, once, when the
//! session is launched or resumed. The hub's owner holds the plan, the session thread gets it
//! by move, and the trainer's `hello` is read from it: nothing after launch reads the spec's
//! settings again, and nothing can disagree about them.

use crate::remote_env::RemoteDescription;
use crate::scene_graph::SceneGraph;
use crate::settings::{Combine, SettingsError};
use crate::sim::EnvFault;

use super::events::QueryKind;
use super::spec::{RunConfig, SessionSettings, SessionSpec};

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
