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
//! - [`rl`]: SAC's parts: MLPs on nalgebra with a hand-written backward pass, Adam, losses,
//!   the tanh-squashed Gaussian policy, the replay buffer.
//! - [`guidance`]: when to ask (DREF's UCB query rule, EF-p%) and, later, what to ask (DRPL).
//! - [`report`]: the paper's Figures 3 and 5: the run grid, aggregation over seeds, `table.md`,
//!   SVG and PNG figures (aggregation and tables are pure; reading runs and drawing are the IO).
//!
//! The edge:
//!
//! - [`cli`]: the `dualrep` command line (`sim` today).

pub mod cli;
pub mod guidance;
pub mod report;
pub mod rl;
pub mod scene_graph;
pub mod sim;
