//! A headless run's folder across stops: the run checkpoint `train` keeps every
//! `--checkpoint-every` steps (with the notes that go beside it), the kernels a resumed run must
//! keep, the lock that refuses a second writer, and `metrics.csv` cut back to the episodes the
//! checkpoint counts.

use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use serde::{Deserialize, Serialize};

use super::episode_file::finished_rows;
use super::output::write_atomically;
use super::train_branch::BranchedFrom;
use crate::guidance::evaluative_run::{EpisodeRecord, EvaluativeRun};
use crate::guidance::evaluative_trainer::EvaluativeTrainer;
use crate::rl::kernels;

/// The run checkpoint's file name inside OUT.
pub const CHECKPOINT_FILE: &str = "checkpoint.run";

/// The folder inside OUT where `--keep-checkpoints` keeps each checkpoint by its step.
pub(super) const KEPT_CHECKPOINTS_DIR: &str = "checkpoints";

/// What `train` keeps with a run checkpoint beside the run itself.
#[derive(Debug, Default, Serialize, Deserialize)]
pub(super) struct ResumeNotes {
    /// The last finished episodes (for the final mean return and success rate).
    pub(super) recent_episodes: Vec<EpisodeRecord>,
    /// Wall time spent on the run before the checkpoint (a branch's: with the run it
    /// branched from, to the branch's step).
    pub(super) wall_seconds: f64,
    /// Where the run began, if it is a branch of another's (`--branch-from`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) branched_from: Option<BranchedFrom>,
}

/// Writes the run checkpoint at the first episode start after each multiple of `every` steps
/// (never if `every` is 0), and keeps the notes that go with it.
pub struct Checkpointer {
    path: PathBuf,
    every: u64,
    /// Where each checkpoint is also kept by its step (`--keep-checkpoints`), if anywhere.
    keep_in: Option<PathBuf>,
    next_at: u64,
    notes: ResumeNotes,
    start: Instant,
}

impl Checkpointer {
    pub(super) fn new(
        path: PathBuf,
        every: u64,
        keep_in: Option<PathBuf>,
        run: &EvaluativeRun,
        notes: ResumeNotes,
    ) -> Self {
        Self {
            path,
            every,
            keep_in,
            next_at: next_multiple(run.steps(), every),
            notes,
            start: Instant::now(),
        }
    }

    pub(super) fn wall_seconds(&self) -> f64 {
        self.notes.wall_seconds + self.start.elapsed().as_secs_f64()
    }

    /// Where the run began, if it is a branch of another's.
    pub(super) fn branched_from(&self) -> Option<&BranchedFrom> {
        self.notes.branched_from.as_ref()
    }

    /// The last finished episodes, oldest first.
    pub(super) fn recent_episodes(&self) -> &[EpisodeRecord] {
        &self.notes.recent_episodes
    }

    pub(super) fn record(&mut self, episode: &EpisodeRecord) {
        let recent = &mut self.notes.recent_episodes;
        recent.push(episode.clone());
        let excess = recent.len().saturating_sub(RECENT_EPISODES);
        recent.drain(..excess);
    }

    /// Save if the run is at an episode start past the next multiple of `every`.
    pub(super) fn maybe_save(
        &mut self,
        run: &EvaluativeRun,
        trainer: &dyn EvaluativeTrainer,
    ) -> anyhow::Result<()> {
        if self.every == 0 || run.steps() < self.next_at || !run.at_episode_start() {
            return Ok(());
        }
        let notes = ResumeNotes {
            recent_episodes: self.notes.recent_episodes.clone(),
            wall_seconds: self.wall_seconds(),
            branched_from: self.notes.branched_from.clone(),
        };
        write_atomically(
            &self.path,
            &run.checkpoint(trainer, serde_json::to_value(notes)?),
        )?;
        if let Some(dir) = &self.keep_in {
            keep_by_step(&self.path, dir, run.steps())?;
        }
        self.next_at = next_multiple(run.steps(), self.every);
        Ok(())
    }
}

/// The name a checkpoint taken at `step` is kept under: zero-padded, so that a folder's listing
/// is in step order.
fn kept_checkpoint_name(step: u64) -> String {
    format!("step-{step:09}.run")
}

