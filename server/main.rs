//! The `dualrep` binary: parse the command line and hand over to `dualrep::cli`.

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = dualrep::cli::Cli::parse();
    match dualrep::cli::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
