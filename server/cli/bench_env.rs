//! `dualrep bench env`: environment steps per second under a random policy (resets included,
//! as in training), on our simulator and, in the same run, through the env protocol
//! (`docs/env-protocol.md`) on a remote env, plus an env that does nothing (`--null-url`: what
//! the protocol itself costs per step). One JSON object.

use std::time::{Duration, Instant};

use anyhow::bail;
use clap::Args;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::remote_env::{RemoteTarget, Timeouts};
use crate::sim::{Env, Task};

#[derive(Debug, Args)]
pub struct EnvBenchArgs {
    /// Our task to time in-process (and the one `--env-url` copies).
    #[arg(long)]
    pub task: Task,
    /// A remote env to time through the protocol, e.g. Gymnasium's copy of the task served by
    /// `python -m dualrep.env`.
    #[arg(long)]
    pub env_url: Option<String>,
    /// An env whose steps do nothing, served the same way: its rate is the protocol's own.
    #[arg(long)]
    pub null_url: Option<String>,
    /// Timed steps per env.
    #[arg(long, default_value_t = 20_000)]
    pub steps: u64,
    /// Time only the remote envs (a caller measuring CPU time per env runs them apart).
    #[arg(long)]
    pub skip_in_process: bool,
}

/// One env's timing.
#[derive(Serialize)]
struct Timing {
    env: String,
    steps: u64,
    episodes: u64,
    steps_per_second: f64,
    microseconds_per_step: f64,
}

#[derive(Serialize)]
struct EnvBench {
    task: Task,
    #[serde(skip_serializing_if = "Option::is_none")]
    in_process: Option<Timing>,
    #[serde(skip_serializing_if = "Option::is_none")]
    remote: Option<Timing>,
    /// In-process steps per second over remote ones.
    #[serde(skip_serializing_if = "Option::is_none")]
    in_process_over_remote: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    null_remote: Option<Timing>,
}

/// Step `env` `steps` times with uniform random actions, resetting as episodes end.
fn time_env(env: &mut dyn Env, steps: u64) -> anyhow::Result<Timing> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut action = vec![0.0f32; env.spec().action_space.dim()];
    let mut episodes = 0u64;
    env.try_reset(episodes)?;
    let start = Instant::now();
    for _ in 0..steps {
        action
            .iter_mut()
            .for_each(|a| *a = rng.random_range(-1.0..=1.0));
        if env.try_step(&action)?.done() {
            episodes += 1;
            env.try_reset(episodes)?;
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    Ok(Timing {
        env: env.spec().id.to_string(),
        steps,
        episodes,
        steps_per_second: steps as f64 / seconds,
        microseconds_per_step: seconds * 1e6 / steps as f64,
    })
}

fn time_remote(url: &str, task: Option<Task>, steps: u64) -> anyhow::Result<Timing> {
    let timeouts = Timeouts {
        request: Duration::from_secs(30),
        ..Timeouts::default()
    };
    let target = RemoteTarget {
        url: url.to_string(),
    };
    let mut env = target.connect(task, timeouts)?;
    time_env(&mut env, steps)
}

pub fn bench_env(args: EnvBenchArgs) -> anyhow::Result<()> {
    if args.steps == 0 {
        bail!("--steps must be at least 1");
    }
    let in_process = match args.skip_in_process {
        true => None,
        false => Some(time_env(args.task.make_env().as_mut(), args.steps)?),
    };
    let remote = match &args.env_url {
        Some(url) => Some(time_remote(url, Some(args.task), args.steps)?),
        None => None,
    };
    let null_remote = match &args.null_url {
        Some(url) => Some(time_remote(url, None, args.steps)?),
        None => None,
    };
    let report = EnvBench {
        task: args.task,
        in_process_over_remote: remote
            .as_ref()
            .zip(in_process.as_ref())
            .map(|(r, i)| i.steps_per_second / r.steps_per_second),
        in_process,
        remote,
        null_remote,
    };
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}
