//! `dualrep sim`: episodes of a random or heuristic policy, summarised as one JSON object.

use clap::Args;

use crate::sim::Task;
use crate::sim::rollout::{SimplePolicy, run_episodes};

#[derive(Debug, Args)]
pub struct SimArgs {
    /// reaching, placing or lunar-lander.
    #[arg(long)]
    pub task: Task,
    /// random or heuristic.
    #[arg(long, default_value = "heuristic")]
    pub policy: SimplePolicy,
    /// Number of episodes (seeds seed, seed + 1, ...).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    pub episodes: u32,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

pub fn run(args: SimArgs) -> anyhow::Result<()> {
    let (summary, _) = run_episodes(args.task, args.policy, args.episodes, args.seed);
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}
