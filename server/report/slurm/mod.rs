//! The Slurm executor: a grid's runs as `sbatch` job arrays, one task per run, each task the
//! same `dualrep train|prefs` command line as the local executor runs, writing into the shared
//! grid folder.
//!
//! - [`script`] (pure): the batch script and the `sbatch` command line.
//! - [`queue`]: `sbatch` and `squeue`, and reading squeue's lines.
//! - [`ledger`]: which task ran which run, so that running the same command again waits for
//!   runs still in the queue and submits only what is missing or failed.
//!
//! Its files live in `<grid>/.slurm/`: `array-<n>.sh`, `submissions.jsonl`, and
//! `logs/<job>_<task>.log` (Slurm's own messages about each task, linked from the run directory
//! as `slurm.log`). Waiting means reading squeue every `poll`; the runs belong to Slurm, so
//! stopping the wait (Ctrl-C, `--no-wait`) stops nothing.

pub mod ledger;
pub mod queue;
pub mod script;

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::thread;
use std::time::{Duration, Instant};

use anyhow::Context;

use self::ledger::{Ledger, Submission};
use self::queue::{Phase, TaskId, TaskState};
use self::script::{ArraySettings, MAX_ARRAY_TASKS, batch_script, sbatch_args};
use super::grid::RunSpec;
use super::run_end::{Exit, Outcome, RunStatus, judge};
use super::runner::{Event, Executor};

/// How long a task that ended well may take to show its `summary.json` on this machine: a
/// shared file system can lag behind the node that wrote it.
const SUMMARY_GRACE: Duration = Duration::from_secs(30);

/// How long squeue may keep failing (a controller restarting) before the wait gives up.
const SQUEUE_PATIENCE: Duration = Duration::from_secs(300);

/// A run in Slurm's hands.
struct Tracked {
    spec: RunSpec,
    task: TaskId,
    phase: Phase,
    /// When this process first saw it running.
    started: Option<Instant>,
    /// When it was first seen ended without its summary, while that may still be lag.
    unsure_since: Option<Instant>,
}

pub struct SlurmExecutor {
    settings: ArraySettings,
    poll: Duration,
    /// The grid's folder as the run directories name it, and absolute.
    root: PathBuf,
    state_dir: PathBuf,
    cwd: PathBuf,
    ledger: Ledger,
    tracked: Vec<Tracked>,
    squeue_failing_since: Option<Instant>,
}

impl SlurmExecutor {
    /// An executor for the grid in `root`; reads what earlier invocations submitted.
    pub fn new(settings: ArraySettings, root: &Path, poll: Duration) -> anyhow::Result<Self> {
        for command in ["sbatch", "squeue"] {
            anyhow::ensure!(
                queue::on_path(command),
                "{command} is not on PATH: `--executor slurm` needs Slurm's client commands \
                 (sbatch, squeue) on a machine that can submit to the cluster"
            );
        }
        let cwd = std::env::current_dir().context("reading the working directory")?;
        let state_dir = cwd.join(root).join(".slurm");
        fs::create_dir_all(state_dir.join("logs"))
            .with_context(|| format!("creating {}", state_dir.display()))?;
        Ok(Self {
            settings,
            poll,
            root: root.to_path_buf(),
            ledger: Ledger::open(&state_dir)?,
            state_dir,
            cwd,
            tracked: Vec::new(),
            squeue_failing_since: None,
        })
    }

    /// A run's name in the ledger: its directory relative to the grid.
    fn key(&self, spec: &RunSpec) -> String {
        spec.dir
            .strip_prefix(&self.root)
            .unwrap_or(&spec.dir)
            .to_string_lossy()
            .into_owned()
    }

