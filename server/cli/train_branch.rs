//! `train --branch-from`: a run that begins as another run's checkpoint and goes on under this
//! command's settings (the check of what may differ is the core's, `run_branch.rs`). The new
//! run's folder starts with the other run's rows up to the checkpoint, so that its
//! `metrics.csv`, `learner.csv`, `answers.csv` and `summary.json` read as a run from step 0
//! would, and its summary says where it branched.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::{Deserialize, Serialize};

use super::answer_log::{ANSWERS_FILE, keep_answer_rows};
use super::learner_log::{LEARNER_FILE, keep_learner_rows};
use super::train_checkpoint::{KEPT_CHECKPOINTS_DIR, ResumeNotes, keep_episodes};
use crate::guidance::evaluative_run::{EvaluativeRun, EvaluativeRunConfig};
use crate::guidance::evaluative_trainer::EvaluativeTrainer;
use crate::sim::Env;

/// Where a branched run began: kept in its checkpoints' notes and written to its summary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BranchedFrom {
    /// The checkpoint it began from, as given.
    pub checkpoint: PathBuf,
    /// The step (and episodes) of that checkpoint: everything before is the other run's.
    pub step: u64,
    pub episodes: u64,
}

/// The branch at `from`'s step under `config`, to `steps`, its folder `out` given the other
/// run's rows.
pub(super) fn start_branch(
    from: &Path,
    bytes: &[u8],
    config: &EvaluativeRunConfig,
    steps: u64,
    env: Option<Box<dyn Env>>,
    trainer: &mut dyn EvaluativeTrainer,
    out: &Path,
) -> anyhow::Result<(EvaluativeRun, ResumeNotes)> {
    let (run, notes) = EvaluativeRun::branch(bytes, config, steps, env, trainer)
        .with_context(|| format!("branching from {}", from.display()))?;
    let mut notes: ResumeNotes = serde_json::from_value(notes)
        .with_context(|| format!("reading the notes in {}", from.display()))?;
    take_rows(&source_folder(from), out, run.episodes())?;
    notes.branched_from = Some(BranchedFrom {
        checkpoint: from.to_path_buf(),
        step: run.steps(),
        episodes: run.episodes(),
    });
    Ok((run, notes))
}

/// The checkpoint `--branch-from` names: the file given, or in a folder of kept checkpoints (or
/// a run's folder holding one, `checkpoints/`), the latest taken at or before the step from
/// which `config` stops asking (the latest of all when it asks to the end). Which one is taken
/// changes only the cost: each is the same run, so the branch is the same from any of them.
pub(super) fn branch_checkpoint(
    path: &Path,
    config: &EvaluativeRunConfig,
) -> anyhow::Result<PathBuf> {
    if !path.is_dir() {
        return Ok(path.to_path_buf());
    }
    let dir = match path.join(KEPT_CHECKPOINTS_DIR) {
        kept if kept.is_dir() => kept,
        _ => path.to_path_buf(),
    };
    let limit = config.feedback_until.unwrap_or(u64::MAX);
    let mut best: Option<(u64, PathBuf)> = None;
    for entry in fs::read_dir(&dir).with_context(|| format!("reading {}", dir.display()))? {
        let file = entry?.path();
        let step = file
            .file_name()
            .and_then(|n| n.to_str())
            .and_then(|n| n.strip_prefix("step-")?.strip_suffix(".run"))
            .and_then(|n| n.parse::<u64>().ok());
        if let Some(step) = step.filter(|&s| s <= limit)
            && best.as_ref().is_none_or(|(b, _)| step > *b)
        {
            best = Some((step, file));
        }
    }
    best.map(|(_, file)| file).with_context(|| {
        format!(
            "--branch-from: no kept checkpoint (step-<N>.run) in {} at or before step {}",
            dir.display(),
            config
                .feedback_until
                .map_or_else(|| "(any)".into(), |n| n.to_string())
        )
    })
}

/// The folder of the run a checkpoint is of: beside `checkpoint.run`, or above the
/// `checkpoints/` folder `--keep-checkpoints` keeps them in.
fn source_folder(checkpoint: &Path) -> PathBuf {
    let parent = checkpoint.parent().unwrap_or(Path::new("."));
    match parent.file_name() {
        Some(name) if name == KEPT_CHECKPOINTS_DIR => {
            parent.parent().unwrap_or(Path::new(".")).to_path_buf()
        }
        _ => parent.to_path_buf(),
    }
}

/// Copies the source run's rows into `out`, cut to the `episodes` the checkpoint counts (the
/// source may have run on past it). `metrics.csv` must be there; the learner's and answers'
/// files are copied where the source wrote them.
fn take_rows(source: &Path, out: &Path, episodes: u64) -> anyhow::Result<()> {
    // Copying a folder's rows onto themselves would empty them.
    if fs::canonicalize(source).ok() == fs::canonicalize(out).ok() {
        anyhow::bail!(
            "--branch-from: {} is a checkpoint of the run in {} itself; branch into another folder",
            source.display(),
            out.display()
        );
    }
    for (file, needed) in [
        ("metrics.csv", true),
        (LEARNER_FILE, false),
        (ANSWERS_FILE, false),
    ] {
        let from = source.join(file);
        if !needed && !from.exists() {
            continue;
        }
        fs::copy(&from, out.join(file)).with_context(|| {
            format!(
                "copying {} (the rows of the run the checkpoint is of)",
                from.display()
            )
        })?;
    }
    keep_episodes(&out.join("metrics.csv"), episodes)?;
    keep_learner_rows(out, episodes)?;
    keep_answer_rows(out, episodes)
}
