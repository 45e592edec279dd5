//! A run's CSV with one row per finished episode (`metrics.csv`, `learner.csv`, `answers.csv`):
//! a new file, or the one an earlier call of the same run began, and (for the two beside
//! `metrics.csv`) its cut back to a checkpoint's episodes on a resume. A run checkpoint is taken
//! at an episode's start, so a row per episode is exact across a resume: no episode is split by
//! it.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::Context;

use super::output::write_atomically;

/// An open per-episode file, flushed after every row.
pub struct EpisodeFile {
    csv: BufWriter<File>,
}

impl EpisodeFile {
    /// A new file at `path` with `header`, or the one an earlier call began when `append`
    /// (created with its header if that run had none: a run begun by a build without the file
    /// starts it at the episode it resumes from).
    pub fn open(path: &Path, header: &str, append: bool) -> anyhow::Result<Self> {
        let fresh = !append || !path.exists();
        let file = if fresh {
            File::create(path)
        } else {
            File::options().append(true).open(path)
        };
        let mut csv = BufWriter::new(file.with_context(|| format!("opening {}", path.display()))?);
        if fresh {
            writeln!(csv, "{header}")?;
        }
        Ok(Self { csv })
    }

    /// One episode's row (its columns after the header's order), flushed.
    pub fn row(&mut self, line: std::fmt::Arguments) -> anyhow::Result<()> {
        self.csv.write_fmt(line)?;
        self.csv.write_all(b"\n")?;
        self.csv.flush()?;
        Ok(())
    }
}

/// Cut the file at `path` back to `header` and the rows of episodes before `episodes` (those
/// a run checkpoint counts; the episode is a row's second column); nothing to do if the run
/// has no such file.
pub fn keep_episode_rows(path: &Path, header: &str, episodes: u64) -> anyhow::Result<()> {
    let text = match fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    let mut keep = vec![header];
    for line in finished_rows(&text).lines().skip(1) {
        let episode: u64 = line
            .split(',')
            .nth(1)
            .and_then(|e| e.parse().ok())
            .with_context(|| format!("{}: a row without its episode: {line:?}", path.display()))?;
        if episode < episodes {
            keep.push(line);
        }
    }
    write_atomically(path, format!("{}\n", keep.join("\n")).as_bytes())
}

/// `text` up to its last newline: a row still being written when the file was read (a run
/// stopped mid-row, or a running run's file copied by `--branch-from`) is not a row yet.
pub fn finished_rows(text: &str) -> &str {
    text.rfind('\n').map_or("", |end| &text[..=end])
}
