//! Writing a command's result files so that a reader never sees half of one.

use std::fs;
use std::path::Path;

use anyhow::Context;
use serde::Serialize;

/// Write `bytes` to `path` through a temporary file and a rename, so a reader never sees half.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let tmp = path.with_extension("tmp");
    fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, path)
        .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
}

/// A run's last act: its summary as pretty JSON at `path` (atomically; its presence marks the
/// run finished for `reproduce`), and as one JSON line on stdout.
pub fn publish_summary<T: Serialize>(path: &Path, summary: &T) -> anyhow::Result<()> {
    write_atomically(path, &serde_json::to_vec_pretty(summary)?)?;
    println!("{}", serde_json::to_string(summary)?);
    Ok(())
}
