//! Runs a grid's runs through an [`Executor`]: the one place that decides what runs, whatever
//! runs it. It knows nothing of figures, only of run directories, and nothing of Slurm: an
//! executor takes runs and says when each has started and ended.
//!
//! - A run whose directory already holds `summary.json` is skipped, so a stopped grid resumes
//!   where it was; only the others go to the executor.
//! - A failed run is reported and the grid goes on; the caller decides the exit status.
//! - After each run ends (or is skipped), a caller's `follow_up` may add runs (how "EF at DREF's
//!   rate" waits for DREF's runs to finish).
//! - Without waiting ([`Waiting::NoWait`]), the runs are handed over and the call returns: an
//!   executor whose runs outlive this process (a Slurm queue) goes on with them, and the next
//!   invocation picks them up.
//!
//! The executors: [`super::local`] (child processes on this machine, J at a time) and
//! [`super::slurm`] (`sbatch` job arrays).

use std::collections::VecDeque;

use super::grid::RunSpec;
pub use super::run_end::{Outcome, RunStatus};
use super::run_files::is_finished;

/// What the runner tells its caller as it goes.
#[derive(Debug)]
pub enum Event<'a> {
    /// Runs were added to the grid by a follow-up.
    Added(usize),
    /// A run is waiting for its turn: handed to the executor, or sent back to the queue (a
    /// preempted Slurm task). `job` names it in the executor's terms ("1234_5" for Slurm).
    Queued {
        spec: &'a RunSpec,
        job: Option<&'a str>,
    },
    Started(&'a RunSpec),
    /// A run ended (or was skipped).
    Finished(&'a Outcome),
    /// A line for the person watching (a submission, a warning).
    Note(&'a str),
}

/// Where runs run. An executor is handed runs that have not finished, reports through
/// `on_event` when each is queued and started, and returns each one's outcome once it ends.
pub trait Executor {
    /// Starts or queues `runs`.
    fn submit(
        &mut self,
        runs: Vec<RunSpec>,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> anyhow::Result<()>;

    /// How many submitted runs have not ended yet.
    fn in_flight(&self) -> usize;

    /// Blocks until at least one run has ended and returns the ones that did. Only called
    /// while [`Executor::in_flight`] is not zero.
    fn wait(&mut self, on_event: &mut dyn FnMut(Event<'_>)) -> anyhow::Result<Vec<Outcome>>;
}

/// Whether [`run_grid`] waits for the runs it handed over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Waiting {
    UntilDone,
    /// Return once every run that can start is with the executor.
    NoWait,
}

/// What a call of [`run_grid`] saw.
#[derive(Debug)]
pub struct GridRun {
    /// Every run that ended (or was skipped), in the order they did.
    pub outcomes: Vec<Outcome>,
    /// Runs still with the executor when the call returned (only without waiting).
    pub in_flight: usize,
}

/// Runs `runs` (and whatever `follow_up` adds) on `executor` and returns what ended. An error
/// is the executor's own (a submission refused), not a run's failure.
pub fn run_grid(
    executor: &mut dyn Executor,
    runs: Vec<RunSpec>,
    waiting: Waiting,
    mut follow_up: impl FnMut(&Outcome) -> Vec<RunSpec>,
    mut on_event: impl FnMut(Event<'_>),
) -> anyhow::Result<GridRun> {
    let mut todo: VecDeque<RunSpec> = runs.into();
    let mut outcomes = Vec::new();
    let mut conclude =
        |outcome: Outcome, todo: &mut VecDeque<RunSpec>, on_event: &mut dyn FnMut(Event<'_>)| {
            on_event(Event::Finished(&outcome));
            let more = follow_up(&outcome);
            if !more.is_empty() {
                on_event(Event::Added(more.len()));
                todo.extend(more);
            }
            outcomes.push(outcome);
        };
    loop {
        // Skipping a finished run may add runs (its follow-up), so drain until none are left.
        let mut fresh = Vec::new();
        while let Some(spec) = todo.pop_front() {
            if is_finished(&spec.dir) {
                let skipped = Outcome {
                    spec,
                    status: RunStatus::Skipped,
                    seconds: 0.0,
                };
                conclude(skipped, &mut todo, &mut on_event);
            } else {
                fresh.push(spec);
            }
        }
        if !fresh.is_empty() {
            executor.submit(fresh, &mut on_event)?;
        }
        if waiting == Waiting::NoWait || executor.in_flight() == 0 {
            break;
        }
        for outcome in executor.wait(&mut on_event)? {
            conclude(outcome, &mut todo, &mut on_event);
        }
    }
    Ok(GridRun {
        outcomes,
        in_flight: executor.in_flight(),
    })
}

#[cfg(test)]
#[path = "runner_tests.rs"]
mod tests;
