//! `GET /api/tasks`: the tasks, their scene-graph predicates, spaces and default settings, so a
//! client can build a launch form without hard-coding them.

use axum::Json;
use serde_json::{Value, json};

use crate::guidance::drpl::selection::QueryMethod;
use crate::scene_graph::SceneGraph;
use crate::session::spec::DEFAULT_QUERIES;
use crate::settings::{Family, Settings};
use crate::sim::Task;

/// Every task with its spaces, predicates and budgets, and for each method family the settings
/// that apply to it at their defaults (the dashboard's advanced form is built from these; a
/// launch may send any of them back in `params`).
pub fn describe() -> Value {
    let tasks: Vec<Value> = [Task::Reaching, Task::Placing, Task::LunarLander]
        .into_iter()
        .map(|task| {
            let env = task.make_env();
            let spec = env.spec();
            json!({
                "id": task.id(),
                "observation_dim": spec.observation_space.dim(),
                "action_dim": spec.action_space.dim(),
                "predicates": SceneGraph::for_task(task).predicates(),
                "defaults": {
                    "steps": if task == Task::LunarLander { 150_000 } else { 100_000 },
                    "queries": DEFAULT_QUERIES,
                },
                "settings": {
                    "evaluative": Settings::defaults(task, Family::Evaluative),
                    "preference": Settings::defaults(task, Family::Preference),
                },
            })
        })
        .collect();
    json!({
        "tasks": tasks,
        "methods": {
            "evaluative": ["dref", "dref-authors", "ef-100", "ef-50", "ef-25", "ef-<percent>", "sac"],
            "preference": QueryMethod::ALL.iter().map(|m| m.id()).collect::<Vec<_>>(),
        },
        "trainers": ["human", "synthetic"],
    })
}

/// The tasks, their spaces, scene-graph predicates and budgets, and per method family every
/// setting that applies, at its default.
#[utoipa::path(
    get,
    path = "/api/tasks",
    tag = "service",
    security(()),
    responses((status = 200, description = "Tasks", body = Object))
)]
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
            for family in ["evaluative", "preference"] {
                let offered = &t["settings"][family];
                assert_eq!(
                    offered["variant"] == "authors",
                    t["id"] != "lunar-lander",
                    "{} {family}",
                    t["id"]
                );
                assert_eq!(offered["pace_hz"], 20.0);
            }
        }
    }
}
