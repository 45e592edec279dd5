//! Talking to Slurm: `sbatch` to submit an array, `squeue` to see where its tasks are. The
//! parsing is pure and tested on squeue's own output; the two calls are thin.
//!
//! The queue is read with `squeue --me --array --states=all`, which lists each array task on
//! its own line, finished ones too for as long as the controller keeps them (`MinJobAge`, five
//! minutes by default). A task gone from the list has ended; its run directory tells how.

use std::collections::HashMap;
use std::fmt;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, bail};

/// One task of a job array, as Slurm names it: `1234_5`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct TaskId {
    pub job: String,
    pub index: u32,
}

impl fmt::Display for TaskId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}_{}", self.job, self.index)
    }
}

/// Where a task is in its life, from Slurm's job state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Waiting to start, or sent back to wait (held, requeued after preemption or a node
    /// failure).
    Queued,
    /// Holding its node: running, suspended, or finishing up.
    Running,
    /// Done, one way or another (COMPLETED, FAILED, CANCELLED, TIMEOUT, NODE_FAIL, ...).
    Ended,
}

impl Phase {
    /// The phase of a Slurm job state (squeue's long names). The two lists are Slurm's states
    /// in which a job is still in the system; every other state is an end, so that a state
    /// this code does not know can never keep the grid waiting forever.
    pub fn of(state: &str) -> Phase {
        match state {
            "PENDING" | "REQUEUED" | "REQUEUE_FED" | "REQUEUE_HOLD" | "RESV_DEL_HOLD"
            | "SPECIAL_EXIT" => Phase::Queued,
            "RUNNING" | "CONFIGURING" | "COMPLETING" | "SUSPENDED" | "STOPPED" | "SIGNALING"
            | "STAGE_OUT" | "RESIZING" => Phase::Running,
            _ => Phase::Ended,
        }
    }
}

/// A task's line in squeue.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TaskState {
    /// Slurm's state name, e.g. `RUNNING`, `TIMEOUT`.
    pub state: String,
    /// The raw wait status once the task ended (`256` is exit code 1, `9` SIGKILL).
    pub exit: Option<i32>,
    /// Time the task has held its node (Slurm's `TimeUsed`, whole seconds).
    pub used_seconds: Option<u64>,
    /// Slurm's reason, e.g. `Resources`, `NonZeroExitCode`.
    pub reason: String,
}

impl TaskState {
    pub fn phase(&self) -> Phase {
        Phase::of(&self.state)
    }
}

/// The fields squeue prints, `|`-separated (`:|` is width 0, then the suffix `|`); the reason,
/// which may hold spaces, last.
const SQUEUE_FORMAT: &str = "ArrayJobID:|,ArrayTaskID:|,State:|,exit_code:|,TimeUsed:|,Reason:";

/// Every array task in `squeue -h -O SQUEUE_FORMAT` output; other jobs (no task index) and
/// lines this code cannot read are left out.
pub fn parse_squeue(text: &str) -> HashMap<TaskId, TaskState> {
    text.lines()
        .filter_map(|line| {
            let mut fields = line.splitn(6, '|').map(str::trim);
            let job = fields.next()?;
            let index = fields.next()?.parse().ok()?;
            let state = fields.next()?;
            let exit = fields.next()?.parse().ok();
            let used_seconds = parse_time_used(fields.next()?);
            let reason = fields.next().unwrap_or_default();
            if job.is_empty() || state.is_empty() {
                return None;
            }
            let id = TaskId {
                job: job.to_string(),
                index,
            };
            let task = TaskState {
                state: state.to_string(),
                exit,
                used_seconds,
                reason: reason.to_string(),
            };
            Some((id, task))
        })
        .collect()
}

/// Slurm's elapsed time, `[[D-]H:]M:SS`, in seconds.
pub fn parse_time_used(text: &str) -> Option<u64> {
    let (days, clock) = match text.split_once('-') {
        Some((d, rest)) => (d.parse::<u64>().ok()?, rest),
        None => (0, text),
    };
    let mut seconds = 0;
    for part in clock.split(':') {
        seconds = seconds * 60 + part.parse::<u64>().ok()?;
    }
    Some(days * 86_400 + seconds)
}

