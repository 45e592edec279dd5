//! `profile = "as-run"`: the constants and behaviours the authors' *published* Figure 3 runs
//! ran with, as read from their repository's history and logs (issue 33;
//! `docs/results/authors-runs/`), where they differ from the repository's head that
//! algorithms.md describes. Each is also a setting of its own; given settings override the
//! profile's values. Applies to every evaluative method of the run (DREF's rule to
//! `dref-authors`, the oracle to EF and DREF alike, the time limit to all).

use crate::guidance::evaluative_run::{EvaluativeRunConfig, GraphAtEpisodeEnd, TimeLimitEnd};
use crate::scene_graph::SceneGraph;
use crate::sim::{Task, TaskRef};

/// Which constants a run starts from before its own settings.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    utoipa::ToSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Profile {
    /// The authors' repository at its head (algorithms.md).
    #[default]
    Head,
    /// What their published runs ran (see the module's notes, per task).
    AsRun,
}

/// Placing's scene graph: the head's 36-cell graph or the published runs' 12-cell one.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, utoipa::ToSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum SceneGraphChoice {
    Head,
    AsRun,
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
pub fn apply(config: &mut EvaluativeRunConfig) -> Result<(), String> {
    let task = match &config.task {
        TaskRef::Builtin(task) => *task,
        TaskRef::Declared(d) => {
            return Err(format!(
                "profile: as-run describes the authors' runs of our three tasks, not {}",
                d.env
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
