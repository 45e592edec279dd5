//! `dualrep sim`: episodes of a random or heuristic policy, summarised as one JSON object.

use clap::Args;

use super::overrides::parse_pair;
use crate::sim::rollout::{SimplePolicy, run_episodes_with};
use crate::sim::{EnvOptions, Task};

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
    /// Choose the task's version: `--set variant=uniform`, `--set release_at=0.9`,
    /// `--set success=through`, `--set observe_grip=level` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_pair)]
    pub options: Vec<(String, String)>,
}

pub fn run(args: SimArgs) -> anyhow::Result<()> {
    let mut options = EnvOptions::default();
    for (k, v) in &args.options {
        options.set(args.task, k, v).map_err(anyhow::Error::msg)?;
    }
    let (summary, _) =
        run_episodes_with(args.task, &options, args.policy, args.episodes, args.seed);
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}
