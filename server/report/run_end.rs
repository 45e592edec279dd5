//! How a run ended, judged the same way whichever executor ran it: a run succeeded when its
//! program exited 0 *and* left its `summary.json`; anything else is a failure, explained with
//! the last line of the run's `stderr.log` (where `dualrep` prints its `error: ...`).
//!
//! Every executor sends a run's output to the same two files in its run directory, so a failed
//! run can be read afterwards wherever it ran.

use std::fs;
use std::path::Path;

use super::grid::RunSpec;
use super::run_files::{SUMMARY_FILE, is_finished};

/// The run's standard output, in its run directory.
pub const STDOUT_LOG: &str = "stdout.log";
/// The run's standard error, in its run directory.
pub const STDERR_LOG: &str = "stderr.log";

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum RunStatus {
    /// Already finished before this invocation.
    Skipped,
    Succeeded,
    /// Why, with the last line of its stderr.
    Failed(String),
}

/// A run and how it ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub spec: RunSpec,
    pub status: RunStatus,
    pub seconds: f64,
}

/// How the run's process ended, as far as its executor knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    Code(i32),
    Signal(i32),
    /// The executor lost sight of the process (a Slurm task that left the queue before its
    /// exit status was seen): only the run directory can tell.
    Unknown,
}

impl Exit {
    /// A raw `wait(2)` status, as Slurm reports it (`exit_code` 256 is exit code 1, 9 is
    /// SIGKILL).
    pub fn from_wait_status(raw: i32) -> Exit {
        match raw & 0x7f {
            0 => Exit::Code((raw >> 8) & 0xff),
            signal => Exit::Signal(signal),
        }
    }
}

/// The verdict on a run whose process ended with `exit`; `context` (the scheduler's view, e.g.
/// "Slurm TIMEOUT") goes in front of a failure's explanation.
pub fn judge(spec: &RunSpec, exit: Exit, context: Option<&str>) -> RunStatus {
    let why = match exit {
        Exit::Code(0) | Exit::Unknown if is_finished(&spec.dir) => return RunStatus::Succeeded,
        Exit::Code(0) => format!(
            "exited 0 but wrote no {}",
            spec.dir.join(SUMMARY_FILE).display()
        ),
        Exit::Unknown => format!(
            "ended without writing {}: {}",
            spec.dir.join(SUMMARY_FILE).display(),
            last_line(&spec.dir.join(STDERR_LOG))
        ),
        Exit::Code(code) => format!(
            "exit code {code}: {}",
            last_line(&spec.dir.join(STDERR_LOG))
        ),
        Exit::Signal(signal) => format!(
            "killed by signal {signal}: {}",
            last_line(&spec.dir.join(STDERR_LOG))
        ),
    };
    RunStatus::Failed(match context {
        Some(context) => format!("{context}, {why}"),
        None => why,
    })
}

/// The last non-empty line of a log, which is where `dualrep` prints its `error: ...`.
pub fn last_line(path: &Path) -> String {
    fs::read_to_string(path)
        .ok()
        .and_then(|text| {
            text.lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .map(str::to_owned)
        })
        .unwrap_or_else(|| "(no stderr)".into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::Task;

    fn spec(dir: &Path) -> RunSpec {
        RunSpec {
            task: Task::Reaching,
            method: "sac".into(),
            seed: 0,
            dir: dir.to_path_buf(),
            args: vec![],
        }
    }

    #[test]
    fn report_wait_statuses_decode_as_slurm_reports_them() {
        assert_eq!(Exit::from_wait_status(0), Exit::Code(0));
        assert_eq!(Exit::from_wait_status(768), Exit::Code(3));
        assert_eq!(Exit::from_wait_status(9), Exit::Signal(9));
        assert_eq!(Exit::from_wait_status(15), Exit::Signal(15));
    }

    #[test]
    fn report_a_run_succeeds_only_with_exit_0_and_its_summary() {
        let tmp = tempfile::tempdir().unwrap();
        let run = spec(tmp.path());
        fs::write(tmp.path().join(STDERR_LOG), "step 10\nerror: boom\n\n").unwrap();
        assert_eq!(
            judge(&run, Exit::Code(2), Some("Slurm FAILED")),
            RunStatus::Failed("Slurm FAILED, exit code 2: error: boom".into())
        );
        assert_eq!(
            judge(&run, Exit::Signal(9), None),
            RunStatus::Failed("killed by signal 9: error: boom".into())
        );
        let RunStatus::Failed(why) = judge(&run, Exit::Unknown, None) else {
            panic!("no summary, no success");
        };
        assert!(why.starts_with("ended without writing"), "{why}");

        fs::write(tmp.path().join(SUMMARY_FILE), "{}").unwrap();
        assert_eq!(judge(&run, Exit::Code(0), None), RunStatus::Succeeded);
        assert_eq!(judge(&run, Exit::Unknown, None), RunStatus::Succeeded);
        // A summary does not excuse a failing exit.
        assert!(matches!(
            judge(&run, Exit::Code(1), None),
            RunStatus::Failed(_)
        ));
    }
}
