//! Running the `dualrep` binary from integration tests.

use std::path::Path;
use std::process::{Command, Output};

/// Run `dualrep args...`, in `dir` when given.
pub fn dualrep_in(args: &[&str], dir: Option<&Path>) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_dualrep"));
    command.args(args);
    if let Some(dir) = dir {
        command.current_dir(dir);
    }
    command.output().expect("binary runs")
}

/// The one-line JSON summary a successful command prints last.
pub fn ok(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().expect("a summary line")).unwrap()
}
