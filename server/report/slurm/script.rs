//! The batch script of one Slurm job array and the `sbatch` command line that submits it, pure.
//!
//! Array task `i` runs `runs[i]`: the very command line the local executor runs (the grid's
//! [`RunSpec::args`]), with its stdout and stderr in the run directory's `stdout.log` and
//! `stderr.log`. Slurm's own messages about a task (a time limit, a node failure) go to the
//! array's log under the grid's `.slurm/logs/`; the task links it beside the run as `slurm.log`.

use std::path::{Component, Path, PathBuf};

use crate::report::grid::RunSpec;
use crate::report::run_end::{STDERR_LOG, STDOUT_LOG};

/// The link in a run directory to Slurm's log of the task that ran it.
pub const SLURM_LOG_LINK: &str = "slurm.log";

/// Most array tasks in one submission: Slurm's default `MaxArraySize` is 1001 (indices 0-1000).
pub const MAX_ARRAY_TASKS: usize = 1000;

/// What one `sbatch` needs beyond the runs.
#[derive(Clone, Debug, PartialEq)]
pub struct ArraySettings {
    pub job_name: String,
    /// The `dualrep` binary as the compute nodes see it.
    pub program: PathBuf,
    pub partition: Option<String>,
    /// Slurm's `--time` (e.g. `1:30:00`).
    pub time: Option<String>,
    pub cpus_per_task: u32,
    /// Most tasks of the array running at once (`--array=0-N%max`).
    pub max_running: Option<usize>,
    /// Passed to `sbatch` as they are, after ours (so they win).
    pub extra: Vec<String>,
    /// Variables every task exports before it runs (the threads and kernels each run gets).
    pub env: Vec<(String, String)>,
}

/// Single-quotes `word` for bash, so that spaces, quotes and newlines stay inside it.
pub fn shell_quote(word: &str) -> String {
    format!("'{}'", word.replace('\'', r"'\''"))
}

/// The batch script that runs `runs[$SLURM_ARRAY_TASK_ID]`. `root` is the grid's directory and
/// `log_dir` the folder of Slurm's task logs, both named as the run directories name them
/// (relative to the working directory, or absolute); `log_dir_abs` is that folder's absolute
/// path, for a run directory outside `root`.
pub fn batch_script(
    settings: &ArraySettings,
    runs: &[RunSpec],
    root: &Path,
    log_dir: &Path,
    log_dir_abs: &Path,
) -> String {
    let mut s = String::from(
        "#!/bin/bash\n\
         # A Slurm job array written by `dualrep`: task i runs the i-th run of the grid, the same\n\
         # `dualrep train|prefs` command line as the local executor, into its run directory.\n\
         set -u\n",
    );
    s += &format!(
        "program={}\n",
        shell_quote(&settings.program.to_string_lossy())
    );
    for (name, value) in &settings.env {
        s += &format!("export {name}={}\n", shell_quote(value));
    }
    s += "case \"${SLURM_ARRAY_TASK_ID:-}\" in\n";
    for (index, run) in runs.iter().enumerate() {
        let words: Vec<String> = run.args.iter().map(|a| shell_quote(a)).collect();
        s += &format!(
            "    {index}) dir={} logs={}\n       set -- {} ;;\n",
            shell_quote(&run.dir.to_string_lossy()),
            shell_quote(
                &relative_from(&run.dir, root, log_dir)
                    .unwrap_or_else(|| log_dir_abs.to_path_buf())
                    .to_string_lossy()
            ),
            words.join(" ")
        );
    }
    s += &format!(
        "    *) echo \"dualrep: array task ${{SLURM_ARRAY_TASK_ID:-(none)}} has no run\" >&2; exit 2 ;;\n\
         esac\n\
         mkdir -p \"$dir\" || exit 1\n\
         ln -sfn \"$logs/${{SLURM_ARRAY_JOB_ID}}_${{SLURM_ARRAY_TASK_ID}}.log\" \"$dir/{SLURM_LOG_LINK}\"\n\
         exec \"$program\" \"$@\" </dev/null >\"$dir/{STDOUT_LOG}\" 2>\"$dir/{STDERR_LOG}\"\n"
    );
    s
}

/// `sbatch`'s arguments for an array of `tasks` tasks from `script`, with each task's Slurm log
/// in `log_dir` and `chdir` as the working directory (where relative run directories resolve).
pub fn sbatch_args(
    settings: &ArraySettings,
    tasks: usize,
    script: &Path,
    log_dir: &Path,
    chdir: &Path,
) -> Vec<String> {
    let mut array = format!("--array=0-{}", tasks.saturating_sub(1));
    if let Some(max) = settings.max_running {
        array += &format!("%{max}");
    }
    let mut args = vec![
        "--parsable".to_string(),
        format!("--job-name={}", settings.job_name),
        array,
        format!("--output={}", log_dir.join("%A_%a.log").display()),
        // A requeued task's second attempt adds to its log instead of erasing the first.
        "--open-mode=append".into(),
        format!("--chdir={}", chdir.display()),
        format!("--cpus-per-task={}", settings.cpus_per_task),
    ];
    if let Some(partition) = &settings.partition {
        args.push(format!("--partition={partition}"));
    }
    if let Some(time) = &settings.time {
        args.push(format!("--time={time}"));
    }
    args.extend(settings.extra.iter().cloned());
    args.push(script.to_string_lossy().into_owned());
    args
}

/// `target` as seen from `dir`, both under `root`: `../../../.slurm/logs` for a run three
/// levels down, so the link survives moving the grid's folder. `None` when either is not under
/// `root`.
fn relative_from(dir: &Path, root: &Path, target: &Path) -> Option<PathBuf> {
    let (Ok(below), Ok(inside)) = (dir.strip_prefix(root), target.strip_prefix(root)) else {
        return None;
    };
    let depth = below
        .components()
        .filter(|c| matches!(c, Component::Normal(_)))
        .count();
    let mut up: PathBuf = std::iter::repeat_n("..", depth).collect();
    up.push(inside);
    Some(up)
}

#[cfg(test)]
#[path = "script_tests.rs"]
mod tests;
