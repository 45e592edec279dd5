//! Environments in another process or on another machine (`docs/env-protocol.md`): any
//! Gymnasium env or a robot behind `python -m dualrep.env`, stepped by a session or the CLI
//! like the built-in tasks. Blocking std networking on the caller's thread (a session's own),
//! a deadline on every read, and a clear reason for every fault.
//!
//! - `wire`: the framing (length-prefixed JSON, raw frame bytes) and the messages.
//! - `description`: the env's `hello`, checked, as the `EnvSpec` the learner sees.
//! - `client`: [`RemoteEnv`], the `Env` over a connection.
//! - `source`: where a run's env comes from (a built-in task, or a URL) and what it declared.

mod client;
pub mod description;
mod source;
pub mod wire;

pub use client::{DEFAULT_REQUEST_TIMEOUT, RemoteEnv, Timeouts, parse_url};
pub use description::{DescriptionError, RemoteDescription};
pub use source::RemoteTarget;
