//! DRPL: preference learning over scene-graph segments (algorithms.md section 3). No IO.
//!
//! - `trajectories`: random-policy trajectories with the scene graph per step.
//! - `trajectory_bytes`: recorded trajectories as bytes (kept by sessions on remote envs).
//! - `features`: each task's reward features phi(s_{t+1}, a_t).
//! - `segments`: cut where g changes, merge short runs, mean features, standardisation.
//! - `pool`: the run's trajectories' features and segments; clips (one side of a query).
//! - `state_pairs`: DRPL's and DRPL-SS's candidates by abstract state, drawn without repeats.
//! - `selection`: the pair per method (DRPL, DRPL-SS, random fragment, full trajectory).
//! - `trainer`: the `PreferenceTrainer` trait and the synthetic oracle.
//! - `simulated_teacher`: the synthetic oracle with a teacher's faults (B-Pref).
//! - `belief`: the Bayesian belief over the reward weights theta (APReL's sampling-based
//!   belief: softmax user, uniform prior on the ball, Metropolis-Hastings).
//! - `acquisition`: how a query is scored among candidates (uniform, APReL's mutual information).
//! - `run`: one run, query by query.
//! - `posterior_file`: the posterior (samples and mean theta) as safetensors for other tools.

pub mod acquisition;
pub mod belief;
pub mod features;
pub mod pool;
pub mod posterior_file;
pub mod run;
pub mod segments;
pub mod selection;
pub mod simulated_teacher;
pub mod state_pairs;
pub mod trainer;
pub mod trajectories;
pub mod trajectory_bytes;
