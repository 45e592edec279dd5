//! `dualrep sim`: episodes of a random or heuristic policy, summarised as one JSON object, and
//! optionally every step of them as CSV with the scene graph's abstract state.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use super::output::write_atomically;
use super::overrides::parse_pair;
use crate::scene_graph::SceneGraph;
use crate::settings::Settings;
use crate::sim::Task;
use crate::sim::rollout::{ActionNoise, SimplePolicy, StepSeen, run_episodes_watched};

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
    /// The standard deviation of Gaussian noise added to each of the policy's actions (then
    /// clipped to [-1, 1]): a heuristic that sometimes fails.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f32,
    /// The noise's correlation from one step to the next, in [0, 1): 0 is white noise, 0.95
    /// keeps a push for about 20 steps (0.4 s on Lunar Lander).
    #[arg(long, default_value_t = 0.0)]
    pub noise_correlation: f32,
    /// Write every step here as CSV: seed, t, the observation after the step, the action, the
    /// reward, the product's scene graph on them (its abstract state as bits, predicate order)
    /// and, on an episode's last step, its outcome.
    #[arg(long, value_name = "PATH")]
    pub steps: Option<PathBuf>,
    /// Choose the task's version: `--set variant=uniform`, `--set release_at=0.9`,
    /// `--set success=through`, `--set observe_grip=level` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_pair)]
    pub options: Vec<(String, String)>,
}

pub fn run(args: SimArgs) -> anyhow::Result<()> {
    let noise = ActionNoise {
        std: args.noise,
        correlation: args.noise_correlation,
    }
    .check()
    .context("--noise, --noise-correlation")?;
    let options = Settings::from_pairs(args.options.iter().map(|(k, v)| (k.as_str(), v.as_str())))
        .and_then(|s| s.env_options(args.task))?;
    let mut steps = args.steps.as_ref().map(|_| StepTable::new(args.task));
    let mut watch = |seen: StepSeen<'_>| {
        if let Some(table) = steps.as_mut() {
            table.push(&seen);
        }
    };
    let (summary, _) = run_episodes_watched(
        args.task,
        &options,
        args.policy,
        noise,
        args.episodes,
        args.seed,
        &mut watch,
    );
    if let (Some(path), Some(table)) = (&args.steps, steps) {
        write_atomically(path, table.csv.as_bytes())
            .with_context(|| format!("--steps {}", path.display()))?;
    }
    println!("{}", serde_json::to_string(&summary)?);
    Ok(())
}

/// The steps of `sim --steps`, one CSV row each, built as the episodes run.
struct StepTable {
    graph: SceneGraph,
    csv: String,
    /// The header is written on the first step, when the observation's and action's sizes are
    /// known.
    header_written: bool,
}

impl StepTable {
    fn new(task: Task) -> Self {
        Self {
            graph: SceneGraph::for_task(task),
            csv: String::new(),
            header_written: false,
        }
    }

    fn push(&mut self, seen: &StepSeen<'_>) {
        if !self.header_written {
            self.csv.push_str("seed,t");
            (0..seen.next_obs.len()).for_each(|i| write!(self.csv, ",obs_{i}").unwrap());
            (0..seen.action.len()).for_each(|i| write!(self.csv, ",action_{i}").unwrap());
            self.csv.push_str(",reward,abstract_state,outcome\n");
            self.header_written = true;
        }
        write!(self.csv, "{},{}", seen.seed, seen.t).unwrap();
        for v in seen.next_obs.iter().chain(seen.action) {
            write!(self.csv, ",{v}").unwrap();
        }
        let state = self.graph.evaluate(seen.next_obs, seen.action);
        writeln!(
            self.csv,
            ",{},{},{}",
            seen.reward,
            state.to_bit_string(self.graph.dim()),
            seen.outcome.map_or("", |o| o.id())
        )
        .unwrap();
    }
}