/// Keeps the checkpoint just written at `path` as `dir/step-<step>.run`. A hard link costs no
/// copy, and the next checkpoint replaces `path` by rename, so the link keeps this one's bytes.
fn keep_by_step(path: &Path, dir: &Path, step: u64) -> anyhow::Result<()> {
    fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let kept = dir.join(kept_checkpoint_name(step));
    // A run stopped between writing a checkpoint and keeping it saves the step again on resume.
    match fs::remove_file(&kept) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(e).with_context(|| format!("replacing {}", kept.display()));
        }
        _ => {}
    }
    if fs::hard_link(path, &kept).is_err() {
        fs::copy(path, &kept)
            .with_context(|| format!("keeping {} as {}", path.display(), kept.display()))?;
    }
    Ok(())
}

/// The first multiple of `every` above `step` (`u64::MAX` when `every` is 0).
fn next_multiple(step: u64, every: u64) -> u64 {
    match every {
        0 => u64::MAX,
        _ => (step / every + 1) * every,
    }
}

/// Episodes behind `final_mean_return` and `final_success_rate`.
pub(super) const RECENT_EPISODES: usize = 10;

/// A run goes on with kernels of the numerics it began with, so that it stays bit for bit what
/// an uninterrupted run would have been: AVX-512 and AVX2 stand in for each other, the
/// portable path only for itself.
pub(super) fn keep_kernels_of(bytes: &[u8], path: &Path, label: &str) -> anyhow::Result<()> {
    let began = EvaluativeRun::checkpoint_kernels(bytes).with_context(|| {
        format!(
            "reading {} (delete it to start the run over)",
            path.display()
        )
    })?;
    let now = kernels::current_path();
    if began.numerics() == now.numerics() {
        return Ok(());
    }
    let Some(same) = began.available_equivalent() else {
        anyhow::bail!(
            "{} was computed with the {began} kernels, which this CPU cannot run; delete it to start \
             the run over",
            path.display()
        );
    };
    eprintln!(
        "{label}: the run began on the {began} kernels and goes on with {same} (not {now}), bit for bit"
    );
    kernels::set_default_path(same);
    Ok(())
}

/// Hold an exclusive lock on the run's folder for as long as the returned handle lives, so
/// that a second `train` on the same folder (a grid restarted while its old runs still go on,
/// the same command typed twice) is refused instead of interleaving its rows with the first's
/// and overwriting its checkpoint. The lock is the folder's own (flock), so no file is left
/// behind, and the kernel drops it when the process ends, however it ends. A file system that
/// cannot lock a folder (some network mounts a cluster's nodes share) gets a warning, not a
/// refusal: the run goes on unguarded, as before there was a lock.
pub(super) fn lock_run_dir(out: &Path) -> anyhow::Result<Option<File>> {
    let dir = File::open(out).with_context(|| format!("opening {}", out.display()))?;
    match dir.try_lock() {
        Ok(()) => Ok(Some(dir)),
        Err(fs::TryLockError::WouldBlock) => anyhow::bail!(
            "another `dualrep train` is writing {} (stop it, or wait for it to finish; this one \
             would resume from its checkpoint)",
            out.display()
        ),
        Err(fs::TryLockError::Error(e)) => {
            eprintln!(
                "warning: cannot lock {} ({e}); a second `dualrep train` on it would not be refused",
                out.display()
            );
            Ok(None)
        }
    }
}

/// Cut `metrics.csv` back to its header and first `episodes` rows: the rows a run checkpoint
/// counts (episodes that finished after it are run again and written again).
pub(super) fn keep_episodes(path: &Path, episodes: u64) -> anyhow::Result<()> {
    let text = fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let keep: Vec<&str> = finished_rows(&text)
        .lines()
        .take(1 + episodes as usize)
        .collect();
    if keep.len() != 1 + episodes as usize {
        anyhow::bail!(
            "{} has {} episode rows, the checkpoint counts {episodes}",
            path.display(),
            keep.len().saturating_sub(1)
        );
    }
    write_atomically(path, format!("{}\n", keep.join("\n")).as_bytes())
}
