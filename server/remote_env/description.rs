//! An env's `hello`, checked: spaces of the sizes they claim with bounds that make sense, a
//! control rate, an episode limit, predicates and features; turned into the `EnvSpec` the
//! learner sees (actions in `[-1, 1]`, scaled here into the env's own bounds).

use std::collections::HashMap;

use super::wire::{Description, SpaceMessage};
use crate::scene_graph::SceneGraph;
use crate::scene_graph::declared::{DeclaredGraphError, declare};
use crate::sim::interned::intern;
use crate::sim::{BoxSpace, DeclaredTask, EnvSpec};

/// The most entries an observation or action may have.
pub const MAX_DIM: usize = 65_536;
/// The most DRPL features an env may declare.
pub const MAX_FEATURES: usize = 64;

/// What is wrong with an env's `hello`: the field, and what about it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DescriptionError {
    #[error("id {0:?}: expected 1 to 200 printable characters")]
    Id(String),
    /// A space (`observation_space`, `action_space`) of more entries than [`MAX_DIM`].
    #[error("{space}: shape {shape:?} has more than {MAX_DIM} entries")]
    SpaceTooLarge {
        space: &'static str,
        shape: Vec<usize>,
    },
    #[error("{space}: shape {shape:?} has no entries")]
    SpaceEmpty {
        space: &'static str,
        shape: Vec<usize>,
    },
    /// Bounds of other lengths than the shape's entries.
    #[error("{space}: shape {shape:?} has {size} entries but low has {low} and high {high}")]
    BoundsLength {
        space: &'static str,
        shape: Vec<usize>,
        size: usize,
        low: usize,
        high: usize,
    },
    /// An action entry without finite bounds.
    #[error("{space}: entry {entry} is unbounded; actions need finite low and high")]
    Unbounded { space: &'static str, entry: usize },
    /// An entry whose bounds are NaN, crossed, or (actions) equal.
    #[error("{space}: entry {entry} has low {low} and high {high}")]
    Bounds {
        space: &'static str,
        entry: usize,
        low: f64,
        high: f64,
    },
    #[error("control_hz {0}: expected a rate in (0, 10000] steps per second")]
    ControlHz(f64),
    #[error("max_episode_steps: expected at least 1")]
    NoEpisodeSteps,
    /// The declared predicates, in the scene graph's words.
    #[error("predicates: {0}")]
    Predicates(DeclaredGraphError),
    #[error("features: {0} declared, at most {MAX_FEATURES}")]
    TooManyFeatures(usize),
    #[error("features: {0} is declared twice")]
    FeatureTwice(String),
    /// Names (`observation_names`, `action_names`) not one per entry.
    #[error("{what}: {given} names for {dim} entries")]
    NameCount {
        what: &'static str,
        given: usize,
        dim: usize,
    },
}

/// What dualrep keeps of an env's `hello`.
#[derive(Clone, Debug, PartialEq)]
pub struct RemoteDescription {
    /// As the learner sees it: the action space is `[-1, 1]^n`.
    pub spec: EnvSpec,
    /// The env's own action bounds, row-major.
    pub action_low: Vec<f64>,
    pub action_high: Vec<f64>,
    /// The predicates it declared, as a scene graph (possibly with none).
    pub graph: SceneGraph,
    /// Declared predicate name -> bit.
    pub predicate_bits: HashMap<String, u32>,
    /// Its own DRPL features' names (empty: none).
    pub features: Vec<String>,
    pub render: bool,
    pub deterministic: bool,
}

impl RemoteDescription {
    /// The task as a run of a declared task records it.
    pub fn declared_task(&self) -> DeclaredTask {
        DeclaredTask {
            env: self.spec.id.to_string(),
            features: if self.features.is_empty() {
                self.spec
                    .observation_names
                    .iter()
                    .map(|n| n.to_string())
                    .collect()
            } else {
                self.features.clone()
            },
            env_features: !self.features.is_empty(),
        }
    }

    pub fn observation_dim(&self) -> usize {
        self.spec.observation_space.dim()
    }

