//! The `dualrep` command line: one sub-command per file, each a thin shell over the library.

mod bench;
mod sim;

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(
    name = "dualrep",
    version,
    about = "Teach robots from a browser (DREF and DRPL)"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a random or heuristic policy on a task and print a JSON summary.
    Sim(sim::SimArgs),
    /// Time the learner: `bench sac` prints updates per second against the sgemm peak.
    Bench(bench::BenchArgs),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Sim(args) => sim::run(args),
        Command::Bench(args) => bench::run(args),
    }
}
