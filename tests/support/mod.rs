//! Helpers shared by the integration tests.

pub mod binary;
pub mod cli;
pub mod debian;
pub mod line_env;
pub mod nginx;
pub mod postgres;
pub mod py_venv;
pub mod pyarrow_py;
pub mod python_client;
pub mod rerun_py;
pub mod rest;
pub mod server;
pub mod shared_db;
pub mod slurm_cluster;
pub mod store_backends;
pub mod trainer;
