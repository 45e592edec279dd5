//! Where a session's environment lives when it is not our simulator (the launch request's
//! `env: {"url": ...}`, the CLI's `--env-url`), and connecting to it for a run: as a remote copy
//! of a built-in task (its scene graph, features and expert are ours, so its sizes must be the
//! task's) or as a task of its own.

use serde::{Deserialize, Serialize};

use super::client::{RemoteEnv, Timeouts};
use crate::sim::{EnvFault, Task};

/// An environment in another process (`docs/env-protocol.md`), as a launch request and a
/// stored session name it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RemoteTarget {
    /// `tcp://HOST:PORT` of a server speaking `docs/env-protocol.md`.
    #[schema(example = "tcp://127.0.0.1:5555")]
    pub url: String,
}

impl RemoteTarget {
    /// Check the URL's form (the env itself is reached when the session starts).
    pub fn validate(&self) -> Result<(), EnvFault> {
        super::client::parse_url(&self.url).map(|_| ())
    }

    /// Connect; with `task`, check that the env is a copy of it (the same observation and
    /// action sizes: the task's scene graph, features and expert read them).
    pub fn connect(&self, task: Option<Task>, timeouts: Timeouts) -> Result<RemoteEnv, EnvFault> {
        let env = RemoteEnv::connect(&self.url, timeouts)?;
        if let Some(task) = task {
            let ours = task.make_env();
            let (o, a) = (
                ours.spec().observation_space.dim(),
                ours.spec().action_space.dim(),
            );
            let d = env.description();
            if (d.observation_dim(), d.action_dim()) != (o, a) {
                return Err(EnvFault(format!(
                    "the env at {} ({}) has {} observations and {} actions; {task} has {o} and {a}, so it cannot stand in for {task}",
                    self.url,
                    d.spec.id,
                    d.observation_dim(),
                    d.action_dim()
                )));
            }
        }
        Ok(env)
    }
}
