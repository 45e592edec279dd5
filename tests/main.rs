//! Every integration test in one binary. Each test binary links the whole Rerun SDK (hundreds
//! of megabytes and most of a test build's link time), so the suite links it once. The
//! no-allocation tests share the binary: the counting allocator below keeps its counters per
//! thread, so the tests running beside them do not disturb their counts (one that must count
//! helper threads too re-runs this binary for itself alone: `sac_no_alloc.rs`).
//!
//! Select a group by its module name: `cargo test --test suite browser::`.

mod report_fixtures;
mod support;

#[global_allocator]
static GLOBAL: support::counting_alloc::Counting = support::counting_alloc::Counting;

mod belief_no_alloc;
mod browser;
mod cli;
mod datasets;
mod durability;
mod env_contract;
mod http_api;
mod lunar_lander;
mod module_graph;
mod prefs_e2e;
mod recording;
mod remote_env_failures;
mod remote_envs;
mod report;
mod reproduce;
mod rl_gradients;
mod rl_no_alloc;
mod sac;
mod sac_no_alloc;
mod security_headers;
mod session_recording;
mod slurm;
mod store;
mod tabletop;
mod train_e2e;
mod ws_sessions;
