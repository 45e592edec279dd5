//! Every integration test of the service in one binary. Each test binary links the whole Rerun
//! SDK (hundreds of megabytes and most of a test build's link time), so the suite links it once.
//! The algorithms' own tests (tasks, networks, SAC, no-allocation counts) are the core crate's,
//! in `core/tests/`, and link nothing of the service.
//!
//! Select a group by its module name: `cargo test --test suite browser::`.

mod report_fixtures;
mod support;

mod api_surface;
mod browser;
mod cli;
mod datasets;
mod durability;
mod http_api;
mod module_graph;
mod prefs_e2e;
mod recording;
mod remote_env_failures;
mod remote_envs;
mod report;
mod reproduce;
mod sac_settings;
mod security_headers;
mod serving_proxy;
mod serving_several;
mod session_recording;
mod sim_checkpoint;
mod slurm;
mod store;
mod store_people;
mod studies;
mod study_pilot;
mod train_branch;
mod train_e2e;
mod ws_sessions;
mod ws_undo;
