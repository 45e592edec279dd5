//! A scene graph an environment declares about itself (an env in another process, see
//! `docs/env-protocol.md`): stable predicate names and the labels people read, checked once and
//! interned, so that [`SceneGraph`] stays a small `Copy` value whichever graph it holds. The env
//! evaluates the predicates and reports the ones that hold after every step.

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use serde::{Deserialize, Serialize};

use super::{Predicate, SceneGraph};
use crate::sim::interned::intern;

/// The most predicates a graph may have: the abstract state is one `u32`.
pub const MAX_PREDICATES: usize = 32;
/// Longest predicate name and label (characters).
pub const MAX_NAME: usize = 64;
pub const MAX_LABEL: usize = 200;

/// A predicate as an env declares it.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeclaredPredicate {
    /// Stable identifier: lowercase letters, digits and `_`, starting with a letter.
    pub name: String,
    /// What a trainer reads ("gripper above hoop").
    pub label: String,
}

/// Why an env's declared predicates do not make a scene graph.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DeclaredGraphError {
    /// More predicates than an abstract state holds.
    #[error("{0} predicates declared: at most {MAX_PREDICATES}")]
    TooMany(usize),
    /// A name that is not a stable identifier.
    #[error(
        "predicate name {0:?}: expected lowercase letters, digits and _ (starting with a letter, at most {MAX_NAME})"
    )]
    BadName(String),
    /// An empty or overlong label (the predicate's name).
    #[error("predicate {0}: its label must be 1 to {MAX_LABEL} characters")]
    BadLabel(String),
    /// A name declared twice.
    #[error("predicate {0} is declared twice")]
    Twice(String),
}

/// Check `predicates` and give them as a graph's predicate list (the same list, declared again,
/// is the same slice).
pub fn declare(
    predicates: &[DeclaredPredicate],
) -> Result<&'static [Predicate], DeclaredGraphError> {
    if predicates.len() > MAX_PREDICATES {
        return Err(DeclaredGraphError::TooMany(predicates.len()));
    }
    let mut seen = std::collections::HashSet::new();
    for p in predicates {
        let valid = p.name.len() <= MAX_NAME
            && p.name.starts_with(|c: char| c.is_ascii_lowercase())
            && p.name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
        if !valid {
            return Err(DeclaredGraphError::BadName(p.name.clone()));
        }
        if p.label.trim().is_empty() || p.label.chars().count() > MAX_LABEL {
            return Err(DeclaredGraphError::BadLabel(p.name.clone()));
        }
        if !seen.insert(p.name.as_str()) {
            return Err(DeclaredGraphError::Twice(p.name.clone()));
        }
    }
    static LISTS: OnceLock<Mutex<HashMap<Vec<DeclaredPredicate>, &'static [Predicate]>>> =
        OnceLock::new();
    let mut lists = LISTS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(&list) = lists.get(predicates) {
        return Ok(list);
    }
    let list: Vec<Predicate> = predicates
        .iter()
        .map(|p| Predicate {
            name: intern(&p.name),
            label: intern(&p.label),
        })
        .collect();
    let list: &'static [Predicate] = Box::leak(list.into_boxed_slice());
    lists.insert(predicates.to_vec(), list);
    Ok(list)
}

/// How a [`SceneGraph`] is written in configs and checkpoints: the built-in graphs by task, a
/// declared one with its predicates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "task", rename_all = "kebab-case")]
pub enum GraphRepr {
    Reaching,
    Placing,
    PlacingAsRun,
    LunarLander {
        #[serde(default)]
        side_engines_on_a0: bool,
    },
    Declared {
        predicates: Vec<DeclaredPredicate>,
    },
}

impl From<SceneGraph> for GraphRepr {
    fn from(graph: SceneGraph) -> Self {
        match graph {
            SceneGraph::Reaching => GraphRepr::Reaching,
            SceneGraph::Placing => GraphRepr::Placing,
            SceneGraph::PlacingAsRun => GraphRepr::PlacingAsRun,
            SceneGraph::LunarLander { side_engines_on_a0 } => {
                GraphRepr::LunarLander { side_engines_on_a0 }
            }
            SceneGraph::Declared(list) => GraphRepr::Declared {
                predicates: list
                    .iter()
                    .map(|p| DeclaredPredicate {
                        name: p.name.to_string(),
                        label: p.label.to_string(),
                    })
                    .collect(),
            },
        }
    }
}

impl TryFrom<GraphRepr> for SceneGraph {
    type Error = DeclaredGraphError;

    fn try_from(repr: GraphRepr) -> Result<Self, DeclaredGraphError> {
        Ok(match repr {
            GraphRepr::Reaching => SceneGraph::Reaching,
            GraphRepr::Placing => SceneGraph::Placing,
            GraphRepr::PlacingAsRun => SceneGraph::PlacingAsRun,
            GraphRepr::LunarLander { side_engines_on_a0 } => {
                SceneGraph::LunarLander { side_engines_on_a0 }
            }
            GraphRepr::Declared { predicates } => SceneGraph::Declared(declare(&predicates)?),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(name: &str, label: &str) -> DeclaredPredicate {
        DeclaredPredicate {
            name: name.into(),
            label: label.into(),
        }
    }

    #[test]
    fn a_declared_graph_is_interned_and_round_trips() {
        let list = [
            p("pole_upright", "pole upright"),
            p("cart_left", "cart left"),
        ];
        let a = declare(&list).unwrap();
        let b = declare(&list.clone()).unwrap();
        assert!(std::ptr::eq(a, b));
        let graph = SceneGraph::Declared(a);
        assert_eq!(graph.dim(), 2);
        let json = serde_json::to_value(graph).unwrap();
        assert_eq!(json["task"], "declared");
        assert_eq!(json["predicates"][1]["label"], "cart left");
        assert_eq!(serde_json::from_value::<SceneGraph>(json).unwrap(), graph);
        // The built-in graphs keep their old form.
        let ll = SceneGraph::for_task(crate::sim::Task::LunarLander);
        assert_eq!(
            serde_json::to_value(ll).unwrap(),
            serde_json::json!({"task": "lunar-lander", "side_engines_on_a0": false})
        );
        assert_eq!(
            serde_json::from_value::<SceneGraph>(serde_json::json!({"task": "lunar-lander"}))
                .unwrap(),
            ll
        );
    }

    #[test]
    fn bad_declarations_are_refused_with_the_reason() {
        let twice = [p("a", "A"), p("a", "B")];
        let refused = |list: &[DeclaredPredicate]| declare(list).unwrap_err().to_string();
        assert_eq!(refused(&twice), "predicate a is declared twice");
        assert_eq!(
            refused(&[p("Upright", "x")]),
            r#"predicate name "Upright": expected lowercase letters, digits and _ (starting with a letter, at most 64)"#
        );
        assert_eq!(
            refused(&[p("ok", " ")]),
            "predicate ok: its label must be 1 to 200 characters"
        );
        let many: Vec<_> = (0..33).map(|i| p(&format!("p{i}"), "x")).collect();
        assert_eq!(refused(&many), "33 predicates declared: at most 32");
        assert!(declare(&[]).unwrap().is_empty());
    }
}
