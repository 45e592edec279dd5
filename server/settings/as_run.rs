//! `profile = "as-run"`: the constants and behaviours the authors' *published* Figure 3 runs
//! ran with, as read from their repository's history and logs (issue 33;
//! `docs/results/authors-runs/`), where they differ from the repository's head that
//! algorithms.md describes. Each is also a setting of its own; given settings override the
//! profile's values. Applies to every evaluative method of the run (DREF's rule to
//! `dref-authors`, the oracle to EF and DREF alike, the time limit to all).

use serde::{Deserialize, Serialize};

use super::SettingsError;
use crate::guidance::evaluative_run::{EvaluativeRunConfig, GraphAtEpisodeEnd, TimeLimitEnd};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::scene_graph::SceneGraph;
use crate::sim::{Task, TaskRef};

/// Which constants a run starts from before its own settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Profile {
    /// The authors' repository at its head (algorithms.md).
    #[default]
    Head,
    /// What their published runs ran (see the module's notes, per task).
    AsRun,
}

/// Placing's scene graph: the head's 36-cell graph or the published runs' 12-cell one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "kebab-case")]
pub enum SceneGraphChoice {
    Head,
    AsRun,
}

/// The authors' published runs (issue 33): the profile, and its switches that belong to no other
/// section (the oracle's are in `oracle`, the scene graph's and the env's in `task_version`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct AsRunSection {
    /// `head` (the authors' repository at its head, algorithms.md) or `as-run` (what their
    /// published runs ran, per task; the settings below, given, override it) [default head].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub profile: Option<Profile>,
    /// Which observation the scene graph reads on an episode's last step: `step` or `reset`
    /// [default step].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub graph_at_episode_end: Option<GraphAtEpisodeEnd>,
    /// How a time limit's end is stored: `truncation` or `terminal` [default truncation].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_limit: Option<TimeLimitEnd>,
}

impl AsRunSection {
    pub(super) fn offered(c: &EvaluativeRunConfig) -> Self {
        Self {
            profile: Some(Profile::Head),
            graph_at_episode_end: Some(c.graph_at_episode_end),
            time_limit: Some(c.time_limit),
        }
    }

    /// The profile's values, before any other setting (which override them).
    pub(super) fn apply_profile(
        &self,
        config: &mut EvaluativeRunConfig,
    ) -> Result<(), SettingsError> {
        match self.profile {
            Some(Profile::AsRun) => apply(config),
            None | Some(Profile::Head) => Ok(()),
        }
    }

    /// The switches given, checked, into `config`.
    pub(super) fn apply_switches(&self, config: &mut EvaluativeRunConfig) {
        if let Some(g) = self.graph_at_episode_end {
            config.graph_at_episode_end = g;
        }
        if let Some(t) = self.time_limit {
            config.time_limit = t;
        }
    }
}

/// How the authors' published runs of `task` stored a time limit's end: all a SAC run (no
/// oracle, no scene graph, no query rule) takes from the profile, so a SAC run of the head's
/// constants with this time limit is a run of the profile too (the report reuses Lunar Lander's
/// 150k SAC runs that way).
pub fn time_limit_as_run(task: Task) -> TimeLimitEnd {
    let mut config = EvaluativeRunConfig::new(task, EvaluativeMethod::Sac, 0);
    apply(&mut config).expect("the profile applies to every task of ours");
    config.time_limit
}

/// The as-run values on `config`'s task:
/// - everywhere: the scene graph at an episode's end reads the reset observation (their
///   vectorised env reset before returning);
/// - Lunar Lander (runs of 2022-05-13, commit 4560259): rank `<= 50` (head 60), the oracle's
///   alpha from 0.99 (head 0.999, from 17bb71b on 05-28), both side-engine bits on a0;
///   its 1000-step limit stays a truncation (Gymnasium's TimeLimit);
/// - Reaching (the plotted runs mix c 0.2/0.1 and k 2/3; three of five ran 2263cda): c 0.1,
///   k 3, and the expert's critic and H_hat shown the env-scale action (+-0.1 per axis: 0.1 x
///   the normalised one); robosuite's time-limit ends stored as terminal;
/// - Placing (runs of 2022-06-06, f2ff175 / 5dce179): the 12-cell graph without gripper bits
///   (`SceneGraph::PlacingAsRun`), c 0.2, k 4 (as the head); time-limit ends terminal.
fn apply(config: &mut EvaluativeRunConfig) -> Result<(), SettingsError> {
    let task = match &config.task {
        TaskRef::Builtin(task) => *task,
        TaskRef::Declared(d) => {
            return Err(SettingsError::bad(
                "profile",
                format!(
                    "as-run describes the authors' runs of our three tasks, not {}",
                    d.env
                ),
            ));
        }
    };
    config.graph_at_episode_end = GraphAtEpisodeEnd::Reset;
    match task {
        Task::LunarLander => {
            config.query_rule.k = 50;
            config.oracle.alpha0 = 0.99;
            config.scene_graph = SceneGraph::LunarLander {
                side_engines_on_a0: true,
            };
        }
        Task::Reaching => {
            config.query_rule.c = 0.1;
            config.query_rule.k = 3;
            config.oracle.action_scale = 0.1;
            config.time_limit = TimeLimitEnd::Terminal;
        }
        Task::Placing => {
            config.scene_graph = SceneGraph::PlacingAsRun;
            config.time_limit = TimeLimitEnd::Terminal;
        }
    }
    Ok(())
}
