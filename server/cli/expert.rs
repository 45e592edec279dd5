//! `dualrep expert`: train the SAC expert that the synthetic evaluative trainer consults, and
//! write it as safetensors plus a JSON note of how it was made (steps, seed, config, returns).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use super::output::{publish_summary, write_atomically};
use super::overrides;
use super::remote::RemoteArgs;
use super::train::{NoTrainer, drive, final_performance, resolve_config, resolve_remote_config};
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig, evaluate_policy_on};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::rl::Sac;
use crate::sim::{Env, Task};

#[derive(Debug, Args)]
pub struct ExpertArgs {
    /// reaching, placing or lunar-lander (with `--env-url`: the task the remote env copies).
    #[arg(long)]
    pub task: Option<Task>,
    #[arg(long, default_value_t = 200_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub steps: u64,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Where to write the expert, e.g. models/lunar-lander.safetensors (the note goes beside it
    /// with the extension .json; training metrics go to a folder with the extension .train).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub overrides: overrides::OverrideArgs,
    /// Episodes of the deterministic policy evaluated at the end (and at each periodic check).
    #[arg(long, default_value_t = 20)]
    pub eval_episodes: u32,
    /// Evaluate the deterministic policy every N steps and ship the best one seen (SB3's
    /// "best model"): SAC on Lunar Lander can drift from landing back to hovering late in a
    /// run, and the oracle should be the best policy the run found. 0 ships the last policy.
    #[arg(long, default_value_t = 0)]
    pub eval_every: u64,
    /// With `--env-url`, the policy is evaluated on a second connection to the env (a robot
    /// that serves one connection at a time needs `--eval-episodes 0`).
    #[command(flatten)]
    pub remote: RemoteArgs,
}

/// The note shipped beside an expert.
#[derive(Debug, Serialize)]
struct ExpertNote {
    task: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    env_url: Option<String>,
    steps: u64,
    seed: u64,
    episodes: u64,
    /// Mean return of the last 10 training episodes (stochastic policy).
    final_mean_return: f64,
    /// Deterministic policy on `eval_episodes` fresh seeds (1_000_000, 1_000_001, ...).
    eval_episodes: u32,
    eval_mean_return: f64,
    eval_success_rate: f64,
    /// With `--eval-every`: the step whose policy was shipped, and every periodic check.
    #[serde(skip_serializing_if = "Option::is_none")]
    shipped_step: Option<u64>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    checks: Vec<EvalCheck>,
    wall_seconds: f64,
    config: EvaluativeRunConfig,
}

/// One periodic evaluation of the policy during training.
#[derive(Debug, Serialize)]
struct EvalCheck {
    step: u64,
    mean_return: f64,
    success_rate: f64,
}

/// The policy's mean return and success rate on a fresh env: ours, or a new connection to the
/// remote one (0 episodes: not evaluated, NaN).
fn evaluate(
    args: &ExpertArgs,
    config: &EvaluativeRunConfig,
    learner: &mut Sac,
    seed: u64,
) -> anyhow::Result<(f64, f64)> {
    if args.eval_episodes == 0 {
        return Ok((f64::NAN, f64::NAN));
    }
    let mut env: Box<dyn Env> = match args.remote.connect(args.task)? {
        Some(remote) => Box::new(remote),
        None => config.make_env(),
    };
    Ok(evaluate_policy_on(
        env.as_mut(),
        learner,
        args.eval_episodes,
        seed,
    )?)
}

pub fn run(args: ExpertArgs) -> anyhow::Result<()> {
    let remote = args.remote.connect(args.task)?;
    let config = match (&remote, args.task) {
        (Some(env), task) => {
            resolve_remote_config(env, task, EvaluativeMethod::Sac, args.seed, &args.overrides)?
        }
        (None, Some(task)) => {
            resolve_config(task, EvaluativeMethod::Sac, args.seed, &args.overrides)?
        }
        (None, None) => unreachable!("RemoteArgs::connect asks for a task"),
    };
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let metrics_dir = args.out.with_extension("train");
    std::fs::create_dir_all(&metrics_dir)?;
    let start = Instant::now();
    let mut run = match remote {
        Some(env) => EvaluativeRun::with_env(config.clone(), Box::new(env), args.steps)?,
        None => EvaluativeRun::new(config.clone(), args.steps),
    };
    let label = format!("expert {} seed {}", config.task, args.seed);
    let mut episodes = Vec::new();
    let mut checks = Vec::new();
    // (mean return, step, policy) of the best periodic check so far.
    let mut best: Option<(f64, u64, Sac)> = None;
    let chunk = if args.eval_every == 0 {
        args.steps
    } else {
        args.eval_every
    };
    let mut target = 0;
    while target < args.steps {
        target = (target + chunk).min(args.steps);
        let appending = run.steps() > 0;
        let mut more = drive(
            &mut run,
            &mut NoTrainer,
            target,
            &metrics_dir,
            &label,
            appending,
            None,
        )?;
        episodes.append(&mut more);
        if args.eval_every > 0 {
            // Evaluate a copy, so the check leaves the run's own state (and its RNG) untouched.
            let mut copy = run.learner().clone();
            let (mean_return, success_rate) = evaluate(&args, &config, &mut copy, 2_000_000)?;
            eprintln!(
                "expert check at step {target}: return {mean_return:.1}, success {success_rate:.2}"
            );
            checks.push(EvalCheck {
                step: target,
                mean_return,
                success_rate,
            });
            if best.as_ref().is_none_or(|(b, _, _)| mean_return > *b) {
                // On disk at once, so a long run stopped early still leaves its best policy.
                write_atomically(&args.out, &copy.to_safetensors())?;
                best = Some((mean_return, target, copy));
            }
        }
    }
    let (final_mean_return, _) = final_performance(&episodes, 10);
    let episodes_done = run.episodes();
    let (shipped_step, mut learner) = match best {
        Some((_, step, policy)) => (Some(step), policy),
        None => (None, run.into_learner()),
    };
    // The shipped policy is judged on seeds the periodic checks never saw.
    let (eval_mean_return, eval_success_rate) = evaluate(&args, &config, &mut learner, 1_000_000)?;
    write_atomically(&args.out, &learner.to_safetensors())?;
    let note = ExpertNote {
        task: config.task.id().to_string(),
        env_url: args.remote.env_url.clone(),
        steps: args.steps,
        seed: args.seed,
        episodes: episodes_done,
        final_mean_return,
        eval_episodes: args.eval_episodes,
        eval_mean_return,
        eval_success_rate,
        shipped_step,
        checks,
        wall_seconds: start.elapsed().as_secs_f64(),
        config,
    };
    publish_summary(&args.out.with_extension("json"), &note)
}
