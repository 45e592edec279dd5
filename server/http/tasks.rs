//! `GET /api/tasks`: the tasks, their scene-graph predicates, spaces and default settings, so a
//! client can build a launch form without hard-coding them.

use axum::Json;
use serde_json::{Value, json};

use crate::guidance::drpl::run::PreferenceRunConfig;
use crate::guidance::drpl::selection::QueryMethod;
use crate::guidance::evaluative_run::EvaluativeRunConfig;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::scene_graph::SceneGraph;
use crate::session::spec::{
    DEFAULT_ANSWER_TIMEOUT_S, DEFAULT_CHECKPOINT_EVERY, DEFAULT_CLIP_FRAMES, DEFAULT_PACE_HZ,
    DEFAULT_QUERIES,
};
use crate::sim::Task;

pub fn describe() -> Value {
    let tasks: Vec<Value> = [Task::Reaching, Task::Placing, Task::LunarLander]
        .into_iter()
        .map(|task| {
            let env = task.make_env();
            let spec = env.spec();
            let mut described = json!({
                "id": task.id(),
                "observation_dim": spec.observation_space.dim(),
                "action_dim": spec.action_space.dim(),
                "predicates": SceneGraph::for_task(task).predicates(),
                "defaults": {
                    "steps": if task == Task::LunarLander { 150_000 } else { 100_000 },
                    "queries": DEFAULT_QUERIES,
                    "dref": EvaluativeRunConfig::new(task, EvaluativeMethod::Dref, 0),
                    "drpl": PreferenceRunConfig::new(task, QueryMethod::Drpl, 0),
                },
            });
            // The task versions (`variant`, ...) are Reaching's and Placing's only: a launch
            // form must not offer them for Lunar Lander, whose settings would refuse them.
            if task == Task::LunarLander {
                for family in ["dref", "drpl"] {
                    if let Some(config) = described["defaults"][family].as_object_mut() {
                        config.remove("env");
                    }
                }
            }
            described
        })
        .collect();
    json!({
        "tasks": tasks,
        "methods": {
            "evaluative": ["dref", "ef-100", "ef-50", "ef-25", "ef-<percent>", "sac"],
            "preference": QueryMethod::ALL.iter().map(|m| m.id()).collect::<Vec<_>>(),
        },
        "trainers": ["human", "synthetic"],
        "session_params": {
            "pace_hz": DEFAULT_PACE_HZ,
            "answer_timeout_s": DEFAULT_ANSWER_TIMEOUT_S,
            "checkpoint_every": DEFAULT_CHECKPOINT_EVERY,
            "clip_frames": DEFAULT_CLIP_FRAMES,
        },
    })
}

pub async fn tasks() -> Json<Value> {
    Json(describe())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_versions_are_offered_for_the_table_top_tasks_only() {
        let d = describe();
        for t in d["tasks"].as_array().unwrap() {
            let offered = t["defaults"]["dref"]["env"]["variant"] == "authors";
            assert_eq!(offered, t["id"] != "lunar-lander", "{}", t["id"]);
            assert_eq!(t["defaults"]["drpl"]["env"].is_object(), offered);
        }
    }
}
