//! The `dualrep` command line: one sub-command per file, each a thin shell over the library.

mod reproduce;
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
    /// Run the paper's Figure 3 or 5 grid as parallel processes; write table.md and figures.
    Reproduce(reproduce::ReproduceArgs),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Sim(args) => sim::run(args),
        Command::Reproduce(args) => reproduce::run(args),
    }
}
