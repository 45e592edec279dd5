//! A session's remote env, reached from its own thread when it starts (blocking IO, never on
//! the async runtime): connected and checked, with what the session resumes from, and another
//! connection on demand for clips.

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::remote_env::{RemoteTarget, Timeouts};
use crate::session::{Reconnect, RemoteSession, SessionSpec, StoredMoment};
use crate::sim::{Env, EnvFault};

/// Why a session's remote env could not be reached or resumed from.
#[derive(Debug, thiserror::Error)]
pub enum ConnectError {
    /// The env is unreachable, or not a copy of the session's task (its own words).
    #[error(transparent)]
    Env(#[from] EnvFault),
    /// The resume checkpoint is there but does not read.
    #[error("reading the session's checkpoint {}: {error}", .path.display())]
    ReadCheckpoint {
        path: PathBuf,
        error: std::io::Error,
    },
}

/// What the session thread needs to reach its env.
pub struct RemotePlan {
    pub target: RemoteTarget,
    pub timeout_s: f64,
    /// `<data dir>/checkpoints/<id>.resume`.
    pub resume_path: PathBuf,
    pub stored_queries: u64,
    /// The stored evaluative queries (with the steps they asked about) a resumed run catches
    /// up on, or takes in where it does not meet them again.
    pub stored_moments: Vec<StoredMoment>,
}

impl RemotePlan {
    /// Connect, read the resume checkpoint if there is one; `Err`: why the session cannot run.
    pub fn connect(self, spec: &SessionSpec) -> Result<RemoteSession, ConnectError> {
        let timeouts = Timeouts {
            request: Duration::from_secs_f64(self.timeout_s),
            ..Timeouts::default()
        };
        let env = self.target.connect(spec.task, timeouts)?;
        let description = env.description().clone();
        let resume_from = match std::fs::read(&self.resume_path) {
            Ok(bytes) => Some(bytes),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(error) => {
                return Err(ConnectError::ReadCheckpoint {
                    path: self.resume_path,
                    error,
                });
            }
        };
        let (target, task) = (self.target, spec.task);
        let reconnect: Reconnect = Box::new(move || {
            target
                .connect(task, timeouts)
                .map(|env| Box::new(env) as Box<dyn Env>)
        });
        Ok(RemoteSession {
            env: Box::new(env),
            description,
            reconnect,
            resume_from,
            stored_queries: self.stored_queries,
            stored_moments: self.stored_moments,
        })
    }
}

/// A remote session resumed from a checkpoint records from there on: keep the recording so far
/// as `<id>.part<N>.rrd` (the first free N) instead of writing over it.
pub fn keep_earlier_recording(path: &Path) -> std::io::Result<()> {
    if !path.exists() {
        return Ok(());
    }
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("recording");
    for n in 1.. {
        let part = path.with_file_name(format!("{stem}.part{n}.rrd"));
        if !part.exists() {
            return std::fs::rename(path, part);
        }
    }
    unreachable!("some part number is free")
}