    /// Submits `runs` (at most [`MAX_ARRAY_TASKS`]) as one array.
    fn submit_array(
        &mut self,
        runs: Vec<RunSpec>,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> anyhow::Result<()> {
        let script_name = format!("array-{}.sh", self.ledger.len() + 1);
        let script = self.state_dir.join(&script_name);
        let logs_abs = self.state_dir.join("logs");
        let logs = self.root.join(".slurm/logs");
        let text = batch_script(&self.settings, &runs, &self.root, &logs, &logs_abs);
        fs::write(&script, text).with_context(|| format!("writing {}", script.display()))?;
        let args = sbatch_args(&self.settings, runs.len(), &script, &logs_abs, &self.cwd);
        let job = queue::sbatch(&args)?;
        self.ledger.append(Submission {
            job: job.clone(),
            script: script_name,
            runs: runs.iter().map(|r| self.key(r)).collect(),
        })?;
        on_event(Event::Note(&format!(
            "submitted {} run(s) as Slurm job array {job} ({})",
            runs.len(),
            script.display()
        )));
        for (index, spec) in runs.into_iter().enumerate() {
            let task = TaskId {
                job: job.clone(),
                index: index as u32,
            };
            on_event(Event::Queued {
                spec: &spec,
                job: Some(&task.to_string()),
            });
            self.tracked.push(Tracked {
                spec,
                task,
                phase: Phase::Queued,
                started: None,
                unsure_since: None,
            });
        }
        Ok(())
    }

    /// Follows the queue: reports starts and requeues, and returns the runs that ended.
    fn update(
        &mut self,
        queue: &HashMap<TaskId, TaskState>,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> Vec<Outcome> {
        let now = Instant::now();
        let mut ended = Vec::new();
        let mut still = Vec::new();
        for mut t in std::mem::take(&mut self.tracked) {
            let state = queue.get(&t.task);
            match state.map(TaskState::phase) {
                Some(Phase::Queued) => {
                    if t.phase != Phase::Queued {
                        // Preempted or its node failed: back in the queue, to run again.
                        let job = t.task.to_string();
                        on_event(Event::Queued {
                            spec: &t.spec,
                            job: Some(&job),
                        });
                    }
                    t.phase = Phase::Queued;
                    still.push(t);
                }
                Some(Phase::Running) => {
                    if t.phase != Phase::Running {
                        on_event(Event::Started(&t.spec));
                        t.started = Some(now);
                    }
                    t.phase = Phase::Running;
                    still.push(t);
                }
                Some(Phase::Ended) | None => {
                    let status = verdict(&t, state);
                    // An end that looked fine but shows no summary yet may be the file system
                    // lagging: look again on the next polls before calling it a failure.
                    let unsure = matches!(status, RunStatus::Failed(_))
                        && match state {
                            Some(s) => s.state == "COMPLETED" && s.exit == Some(0),
                            None => t.phase == Phase::Running,
                        };
                    if unsure {
                        let since = *t.unsure_since.get_or_insert(now);
                        if now.duration_since(since) < SUMMARY_GRACE {
                            still.push(t);
                            continue;
                        }
                    }
                    // Slurm's count of the task's time, or ours where it says less (whole
                    // seconds, or a task that ended between two looks at the queue).
                    let seen = t.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
                    let used = state.and_then(|s| s.used_seconds).unwrap_or(0) as f64;
                    ended.push(Outcome {
                        seconds: seen.max(used),
                        spec: t.spec,
                        status,
                    });
                }
            }
        }
        self.tracked = still;
        ended
    }

    /// squeue, tolerating a controller that is briefly away.
    fn read_queue(
        &mut self,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> anyhow::Result<Option<HashMap<TaskId, TaskState>>> {
        match queue::squeue() {
            Ok(queue) => {
                self.squeue_failing_since = None;
                Ok(Some(queue))
            }
            Err(err) => {
                let since = *self.squeue_failing_since.get_or_insert_with(|| {
                    on_event(Event::Note(&format!("{err:#}; trying again")));
                    Instant::now()
                });
                if since.elapsed() > SQUEUE_PATIENCE {
                    return Err(err.context(format!(
                        "squeue has failed for {} s; the runs go on in Slurm, and the same \
                         command picks them up again",
                        SQUEUE_PATIENCE.as_secs()
                    )));
                }
                Ok(None)
            }
        }
    }
}

/// How a run whose task is no longer queued or running ended.
fn verdict(t: &Tracked, state: Option<&TaskState>) -> RunStatus {
    match state {
        Some(s) => {
            let exit = s.exit.map_or(Exit::Unknown, Exit::from_wait_status);
            judge(
                &t.spec,
                exit,
                Some(&format!("Slurm {} {}", s.state, t.task)),
            )
        }
        None => judge(
            &t.spec,
            Exit::Unknown,
            Some(&format!("Slurm task {} left the queue", t.task)),
        ),
    }
}

impl Executor for SlurmExecutor {
    fn submit(
        &mut self,
        runs: Vec<RunSpec>,
        on_event: &mut dyn FnMut(Event<'_>),
    ) -> anyhow::Result<()> {
        // A run whose latest task is still queued or running is waited for, not resubmitted.
        let queue = if runs
            .iter()
            .any(|r| self.ledger.latest(&self.key(r)).is_some())
        {
            queue::squeue()
                .context("reading the Slurm queue, to tell runs still in it from those to submit")?
        } else {
            Default::default()
        };
        let mut fresh = Vec::new();
        let mut adopted = Vec::new();
        for spec in runs {
            let alive = self.ledger.latest(&self.key(&spec)).and_then(|task| {
                let phase = queue.get(task)?.phase();
                (phase != Phase::Ended).then(|| (task.clone(), phase))
            });
            match alive {
                Some((task, phase)) => adopted.push((spec, task, phase)),
                None => fresh.push(spec),
            }
        }
        if !adopted.is_empty() {
            on_event(Event::Note(&format!(
                "{} run(s) already in the Slurm queue from an earlier submission: waiting for \
                 them, not submitting them again",
                adopted.len()
            )));
        }
        for (spec, task, phase) in adopted {
            on_event(Event::Queued {
                spec: &spec,
                job: Some(&task.to_string()),
            });
            let started = (phase == Phase::Running).then(|| {
                on_event(Event::Started(&spec));
                Instant::now()
            });
            self.tracked.push(Tracked {
                spec,
                task,
                phase,
                started,
                unsure_since: None,
            });
        }
        while !fresh.is_empty() {
            let rest = fresh.split_off(fresh.len().min(MAX_ARRAY_TASKS));
            self.submit_array(std::mem::replace(&mut fresh, rest), on_event)?;
        }
        Ok(())
    }

    fn in_flight(&self) -> usize {
        self.tracked.len()
    }

    fn wait(&mut self, on_event: &mut dyn FnMut(Event<'_>)) -> anyhow::Result<Vec<Outcome>> {
        loop {
            thread::sleep(self.poll);
            let Some(queue) = self.read_queue(on_event)? else {
                continue;
            };
            let ended = self.update(&queue, on_event);
            if !ended.is_empty() {
                return Ok(ended);
            }
        }
    }
}
