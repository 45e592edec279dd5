//! Runs a grid's runs as child processes, `jobs` at a time. The one part of `report` that
//! spawns processes; it knows nothing of figures, only of run directories.
//!
//! - A run whose directory already holds `summary.json` is skipped, so a stopped grid resumes
//!   where it was.
//! - Each child's stdout and stderr go to `stdout.log` and `stderr.log` in its run directory,
//!   so a failure can be read afterwards and parallel children do not interleave on a terminal.
//! - A failed child (non-zero exit, or exit 0 without a summary) is reported and the grid goes
//!   on; the caller decides the exit status from the outcomes.
//! - After each run, a caller's `follow_up` may add runs (how "EF at DREF's rate" waits for
//!   DREF's runs to finish).
//!
//! Children run on plain threads, one per child in flight, each blocked in `wait`; the calling
//! thread owns all bookkeeping and callbacks, so neither needs to be `Send`.

use std::collections::VecDeque;
use std::fs::{self, File};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::thread;
use std::time::Instant;

use super::grid::RunSpec;
use super::run_files::is_finished;

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

/// What the runner tells its caller as it goes.
#[derive(Debug)]
pub enum Event<'a> {
    /// Runs were added to the grid by a follow-up.
    Added(usize),
    Started(&'a RunSpec),
    /// A run ended (or was skipped).
    Finished(&'a Outcome),
}

/// Runs `runs` (and whatever `follow_up` adds) with `program` as the child, at most `jobs` at a
/// time, and returns every outcome in the order they ended.
pub fn run_grid(
    program: &Path,
    runs: Vec<RunSpec>,
    jobs: usize,
    follow_up: impl FnMut(&Outcome) -> Vec<RunSpec>,
    on_event: impl FnMut(Event<'_>),
) -> Vec<Outcome> {
    run_grid_with_env(program, &[], runs, jobs, follow_up, on_event)
}

/// [`run_grid`] with `env` set in every child's environment.
pub fn run_grid_with_env(
    program: &Path,
    env: &[(String, String)],
    runs: Vec<RunSpec>,
    jobs: usize,
    mut follow_up: impl FnMut(&Outcome) -> Vec<RunSpec>,
    mut on_event: impl FnMut(Event<'_>),
) -> Vec<Outcome> {
    let jobs = jobs.max(1);
    let mut queue: VecDeque<RunSpec> = runs.into();
    let mut outcomes = Vec::new();
    let mut in_flight: Vec<Option<RunSpec>> = Vec::new();
    let mut running = 0;
    let (tx, rx) = mpsc::channel::<(usize, RunStatus, f64)>();

    // Bookkeeping shared by skipped and finished runs.
    let mut conclude =
        |outcome: Outcome, queue: &mut VecDeque<RunSpec>, on_event: &mut dyn FnMut(Event<'_>)| {
            on_event(Event::Finished(&outcome));
            let more = follow_up(&outcome);
            if !more.is_empty() {
                on_event(Event::Added(more.len()));
                queue.extend(more);
            }
            outcomes.push(outcome);
        };

    loop {
        while running < jobs {
            let Some(spec) = queue.pop_front() else { break };
            if is_finished(&spec.dir) {
                let skipped = Outcome {
                    spec,
                    status: RunStatus::Skipped,
                    seconds: 0.0,
                };
                conclude(skipped, &mut queue, &mut on_event);
                continue;
            }
            on_event(Event::Started(&spec));
            let slot = in_flight.len();
            let (tx, program, child_spec) = (tx.clone(), program.to_path_buf(), spec.clone());
            let env = env.to_vec();
            in_flight.push(Some(spec));
            running += 1;
            thread::spawn(move || {
                let start = Instant::now();
                let status = run_child(&program, &env, &child_spec);
                // The receiver lives until every child has reported; a send cannot fail.
                let _ = tx.send((slot, status, start.elapsed().as_secs_f64()));
            });
        }
        if running == 0 {
            break;
        }
        let (slot, status, seconds) = rx
            .recv()
            .expect("a child thread holds a sender while it runs");
        running -= 1;
        let spec = in_flight[slot].take().expect("each slot reports once");
        let outcome = Outcome {
            spec,
            status,
            seconds,
        };
        conclude(outcome, &mut queue, &mut on_event);
    }
    outcomes
}

/// Runs one child to completion and says how it went.
fn run_child(program: &Path, env: &[(String, String)], spec: &RunSpec) -> RunStatus {
    let stderr_path = spec.dir.join("stderr.log");
    let started = fs::create_dir_all(&spec.dir).and_then(|()| {
        let stdout = File::create(spec.dir.join("stdout.log"))?;
        let stderr = File::create(&stderr_path)?;
        Command::new(program)
            .args(&spec.args)
            .envs(env.iter().map(|(k, v)| (k, v)))
            .stdin(Stdio::null())
            .stdout(stdout)
            .stderr(stderr)
            .status()
    });
    match started {
        Err(err) => {
            let why = format!("could not run {}: {err}", program.display());
            // Best effort: the message also goes to the caller.
            let _ = fs::write(&stderr_path, format!("{why}\n"));
            RunStatus::Failed(why)
        }
        Ok(status) if !status.success() => {
            let code = status
                .code()
                .map_or("killed by a signal".into(), |c| format!("exit code {c}"));
            RunStatus::Failed(format!("{code}: {}", last_line(&stderr_path)))
        }
        Ok(_) if !is_finished(&spec.dir) => RunStatus::Failed(format!(
            "exited 0 but wrote no {}",
            spec.dir.join(super::run_files::SUMMARY_FILE).display()
        )),
        Ok(_) => RunStatus::Succeeded,
    }
}

/// The last non-empty line of a log, which is where `dualrep` prints its `error: ...`.
fn last_line(path: &Path) -> String {
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
#[path = "runner_tests.rs"]
mod tests;
