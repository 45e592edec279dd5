//! Why a session could not run on, or could not start: [`SessionError`], what a failed
//! session's `Ending::Failed` reason reads, and [`ExpertError`], why the synthetic trainer has no
//! expert. Their text is what the store keeps and the API shows, so it does not change with
//! the type. A cause is part of the text and not also a `source()`, so that a printer of
//! chains (the CLI's `{:#}`) does not repeat it.

use std::path::PathBuf;

use crate::guidance::evaluative_run::{RunCheckpointError, TakeInError};
use crate::rl::CheckpointError;
use crate::rl::kernels::KernelPath;
use crate::sim::{EnvFault, Task};

/// Why the synthetic trainer's expert could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ExpertError {
    /// No expert file at `path` (the task is named as `dualrep expert` takes it).
    #[error(
        "the synthetic trainer needs an expert at {} ({error}); train one with {}",
        .path.display(),
        train_with(.task)
    )]
    Missing {
        path: PathBuf,
        task: String,
        error: std::io::Error,
    },
    /// The file is there but is not an expert.
    #[error("loading the expert {}: {error}", .path.display())]
    Unreadable {
        path: PathBuf,
        error: CheckpointError,
    },
    /// The binary carries no expert for the task.
    #[error("this binary ships no expert for {0}")]
    NotShipped(Task),
    /// The expert the binary carries does not load.
    #[error("loading the shipped expert: {0}")]
    ShippedUnreadable(CheckpointError),
}

/// The command that trains an expert for `task` (ours, or a remote env's id).
fn train_with(task: &str) -> String {
    match task.parse::<Task>() {
        Ok(t) => format!("`dualrep expert --task {t}`"),
        Err(_) => format!("`dualrep expert --env-url URL` on {task}"),
    }
}

/// Why a session stopped running before its end: its `Ending::Failed` reason.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The kernels the session was launched with, and none of the same numerics, run here.
    #[error("the session computes with the {0} kernels, which this CPU cannot run")]
    KernelsUnavailable(KernelPath),
    /// A session on a remote env without its env connected, or a connected env without one.
    #[error("a session on a remote env needs its env connected (and only such one)")]
    RemoteNotConnected,
    #[error(transparent)]
    Expert(#[from] ExpertError),
    /// A synthetic session on a remote env's own task, and no folder of experts.
    #[error(
        "a synthetic session on {env} needs an expert: train one with `dualrep expert --env-url URL --out DIR/{env}.safetensors` and start the server with --models-dir DIR"
    )]
    NoModelsDir { env: String },
    /// The latest run checkpoint of a remote session does not resume.
    #[error("resuming from the latest checkpoint: {0}")]
    Resume(RunCheckpointError),
    /// The notes kept with that checkpoint do not read.
    #[error("reading the latest checkpoint's notes: {0}")]
    ResumeNotes(serde_json::Error),
    /// A stored answered step after that checkpoint does not fit the run.
    #[error("taking in the answers given after the latest checkpoint: {0}")]
    TakeIn(TakeInError),
    /// The env failed (its own words).
    #[error(transparent)]
    Env(#[from] EnvFault),
    /// The env failed at a step of the run.
    #[error("at step {step}: {fault}")]
    EnvAtStep { step: u64, fault: EnvFault },
    /// The env failed while replaying a query's clip.
    #[error("replaying a clip: {0}")]
    ClipReplay(EnvFault),
    /// A resume that does not reproduce the checkpoint it resumes from.
    #[error(
        "the resumed session's replay diverged from its checkpoint at {progress} (digest {got}, stored {expected})"
    )]
    ReplayDiverged {
        progress: u64,
        got: String,
        expected: String,
    },
    /// A human preference session on an env that does not repeat an episode from its seed.
    #[error(
        "{env} says it does not repeat an episode from its seed (deterministic: false): people compare clips replayed from the recorded trajectories, so a human preference session needs an env that does"
    )]
    NotDeterministic { env: String },
    /// Recording a preference session's trajectories on a remote env failed.
    #[error("recording the trajectories: {0}")]
    RecordTrajectories(EnvFault),
    /// The recorded trajectories give no segments to compare.
    #[error(
        "the recorded trajectories have no segments to compare (the env's predicates never change for long enough)"
    )]
    NoSegments,
    /// A remote preference session's kept trajectories do not read (what was wrong).
    #[error("reading the recorded trajectories: {0}")]
    KeptTrajectories(String),
    /// The env describes itself otherwise than when the trajectories were recorded.
    #[error(
        "the env does not describe itself as when the session recorded its trajectories (other predicates, features or sizes?)"
    )]
    EnvChanged,
}
