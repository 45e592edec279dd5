//! `dualrep expert`: train the SAC expert that the synthetic evaluative trainer consults, and
//! write it as safetensors plus a JSON note of how it was made (steps, seed, config, returns).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use super::output::{publish_summary, write_atomically};
use super::overrides;
use super::train::{NoTrainer, drive, final_performance, resolve_config};
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig, evaluate_policy};
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::sim::Task;

#[derive(Debug, Args)]
pub struct ExpertArgs {
    #[arg(long)]
    pub task: Task,
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
    /// Episodes of the deterministic policy evaluated at the end.
    #[arg(long, default_value_t = 20)]
    pub eval_episodes: u32,
}

/// The note shipped beside an expert.
#[derive(Debug, Serialize)]
struct ExpertNote {
    task: Task,
    steps: u64,
    seed: u64,
    episodes: u64,
    /// Mean return of the last 10 training episodes (stochastic policy).
    final_mean_return: f64,
    /// Deterministic policy on `eval_episodes` fresh seeds (1_000_000, 1_000_001, ...).
    eval_episodes: u32,
    eval_mean_return: f64,
    eval_success_rate: f64,
    wall_seconds: f64,
    config: EvaluativeRunConfig,
}

pub fn run(args: ExpertArgs) -> anyhow::Result<()> {
    let config = resolve_config(args.task, EvaluativeMethod::Sac, args.seed, &args.overrides)?;
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let metrics_dir = args.out.with_extension("train");
    std::fs::create_dir_all(&metrics_dir)?;
    let start = Instant::now();
    let mut run = EvaluativeRun::new(config.clone(), args.steps);
    let label = format!("expert {} seed {}", args.task, args.seed);
    let episodes = drive(&mut run, &mut NoTrainer, args.steps, &metrics_dir, &label)?;
    let (final_mean_return, _) = final_performance(&episodes, 10);
    let episodes_done = run.episodes();
    let mut learner = run.into_learner();
    let (eval_mean_return, eval_success_rate) =
        evaluate_policy(args.task, &mut learner, args.eval_episodes, 1_000_000);
    write_atomically(&args.out, &learner.to_safetensors())?;
    let note = ExpertNote {
        task: args.task,
        steps: args.steps,
        seed: args.seed,
        episodes: episodes_done,
        final_mean_return,
        eval_episodes: args.eval_episodes,
        eval_mean_return,
        eval_success_rate,
        wall_seconds: start.elapsed().as_secs_f64(),
        config,
    };
    publish_summary(&args.out.with_extension("json"), &note)
}
