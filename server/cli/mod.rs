//! The `dualrep` command line: one sub-command per file, each a thin shell over the library.

mod answer_log;
mod arg_error;
mod bench;
mod bench_env;
mod bench_kernels;
mod bench_train;
mod compute;
mod episode_file;
mod expert;
mod export;
mod grid_executor;
mod learner_log;
mod loadtest;
mod output;
pub(crate) mod overrides;
mod prefs;
mod progress;
mod remote;
mod report;
mod reproduce;
pub mod serve;
#[cfg(test)]
mod settings_reach;
mod sim;
mod sim_judge;
mod study;
mod study_server;
mod train;
mod train_branch;
mod train_checkpoint;

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
    #[command(flatten)]
    pub compute: compute::ComputeArgs,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Serve the web UI, the REST API and the trainer websockets; run training sessions.
    Serve(serve::ServeArgs),
    /// Run a random or heuristic policy on a task and print a JSON summary.
    Sim(sim::SimArgs),
    /// Train SAC, EF-p% or DREF with the synthetic evaluative trainer; write metrics.csv and summary.json.
    Train(train::TrainArgs),
    /// Learn a reward from preferences (DRPL or a baseline) with the synthetic oracle; write alignment.csv and summary.json.
    Prefs(prefs::PrefsArgs),
    /// Train the SAC expert that the synthetic evaluative trainer consults.
    Expert(expert::ExpertArgs),
    /// Run the paper's Figure 3 or 5 grid (or the robustness grid) here or on Slurm; write table.md and figures.
    Reproduce(reproduce::ReproduceArgs),
    /// A stored session's datasets from a data dir: transitions or pairs (Parquet), posterior or policy (safetensors).
    Export(export::ExportArgs),
    /// Real websocket trainers against a server: answers per second, ack latency, lost answers.
    Loadtest(loadtest::LoadtestArgs),
    /// Time the learner: `bench sac` (updates per second against the FMA peak), `bench train`
    /// (environment steps per second of a whole run), `bench kernels`, `bench belief`.
    Bench(bench::BenchArgs),
    /// Human-subject studies: `study create` and `study list` on a running server; `study
    /// pilot` estimates a study's power with simulated participants before anyone is recruited.
    Study(study::StudyArgs),
    /// Reports from a data dir: `report study` writes a study's results, tidy table (CSV,
    /// Parquet) and figure (SVG, PNG).
    Report(report::ReportArgs),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    let compute = cli.compute.install()?;
    match cli.command {
        Command::Serve(args) => serve::run(args),
        Command::Sim(args) => sim::run(args),
        Command::Train(args) => train::run(args),
        Command::Prefs(args) => prefs::run(args),
        Command::Expert(args) => expert::run(args),
        Command::Reproduce(args) => reproduce::run(args, &compute),
        Command::Export(args) => export::run(args),
        Command::Bench(args) => bench::run(args, &compute),
        Command::Loadtest(args) => loadtest::run(args),
        Command::Study(args) => study::run(args),
        Command::Report(args) => report::run(args),
    }
}
