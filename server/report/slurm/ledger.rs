//! Which Slurm task ran (or is running) which run: `<grid>/.slurm/submissions.jsonl`, one line
//! per `sbatch`, appended once Slurm has accepted the array.
//!
//! This is how a grid survives its submitter: run the command again (after `--no-wait`, a
//! lost login, a Ctrl-C) and each unfinished run's latest task is looked up in the queue; a
//! task still queued or running is waited for, not submitted a second time.

use std::collections::HashMap;
use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::{Deserialize, Serialize};

use super::queue::TaskId;

/// One accepted `sbatch`: array task `i` runs `runs[i]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    pub job: String,
    /// The batch script, relative to the ledger's folder.
    pub script: String,
    /// Run directories relative to the grid's folder, by array index.
    pub runs: Vec<String>,
}

/// Every submission of a grid, read at start and appended to as arrays are submitted.
#[derive(Debug)]
pub struct Ledger {
    path: PathBuf,
    submissions: Vec<Submission>,
    /// Each run's latest task.
    latest: HashMap<String, TaskId>,
}

pub const LEDGER_FILE: &str = "submissions.jsonl";

impl Ledger {
    /// Reads `dir/submissions.jsonl` (none yet is an empty ledger).
    pub fn open(dir: &Path) -> anyhow::Result<Ledger> {
        let path = dir.join(LEDGER_FILE);
        let mut ledger = Ledger {
            path: path.clone(),
            submissions: Vec::new(),
            latest: HashMap::new(),
        };
        let text = match fs::read_to_string(&path) {
            Ok(text) => text,
            Err(err) if err.kind() == std::io::ErrorKind::NotFound => return Ok(ledger),
            Err(err) => return Err(err).with_context(|| format!("reading {}", path.display())),
        };
        for (n, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let submission: Submission = serde_json::from_str(line).with_context(|| {
                format!(
                    "{} line {}: not a submission record (was the file edited?)",
                    path.display(),
                    n + 1
                )
            })?;
            ledger.note(submission);
        }
        Ok(ledger)
    }

    fn note(&mut self, submission: Submission) {
        for (index, run) in submission.runs.iter().enumerate() {
            let task = TaskId {
                job: submission.job.clone(),
                index: index as u32,
            };
            self.latest.insert(run.clone(), task);
        }
        self.submissions.push(submission);
    }

    /// Records a submission as soon as Slurm has accepted it, flushed to the device: tasks
    /// already in the queue must not be forgotten (and submitted twice) after a crash.
    pub fn append(&mut self, submission: Submission) -> anyhow::Result<()> {
        let mut line = serde_json::to_string(&submission)?;
        line.push('\n');
        let mut file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(&self.path)
            .with_context(|| format!("opening {}", self.path.display()))?;
        file.write_all(line.as_bytes())
            .and_then(|()| file.sync_data())
            .with_context(|| format!("writing {}", self.path.display()))?;
        self.note(submission);
        Ok(())
    }

    /// The task that last ran `run` (a run directory relative to the grid), if any.
    pub fn latest(&self, run: &str) -> Option<&TaskId> {
        self.latest.get(run)
    }

    /// How many arrays were submitted so far (numbers the next batch script).
    pub fn len(&self) -> usize {
        self.submissions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.submissions.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn submission(job: &str, runs: &[&str]) -> Submission {
        Submission {
            job: job.into(),
            script: format!("array-{job}.sh"),
            runs: runs.iter().map(|r| r.to_string()).collect(),
        }
    }

    #[test]
    fn report_slurm_ledger_keeps_each_runs_latest_task_across_invocations() {
        let tmp = tempfile::tempdir().unwrap();
        let mut ledger = Ledger::open(tmp.path()).unwrap();
        assert!(ledger.is_empty());
        ledger
            .append(submission("41", &["r/a/seed0", "r/a/seed1"]))
            .unwrap();
        // seed1 failed and went again in a second array.
        ledger.append(submission("57", &["r/a/seed1"])).unwrap();

        let again = Ledger::open(tmp.path()).unwrap();
        assert_eq!(again.len(), 2);
        let task = |job: &str, index| TaskId {
            job: job.into(),
            index,
        };
        assert_eq!(again.latest("r/a/seed0"), Some(&task("41", 0)));
        assert_eq!(again.latest("r/a/seed1"), Some(&task("57", 0)));
        assert_eq!(again.latest("r/a/seed2"), None);
    }

    #[test]
    fn report_slurm_ledger_names_a_damaged_line() {
        let tmp = tempfile::tempdir().unwrap();
        fs::write(tmp.path().join(LEDGER_FILE), "{\"job\":\"1\"\n").unwrap();
        let err = Ledger::open(tmp.path()).unwrap_err();
        assert!(
            format!("{err:#}").contains("line 1: not a submission record"),
            "{err:#}"
        );
    }
}
