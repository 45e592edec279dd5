//! `dualrep sim`: episodes of a random or heuristic policy, summarised as one JSON object.

use clap::Args;

use super::overrides::parse_pair;
use crate::settings::Settings;
use crate::sim::Task;
use crate::sim::rollout::{SimplePolicy, run_episodes_with};

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
    let options = Settings::from_pairs(args.options.iter().map(|(k, v)| (k.as_str(), v.as_str())))
        .and_then(|s| s.env_options(args.task))?;
    let (summary, _) =
        run_episodes_with(args.task, &options, args.policy, args.episodes, args.seed);
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}
