//! Scene graphs: each task's symbolic predicates, evaluated on `(s_{t+1}, a_t)`, packed into an
//! `AbstractState` bit vector (the key DREF ranks and DRPL segments by). No IO.
//!
//! - `abstract_state`: the bit vector, Hamming distance, display.
//! - `reaching`, `placing`, `lunar_lander`: each task's predicates and evaluator.
//! - `declared`: the predicates an environment in another process declares and evaluates itself.

mod abstract_state;
pub mod declared;
pub mod lunar_lander;
pub mod placing;
pub mod reaching;

pub use abstract_state::AbstractState;
use serde::{Deserialize, Serialize};

use crate::sim::{Env, Task};

/// One symbolic fact about the scene: a stable machine name and a label a trainer reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Predicate {
    /// Stable identifier (snake_case), used in files, the API and recordings.
    pub name: &'static str,
    /// What the trainer reads, e.g. "gripper above hoop".
    pub label: &'static str,
}

/// A task's scene graph: which predicates it has and how to evaluate them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "declared::GraphRepr", into = "declared::GraphRepr")]
pub enum SceneGraph {
    Reaching,
    Placing,
    /// Placing's graph as the authors' published runs had it (`scene_graph = "as-run"`).
    PlacingAsRun,
    LunarLander {
        /// The authors' code tests both side-engine predicates on a0 instead of a1 (a bug we
        /// reproduce only on request).
        #[serde(default)]
        side_engines_on_a0: bool,
    },
    /// Predicates an environment in another process declared (names interned, see
    /// `sim::interned`) and reports step by step: the env is the graph's evaluator.
    Declared(&'static [Predicate]),
}

impl SceneGraph {
    /// The default scene graph of a task (Lunar Lander's side engines on a1).
    pub fn for_task(task: Task) -> Self {
        match task {
            Task::Reaching => SceneGraph::Reaching,
            Task::Placing => SceneGraph::Placing,
            Task::LunarLander => SceneGraph::LunarLander {
                side_engines_on_a0: false,
            },
        }
    }

    pub fn predicates(&self) -> &'static [Predicate] {
        match self {
            SceneGraph::Reaching => &reaching::PREDICATES,
            SceneGraph::Placing => &placing::PREDICATES,
            SceneGraph::PlacingAsRun => &placing::AS_RUN_PREDICATES,
            SceneGraph::LunarLander { .. } => &lunar_lander::PREDICATES,
            SceneGraph::Declared(predicates) => predicates,
        }
    }

    /// Number of predicates, dim(G).
    pub fn dim(&self) -> usize {
        self.predicates().len()
    }

    /// Evaluate the graph on the next observation `s_{t+1}` and the action `a_t` that led to it.
    /// A declared graph has no evaluator here (its env reports the bits): use
    /// [`SceneGraph::after_step`] where the env is at hand.
    pub fn evaluate(&self, next_obs: &[f32], action: &[f32]) -> AbstractState {
        match *self {
            SceneGraph::Reaching => reaching::evaluate(next_obs),
            SceneGraph::Placing => placing::evaluate(next_obs),
            SceneGraph::PlacingAsRun => placing::evaluate_as_run(next_obs),
            SceneGraph::LunarLander { side_engines_on_a0 } => {
                lunar_lander::evaluate(next_obs, action, side_engines_on_a0)
            }
            SceneGraph::Declared(_) => AbstractState::default(),
        }
    }

    /// The abstract state after `env`'s last step: what the env reported for a declared graph,
    /// else the graph evaluated on `(next_obs, action)` (a built-in task's graph on a remote
    /// copy of that task is evaluated here too).
    pub fn after_step(&self, env: &dyn Env, next_obs: &[f32], action: &[f32]) -> AbstractState {
        match self {
            SceneGraph::Declared(_) => AbstractState(env.reported_predicates().unwrap_or(0)),
            _ => self.evaluate(next_obs, action),
        }
    }

    /// The labels of the predicates that hold in `state`, in predicate order.
    pub fn holding(&self, state: AbstractState) -> Vec<&'static str> {
        self.predicates()
            .iter()
            .enumerate()
            .filter(|(i, _)| state.bit(*i))
            .map(|(_, p)| p.label)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn predicate_names_are_unique_snake_case_per_task() {
        for task in Task::ALL {
            let graph = SceneGraph::for_task(task);
            let names: Vec<_> = graph.predicates().iter().map(|p| p.name).collect();
            let mut sorted = names.clone();
            sorted.sort();
            sorted.dedup();
            assert_eq!(
                sorted.len(),
                names.len(),
                "{task}: duplicate predicate name"
            );
            for name in names {
                assert!(
                    name.chars()
                        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
                );
            }
        }
    }

    #[test]
    fn holding_lists_labels_of_set_bits() {
        let graph = SceneGraph::Reaching;
        let state = graph.evaluate(&[0.0, 0.0], &[0.0, 0.0]);
        assert_eq!(
            graph.holding(state),
            vec!["gripper centred in x", "gripper centred in y"]
        );
    }
}
