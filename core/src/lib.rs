//! # dualrep-core
//!
//! The algorithms of dualrep, after Zhang et al., "A Dual Representation Framework for Robot
//! Learning with Human Guidance" (CoRL 2022), with no IO: no tokio, axum, sqlx or rerun in
//! this crate's dependency tree (the service crate `dualrep` adds those on top, and
//! `tests/module_graph.rs` there checks this crate's tree), so they run headless in tests,
//! benchmarks and the CLI, and their tests link nothing of the service.
//!
//! - [`sim`]: the `Env` trait and the three tasks on rapier: Reaching and Placing (rapier3d),
//!   Lunar Lander (rapier2d, Gymnasium's semantics); heuristic controllers; rollouts.
//! - [`scene_graph`]: each task's predicates, evaluated on `(s_{t+1}, a_t)` into an
//!   `AbstractState` bit vector.
//! - [`rl`]: MLPs on nalgebra with a hand-written backward pass, Adam, losses, the
//!   tanh-squashed Gaussian policy, the replay buffer, and SAC with DREF's twin human critic
//!   (checkpoints as safetensors bytes). `rl::kernels` computes every layer's products: on the
//!   portable path (matrixmultiply) or on the AVX-512 / AVX2 kernels of the `dualrep-kernels`
//!   crate (`kernels/`), chosen at run time, on one or more threads.
//! - [`guidance`]: when to ask (DREF's UCB query rule, EF-p%, a person's pace), who answers
//!   (the `EvaluativeTrainer` trait, the expert oracle, simulated teachers' faults), the
//!   evaluative training loop, what to ask (DRPL), and how much trainers agree.
//!
//! Feature `schema` derives `utoipa::ToSchema` on the types the service's REST API shows.

pub mod guidance;
pub mod rl;
pub mod scene_graph;
pub mod sim;