    pub fn action_dim(&self) -> usize {
        self.spec.action_space.dim()
    }
}

fn space(
    what: &'static str,
    s: &SpaceMessage,
    bounded: bool,
) -> Result<(Vec<f64>, Vec<f64>), DescriptionError> {
    let size = s
        .shape
        .iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .filter(|&n| n <= MAX_DIM)
        .ok_or_else(|| DescriptionError::SpaceTooLarge {
            space: what,
            shape: s.shape.clone(),
        })?;
    if size == 0 {
        return Err(DescriptionError::SpaceEmpty {
            space: what,
            shape: s.shape.clone(),
        });
    }
    if s.low.len() != size || s.high.len() != size {
        return Err(DescriptionError::BoundsLength {
            space: what,
            shape: s.shape.clone(),
            size,
            low: s.low.len(),
            high: s.high.len(),
        });
    }
    let (mut low, mut high) = (Vec::with_capacity(size), Vec::with_capacity(size));
    for (i, (lo, hi)) in s.low.iter().zip(&s.high).enumerate() {
        let lo = lo.unwrap_or(f64::NEG_INFINITY);
        let hi = hi.unwrap_or(f64::INFINITY);
        if bounded && !(lo.is_finite() && hi.is_finite()) {
            return Err(DescriptionError::Unbounded {
                space: what,
                entry: i,
            });
        }
        if lo.is_nan() || hi.is_nan() || lo > hi || (bounded && lo == hi) {
            return Err(DescriptionError::Bounds {
                space: what,
                entry: i,
                low: lo,
                high: hi,
            });
        }
        low.push(lo);
        high.push(hi);
    }
    Ok((low, high))
}

/// Names for `dim` entries: the declared ones (checked), else `prefix0`, `prefix1`, ...
fn names(
    what: &'static str,
    declared: &Option<Vec<String>>,
    dim: usize,
    prefix: &str,
) -> Result<Vec<&'static str>, DescriptionError> {
    match declared {
        Some(list) if list.len() != dim => Err(DescriptionError::NameCount {
            what,
            given: list.len(),
            dim,
        }),
        Some(list) => Ok(list.iter().map(|n| intern(n)).collect()),
        None => Ok((0..dim).map(|i| intern(&format!("{prefix}{i}"))).collect()),
    }
}