/// This user's array tasks in the queue, finished ones included while Slurm keeps them.
pub fn squeue() -> anyhow::Result<HashMap<TaskId, TaskState>> {
    let out = Command::new("squeue")
        .args(["--me", "--noheader", "--array", "--states=all"])
        .arg(format!("--Format={SQUEUE_FORMAT}"))
        .output()
        .map_err(|err| missing_command("squeue", err))?;
    if !out.status.success() {
        bail!(
            "squeue failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    Ok(parse_squeue(&String::from_utf8_lossy(&out.stdout)))
}

/// Submits with `sbatch ARGS` (which must include `--parsable`) and returns the job id.
pub fn sbatch(args: &[String]) -> anyhow::Result<String> {
    let out = Command::new("sbatch")
        .args(args)
        .output()
        .map_err(|err| missing_command("sbatch", err))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        bail!(
            "sbatch refused the job array ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    parse_job_id(&stdout).with_context(|| format!("sbatch printed no job id: {stdout:?}"))
}

/// The job id `sbatch --parsable` prints: `1234`, or `1234;cluster` on a multi-cluster setup.
pub fn parse_job_id(stdout: &str) -> Option<String> {
    let id = stdout.trim().split(';').next()?.trim();
    (!id.is_empty() && id.bytes().all(|b| b.is_ascii_digit())).then(|| id.to_string())
}

/// Whether `program` is on PATH (the Slurm client commands, before anything is written).
pub fn on_path(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|paths| {
        std::env::split_paths(&paths).any(|dir| is_executable(&dir.join(program)))
    })
}

fn is_executable(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    path.metadata()
        .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

fn missing_command(name: &str, err: std::io::Error) -> anyhow::Error {
    anyhow::anyhow!(
        "could not run {name}: {err}. `--executor slurm` needs Slurm's client commands \
         (sbatch, squeue) on PATH, on a machine that can submit to the cluster"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// squeue 22.05's output for a held array, a running task, and ended ones.
    const SQUEUE: &str = "\
5|2|CANCELLED|15|0:03|None
8|0|PENDING|0|0:00|JobHeldUser
8|1|RUNNING|0|1-02:03:04|None
5|0|FAILED|768|12:01|NonZeroExitCode
5|1|COMPLETED|0|0:00|None
12|N/A|RUNNING|0|0:09|None
9|3|PENDING|0|0:00|launch failed requeued held
";

    #[test]
    fn report_slurm_squeue_lines_become_task_states() {
        let tasks = parse_squeue(SQUEUE);
        assert_eq!(tasks.len(), 6, "the job that is no array is left out");
        let get = |job: &str, index| {
            tasks[&TaskId {
                job: job.into(),
                index,
            }]
                .clone()
        };
        assert_eq!(get("8", 0).phase(), Phase::Queued);
        assert_eq!(get("8", 1).phase(), Phase::Running);
        let failed = get("5", 0);
        assert_eq!((failed.phase(), failed.exit), (Phase::Ended, Some(768)));
        assert_eq!(failed.reason, "NonZeroExitCode");
        assert_eq!(failed.used_seconds, Some(721));
        assert_eq!(get("8", 1).used_seconds, Some(93_784));
        assert_eq!(get("5", 2).phase(), Phase::Ended);
        assert_eq!(get("9", 3).reason, "launch failed requeued held");
        assert_eq!(
            TaskId {
                job: "8".into(),
                index: 1
            }
            .to_string(),
            "8_1"
        );
    }

    #[test]
    fn report_slurm_states_map_to_phases() {
        for (state, phase) in [
            ("PENDING", Phase::Queued),
            ("REQUEUED", Phase::Queued),
            ("RUNNING", Phase::Running),
            ("COMPLETING", Phase::Running),
            ("COMPLETED", Phase::Ended),
            ("TIMEOUT", Phase::Ended),
            ("NODE_FAIL", Phase::Ended),
            ("PREEMPTED", Phase::Ended),
            ("OUT_OF_MEMORY", Phase::Ended),
            ("SOMETHING_NEW", Phase::Ended),
        ] {
            assert_eq!(Phase::of(state), phase, "{state}");
        }
    }

    #[test]
    fn report_slurm_job_ids_from_sbatch_parsable() {
        assert_eq!(parse_job_id("1234\n").as_deref(), Some("1234"));
        assert_eq!(parse_job_id("1234;cluster2\n").as_deref(), Some("1234"));
        assert_eq!(parse_job_id("Submitted batch job 12"), None);
        assert_eq!(parse_job_id(""), None);
    }
}
