//! `dualrep bench train`: environment steps per second of a whole run, end to end: the env, the
//! scene graph, the query rule, the synthetic trainer (the expert oracle) and one gradient step
//! per environment step, exactly as `dualrep train` runs it, minus the files. One JSON object.
//! `benches/reference/sb3_train.py` is stable-baselines3's SAC on Gymnasium's
//! `LunarLanderContinuous-v3` with the same configuration.

use std::time::Instant;

use clap::Args;
use serde::Serialize;

use super::compute::Compute;
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig};
use crate::guidance::evaluative_trainer::{EvaluativeTrainer, NoTrainer};
use crate::guidance::expert_oracle::ExpertOracle;
use crate::guidance::feedback_schedule::EvaluativeMethod;
use crate::rl::kernels::{self, KernelPath};
use crate::sim::Task;

#[derive(Debug, Args)]
pub struct TrainBenchArgs {
    /// reaching, placing or lunar-lander.
    #[arg(long)]
    pub task: Task,
    /// dref (the default: env, scene graph, oracle and the human critic's update), sac or
    /// ef-<percent>.
    #[arg(long, default_value = "dref")]
    pub method: EvaluativeMethod,
    /// Environment steps to time (one gradient step each, from the first).
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u64).range(1..))]
    pub steps: u64,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

#[derive(Serialize)]
struct TrainBench {
    task: Task,
    method: EvaluativeMethod,
    steps: u64,
    kernels: KernelPath,
    threads: usize,
    seconds: f64,
    env_steps_per_second: f64,
    /// Queries the oracle answered.
    feedback_count: u64,
}

pub fn run(args: TrainBenchArgs, compute: &Compute) -> anyhow::Result<()> {
    let threads = compute.threads_alone();
    let config = EvaluativeRunConfig::new(args.task, args.method, args.seed);
    let mut trainer: Box<dyn EvaluativeTrainer> = match args.method {
        EvaluativeMethod::Sac => Box::new(NoTrainer),
        _ => {
            let expert = crate::session::load_task_expert(None, args.task)?;
            let act_dim = config.make_env().spec().action_space.dim();
            Box::new(ExpertOracle::new(expert, act_dim))
        }
    };
    let mut run = EvaluativeRun::new(config, args.steps);
    let start = Instant::now();
    kernels::with_threads(threads, || {
        while run.steps() < args.steps {
            run.step(trainer.as_mut());
        }
    });
    let seconds = start.elapsed().as_secs_f64();
    let report = TrainBench {
        task: args.task,
        method: args.method,
        steps: args.steps,
        kernels: kernels::current_path(),
        threads,
        seconds,
        env_steps_per_second: args.steps as f64 / seconds,
        feedback_count: run.feedback_count(),
    };
    println!("{}", serde_json::to_string(&report)?);
    Ok(())
}