/// Check an env's `hello` and keep what dualrep needs; `Err` says what is wrong with it.
pub fn check(d: &Description) -> Result<RemoteDescription, DescriptionError> {
    if d.id.is_empty() || d.id.len() > 200 || d.id.chars().any(char::is_control) {
        return Err(DescriptionError::Id(d.id.clone()));
    }
    let (obs_low, obs_high) = space("observation_space", &d.observation_space, false)?;
    let (action_low, action_high) = space("action_space", &d.action_space, true)?;
    if !(d.control_hz.is_finite() && d.control_hz > 0.0 && d.control_hz <= 10_000.0) {
        return Err(DescriptionError::ControlHz(d.control_hz));
    }
    if d.max_episode_steps == 0 {
        return Err(DescriptionError::NoEpisodeSteps);
    }
    let predicates = declare(&d.predicates).map_err(DescriptionError::Predicates)?;
    if d.features.len() > MAX_FEATURES {
        return Err(DescriptionError::TooManyFeatures(d.features.len()));
    }
    let mut seen = std::collections::HashSet::new();
    if let Some(twice) = d.features.iter().find(|f| !seen.insert(f.as_str())) {
        return Err(DescriptionError::FeatureTwice(twice.clone()));
    }
    let obs_dim = obs_low.len();
    let act_dim = action_low.len();
    let spec = EnvSpec {
        id: intern(&d.id),
        observation_space: BoxSpace {
            low: obs_low.iter().map(|&v| v as f32).collect(),
            high: obs_high.iter().map(|&v| v as f32).collect(),
        },
        action_space: BoxSpace::uniform(act_dim, -1.0, 1.0),
        observation_names: names("observation_names", &d.observation_names, obs_dim, "obs")?,
        action_names: names("action_names", &d.action_names, act_dim, "action")?,
        max_episode_steps: d.max_episode_steps,
        control_hz: d.control_hz as f32,
    };
    let predicate_bits = predicates
        .iter()
        .enumerate()
        .map(|(i, p)| (p.name.to_string(), i as u32))
        .collect();
    Ok(RemoteDescription {
        spec,
        action_low,
        action_high,
        graph: SceneGraph::Declared(predicates),
        predicate_bits,
        features: d.features.clone(),
        render: d.render,
        deterministic: d.deterministic,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn description(
        patch: serde_json::Value,
    ) -> Result<RemoteDescription, Box<dyn std::error::Error>> {
        let mut d = json!({
            "id": "Pendulum-v1",
            "observation_space": {"shape": [3], "low": [-1, -1, -8], "high": [1, 1, 8]},
            "action_space": {"shape": [1], "low": [-2], "high": [2]},
            "control_hz": 20,
            "max_episode_steps": 200,
            "predicates": [{"name": "upright", "label": "pendulum upright"}],
            "render": true,
            "deterministic": true
        });
        for (k, v) in patch.as_object().unwrap() {
            d[k] = v.clone();
        }
        let d: Description = serde_json::from_value(d)?;
        Ok(check(&d)?)
    }

    #[test]
    fn a_gymnasium_box_env_reads_into_a_spec_with_unit_actions() {
        let r = description(json!({})).unwrap();
        assert_eq!(r.spec.id, "Pendulum-v1");
        assert_eq!(r.spec.action_space, BoxSpace::uniform(1, -1.0, 1.0));
        assert_eq!(
            (r.action_low.clone(), r.action_high.clone()),
            (vec![-2.0], vec![2.0])
        );
        assert_eq!(r.spec.observation_names, vec!["obs0", "obs1", "obs2"]);
        assert_eq!(r.graph.dim(), 1);
        assert_eq!(r.predicate_bits["upright"], 0);
        let task = r.declared_task();
        assert_eq!(task.features, vec!["obs0", "obs1", "obs2"]);
        assert!(!task.env_features);
        // Unbounded observations are fine (null in JSON).
        let r = description(json!({"observation_space":
            {"shape": [1, 2], "low": [null, 0], "high": [null, 1]}}))
        .unwrap();
        assert_eq!(r.spec.observation_space.low[0], f32::NEG_INFINITY);
    }

    #[test]
    fn a_broken_hello_says_what_is_wrong() {
        let refused = |patch| description(patch).unwrap_err().to_string();
        assert!(
            refused(json!({"action_space": {"shape": [2], "low": [-1], "high": [1]}}))
                .contains("low has 1")
        );
        assert!(
            refused(json!({"action_space": {"shape": [1], "low": [null], "high": [1]}}))
                .contains("unbounded")
        );
        assert!(
            refused(json!({"action_space": {"shape": [1], "low": [1], "high": [-1]}}))
                .contains("low 1")
        );
        assert!(refused(json!({"control_hz": 0})).contains("control_hz"));
        let d: Description = serde_json::from_value(json!({
            "id": "x",
            "observation_space": {"shape": [1], "low": [0], "high": [1]},
            "action_space": {"shape": [1], "low": [1], "high": [1]},
            "control_hz": 20,
            "max_episode_steps": 1
        }))
        .unwrap();
        assert_eq!(
            check(&d),
            Err(DescriptionError::Bounds {
                space: "action_space",
                entry: 0,
                low: 1.0,
                high: 1.0
            })
        );
        assert!(refused(json!({"max_episode_steps": 0})).contains("max_episode_steps"));
        assert!(
            refused(json!({"predicates": [{"name": "A", "label": "a"}]})).contains("predicates")
        );
        assert!(refused(json!({"features": ["x", "x"]})).contains("twice"));
        assert!(refused(json!({"observation_names": ["a"]})).contains("1 names for 3"));
        assert!(refused(json!({"colour": "red"})).contains("unknown field"));
        assert!(
            refused(json!({"observation_space": {"shape": [0], "low": [], "high": []}}))
                .contains("no entries")
        );
    }
}
