//! The core crate's integration tests in one binary: the tasks and their scene graphs, the
//! networks against finite differences and PyTorch's values, SAC, DRPL's belief, and what the
//! hot loops allocate. Nothing of the service links here: no tokio, axum, sqlx or rerun.
//!
//! The no-allocation tests share the binary: the counting allocator below keeps its counters
//! per thread, so the tests running beside them do not disturb their counts (one that must
//! count helper threads too re-runs this binary for itself alone: `sac_no_alloc.rs`).
//!
//! Select a group by its module name: `cargo test -p dualrep-core --test core rl_gradients::`.

mod support;

#[global_allocator]
static GLOBAL: support::counting_alloc::Counting = support::counting_alloc::Counting;

mod belief_no_alloc;
mod env_contract;
mod lunar_lander;
mod placing;
mod rl_gradients;
mod rl_layer_norm;
mod rl_no_alloc;
mod sac;
mod sac_no_alloc;
mod tabletop;
