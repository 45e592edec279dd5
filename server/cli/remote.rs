//! `--env-url` for `train`, `prefs` and `expert`: run on an environment in another process
//! (`docs/env-protocol.md`), as a remote copy of `--task` or as a task of its own.

use std::time::Duration;

use anyhow::bail;
use clap::Args;

use crate::remote_env::{RemoteEnv, RemoteTarget, Timeouts};
use crate::sim::Task;

#[derive(Debug, Args)]
pub struct RemoteArgs {
    /// Step an env served at this URL (`tcp://HOST:PORT`, e.g. by `python -m dualrep.env`)
    /// instead of our simulator. With `--task`, it stands in for that task (its scene graph,
    /// features and expert); without, it is a task of its own, with the predicates it declares.
    #[arg(long, value_name = "URL")]
    pub env_url: Option<String>,
    /// Seconds the remote env may take to answer one request (a reset included).
    #[arg(long, default_value_t = 30.0, value_name = "S")]
    pub env_timeout_s: f64,
}

impl RemoteArgs {
    /// The remote env, connected (checked against `task` when given); `None` without
    /// `--env-url`, where `task` must be given.
    pub fn connect(&self, task: Option<Task>) -> anyhow::Result<Option<RemoteEnv>> {
        let Some(url) = &self.env_url else {
            if task.is_none() {
                bail!("give --task, --env-url, or both");
            }
            return Ok(None);
        };
        if !(self.env_timeout_s.is_finite() && self.env_timeout_s > 0.0) {
            bail!("--env-timeout-s: expected a positive number of seconds");
        }
        let timeouts = Timeouts {
            request: Duration::from_secs_f64(self.env_timeout_s),
            ..Timeouts::default()
        };
        let target = RemoteTarget { url: url.clone() };
        Ok(Some(target.connect(task, timeouts)?))
    }
}
