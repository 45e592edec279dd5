//! A session's data for other tools: its labelled transitions or preference pairs as Parquet
//! (`tables`, pure), its learner's policy as safetensors (`policy`, pure), its records as JSONL
//! (`session_jsonl`, pure) and its answers as CSV (`answers_csv`, pure), and `session`, which
//! reads a stored session's rows and checkpoint files to make the Parquet and safetensors files; the posterior of a
//! preference session is written by the session itself at its checkpoints
//! (`guidance::drpl::posterior_file`). The HTTP routes (`http::datasets`) and `dualrep export`
//! both serve these.

pub mod answers_csv;
pub mod policy;
pub mod session;
pub mod session_jsonl;
pub mod study_table;
pub mod tables;
