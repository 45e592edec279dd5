//! The local executor: each run as a child process on this machine, `jobs` at a time.
//!
//! Children run on plain threads, one per child in flight, each blocked in `wait`; the calling
//! thread owns all bookkeeping and callbacks, so neither needs to be `Send`. Each child's stdout
//! and stderr go to `stdout.log` and `stderr.log` in its run directory, so a failure can be read
//! afterwards and parallel children do not interleave on a terminal.

use std::collections::VecDeque;
use std::fs::{self, File};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::thread;
use std::time::Instant;

use super::grid::RunSpec;
use super::run_end::{Exit, Outcome, RunStatus, STDERR_LOG, STDOUT_LOG, judge};
use super::runner::{Event, Executor};

/// A process pool of `jobs` children running `program`.
pub struct LocalPool {
    program: PathBuf,
    /// Variables set in every child's environment (the threads and kernels each run gets).
    env: Vec<(String, String)>,
    jobs: usize,
    queue: VecDeque<RunSpec>,
    /// Runs in flight by slot; a slot is reused once its child has reported.
    slots: Vec<Option<RunSpec>>,
    running: usize,
    tx: mpsc::Sender<(usize, RunStatus, f64)>,
    rx: mpsc::Receiver<(usize, RunStatus, f64)>,
}

impl LocalPool {
    pub fn new(program: &Path, jobs: usize) -> Self {
        let (tx, rx) = mpsc::channel();
        Self {
            program: program.to_path_buf(),
            env: Vec::new(),
            jobs: jobs.max(1),
            queue: VecDeque::new(),
            slots: Vec::new(),
            running: 0,
            tx,
            rx,
        }
    }

    /// Sets `env` in every child's environment.
    pub fn with_env(mut self, env: &[(String, String)]) -> Self {
        self.env = env.to_vec();
        self
    }

    /// Starts queued runs until `jobs` are running.
    fn fill(&mut self, on_event: &mut dyn FnMut(Event<'_>)) {
        while self.running < self.jobs {
            let Some(spec) = self.queue.pop_front() else {
                break;
            };
            on_event(Event::Started(&spec));
            let slot = match self.slots.iter().position(Option::is_none) {
                Some(free) => free,
                None => {
                    self.slots.push(None);
                    self.slots.len() - 1
                }
            };
            let (tx, program, child_spec) = (self.tx.clone(), self.program.clone(), spec.clone());
            let env = self.env.clone();
            self.slots[slot] = Some(spec);
            self.running += 1;
            thread::spawn(move || {
                let start = Instant::now();
                let status = run_child(&program, &env, &child_spec);
                // The pool holds the receiver while children run; a send cannot fail.
                let _ = tx.send((slot, status, start.elapsed().as_secs_f64()));
            });
        }
    }
}

impl Executor for LocalPool {
    fn submit(
        &mut self,
        runs: Vec<RunSpec>,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> anyhow::Result<()> {
        for spec in runs {
            on_event(Event::Queued {
                spec: &spec,
                job: None,
            });
            self.queue.push_back(spec);
        }
        self.fill(on_event);
        Ok(())
    }

    fn in_flight(&self) -> usize {
        self.queue.len() + self.running
    }

    fn wait(&mut self, on_event: &mut dyn FnMut(Event<'_>)) -> anyhow::Result<Vec<Outcome>> {
        // Refill first, not after a run ends: the caller hears of the end (and may add
        // follow-up runs) before the next run starts, in the order they happened.
        self.fill(on_event);
        let (slot, status, seconds) = self
            .rx
            .recv()
            .expect("the pool holds a sender, and a child thread one while it runs");
        self.running -= 1;
        let spec = self.slots[slot].take().expect("each slot reports once");
        Ok(vec![Outcome {
            spec,
            status,
            seconds,
        }])
    }
}

/// Runs one child to completion and says how it went.
fn run_child(program: &Path, env: &[(String, String)], spec: &RunSpec) -> RunStatus {
    let stderr_path = spec.dir.join(STDERR_LOG);
    let started = fs::create_dir_all(&spec.dir).and_then(|()| {
        let stdout = File::create(spec.dir.join(STDOUT_LOG))?;
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
        Ok(status) => {
            let exit = match (status.code(), status.signal()) {
                (Some(code), _) => Exit::Code(code),
                (None, Some(signal)) => Exit::Signal(signal),
                (None, None) => Exit::Unknown,
            };
            judge(spec, exit, None)
        }
    }
}

#[cfg(test)]
#[path = "local_tests.rs"]
pub(crate) mod tests;
