//! A session's data for other tools: its labelled transitions or preference pairs as Parquet
//! (`tables`, pure), its learner's policy as safetensors (`policy`, pure), and `session`, which
//! reads a stored session's rows and checkpoint files to make them; the posterior of a
//! preference session is written by the session itself at its checkpoints
//! (`guidance::drpl::posterior_file`). The HTTP routes (`http::datasets`) and `dualrep export`
//! both serve these.

pub mod policy;
pub mod session;
pub mod tables;
