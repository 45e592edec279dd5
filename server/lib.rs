//! # dualrep
//!
//! Teach robots from a browser: a robot trains its SAC policy in simulation and asks people for
//! guidance, choosing *when* to ask (DREF) and *what* to ask (DRPL) from a symbolic scene graph,
//! after Zhang et al., "A Dual Representation Framework for Robot Learning with Human Guidance"
//! (CoRL 2022).
//!
//! ## Layout
//!
//! Algorithm modules do no IO (no tokio, axum, sqlx or rerun), so they run headless in tests,
//! benchmarks and the CLI:
//!
//! - [`sim`]: the `Env` trait and the three tasks on rapier: Reaching and Placing (rapier3d),
//!   Lunar Lander (rapier2d, Gymnasium's semantics); heuristic controllers; rollouts.
//! - [`scene_graph`]: each task's predicates, evaluated on `(s_{t+1}, a_t)` into an
//!   `AbstractState` bit vector.
//! - [`rl`]: MLPs on nalgebra with a hand-written backward pass, Adam, losses, the
//!   tanh-squashed Gaussian policy, the replay buffer, and SAC with DREF's twin human critic
//!   (checkpoints as safetensors bytes).
//! - [`guidance`]: when to ask (DREF's UCB query rule, EF-p%), who answers (the
//!   `EvaluativeTrainer` trait, the expert oracle), the evaluative training loop; later, what
//!   to ask (DRPL).
//!
//! The edge (files and processes):
//!
//! - [`record`]: the Rerun recording of a session (scene per step, rewards, predicates,
//!   queries and answers on `step` and `episode` timelines) to an `.rrd` file and/or a live
//!   viewer, from a logging thread behind a bounded channel.
//! - [`report`]: the paper's Figures 3 and 5: the run grid and its child processes, aggregation
//!   over seeds, `table.md`, SVG and PNG figures (aggregation and tables are pure functions).
//! - [`cli`]: the `dualrep` command line: `sim`, `train`, `prefs`, `expert`, `reproduce`,
//!   `bench`.

pub mod cli;
pub mod guidance;
pub mod record;
pub mod report;
pub mod rl;
pub mod scene_graph;
pub mod sim;
