//! The settings of the task itself, which both families take: its scene graph's options and
//! its version (tasks.md; Reaching and Placing), each checked against the task it names.

use serde::{Deserialize, Serialize};

use super::{SceneGraphChoice, SettingsError};
use crate::scene_graph::SceneGraph;
use crate::sim::{
    EnvOptions, GripObservation, HoopShape, PlacingSuccess, Start, Task, TaskRef, Variant,
};

/// The scene graph's options.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct SceneGraphSection {
    /// Lunar Lander: test both side engines on a0, as the authors' code does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub side_engines_on_a0: Option<bool>,
    /// Placing: `head` (36 cells) or `as-run` (the published runs' 12 cells).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene_graph: Option<SceneGraphChoice>,
}

/// The task's version (tasks.md; Reaching and Placing).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default)]
pub struct EnvSection {
    /// `authors` (home pose, 1.2 cm steps, gradual gripper) or `uniform` (the first version).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variant: Option<Variant>,
    /// Where episodes start: `home` (the authors' variant) or `uniform` (anywhere over the
    /// table; the first version, and DRPL's random trajectories as in the paper).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start: Option<Start>,
    /// Placing: `over` (released over the opening) or `through` (fallen through it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub success: Option<PlacingSuccess>,
    /// Placing: the observation's fourth entry is the last command's `sign` or the `level`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observe_grip: Option<GripObservation>,
    /// Placing (authors' variant): the ball drops once the gripper's level is at or below this.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub release_at: Option<f32>,
    /// Placing: `box` (tasks.md's closed basket) or `ring` (the authors' scene's ring on an
    /// overhang and a pole, which the gated gripper cannot touch).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hoop: Option<HoopShape>,
}

impl SceneGraphSection {
    /// Lunar Lander's side-engine test and Placing's graph, for both families (DRPL cuts its
    /// segments where the graph changes, so the authors' as-run graph is one of its ablations:
    /// `docs/results/fig5/ablations/scene_graph-as-run/`).
    pub(super) fn offered(task: Task) -> Self {
        let side_engines_on_a0 = match SceneGraph::for_task(task) {
            SceneGraph::LunarLander { side_engines_on_a0 } => Some(side_engines_on_a0),
            _ => None,
        };
        let placing_graph = task == Task::Placing;
        Self {
            side_engines_on_a0,
            scene_graph: placing_graph.then_some(SceneGraphChoice::Head),
        }
    }

    /// The options given, checked against `graph`'s task, into `graph`.
    pub(super) fn apply(&self, graph: &mut SceneGraph) -> Result<(), SettingsError> {
        match (self.side_engines_on_a0, &mut *graph) {
            (None, _) => {}
            (Some(on), SceneGraph::LunarLander { side_engines_on_a0 }) => *side_engines_on_a0 = on,
            (Some(_), _) => {
                return Err(SettingsError::WrongTask {
                    key: "side_engines_on_a0",
                    applies_to: "lunar-lander only",
                    task: None,
                });
            }
        }
        match (self.scene_graph, *graph) {
            (None, _) => Ok(()),
            (Some(SceneGraphChoice::Head), SceneGraph::Placing | SceneGraph::PlacingAsRun) => {
                *graph = SceneGraph::Placing;
                Ok(())
            }
            (Some(SceneGraphChoice::AsRun), SceneGraph::Placing | SceneGraph::PlacingAsRun) => {
                *graph = SceneGraph::PlacingAsRun;
                Ok(())
            }
            (Some(_), _) => Err(SettingsError::WrongTask {
                key: "scene_graph",
                applies_to: "placing only",
                task: None,
            }),
        }
    }
}

impl EnvSection {
    /// The version's settings that `task` has, at `env`'s values.
    pub(super) fn offered(task: Task, env: &EnvOptions) -> Self {
        let table_top = task != Task::LunarLander;
        let placing = task == Task::Placing;
        Self {
            variant: table_top.then_some(env.variant),
            start: table_top.then(|| env.start_pose()),
            success: placing.then(|| env.placing_success()),
            observe_grip: placing.then_some(env.observe_grip),
            release_at: placing.then_some(env.release_at),
            hoop: placing.then_some(env.hoop),
        }
    }

    /// The settings given, checked against `task`, into `env`.
    pub(super) fn apply(&self, env: &mut EnvOptions, task: &TaskRef) -> Result<(), SettingsError> {
        let builtin = task.builtin();
        let table_top_only = |key: &'static str| -> Result<(), SettingsError> {
            if !matches!(builtin, Some(Task::Reaching | Task::Placing)) {
                Err(SettingsError::WrongTask {
                    key,
                    applies_to: "reaching and placing",
                    task: Some(task.to_string()),
                })
            } else {
                Ok(())
            }
        };
        if let Some(v) = self.variant {
            table_top_only("variant")?;
            env.variant = v;
        }
        if let Some(s) = self.start {
            table_top_only("start")?;
            env.start = Some(s);
        }
        let placing_only = |key: &'static str| -> Result<(), SettingsError> {
            if builtin == Some(Task::Placing) {
                Ok(())
            } else {
                Err(SettingsError::WrongTask {
                    key,
                    applies_to: "placing only",
                    task: Some(task.to_string()),
                })
            }
        };
        if let Some(s) = self.success {
            placing_only("success")?;
            env.success = Some(s);
        }
        if let Some(g) = self.observe_grip {
            placing_only("observe_grip")?;
            env.observe_grip = g;
        }
        if let Some(r) = self.release_at {
            placing_only("release_at")?;
            if !(-1.0..1.0).contains(&r) {
                return Err(SettingsError::bad(
                    "release_at",
                    format!("expected a number in [-1, 1), got {r}"),
                ));
            }
            env.release_at = r;
        }
        if let Some(h) = self.hoop {
            placing_only("hoop")?;
            env.hoop = h;
        }
        Ok(())
    }
}
