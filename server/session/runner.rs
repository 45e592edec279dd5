//! The session loop: drives a session's plan on the calling thread (the server gives each
//! session its own), pacing human sessions to a watchable rate, streaming
//! frames, asking people through the control channel, replaying stored answers after a resume,
//! and checkpointing. The loops themselves are in `evaluative_loop` and `preference_loop`.

use std::path::PathBuf;
use std::sync::Arc;

use crate::rl::kernels::{self, KernelPath};

use super::error::SessionError;
use super::events::{
    AnswerValue, Controls, Ending, Halt, Observer, Revision, SessionEvent, SessionSink,
    StoredRevision,
};
use super::plan::RunConfig;
use super::plan::SessionPlan;
use super::remote::RemoteSession;
use super::{evaluative_loop, preference_loop};

/// Everything a session thread gets besides its plan.
pub struct SessionContext {
    pub sink: Arc<dyn SessionSink>,
    pub controls: Controls,
    /// Answers already stored for this session, by query order: replayed, never asked again.
    pub stored_answers: Vec<AnswerValue>,
    /// Revisions of stored answers (undos), ordered by the progress they were applied at.
    pub stored_revisions: Vec<StoredRevision>,
    /// The latest checkpoint `(progress, digest)`: a resumed session checks its replay against it.
    pub verify: Option<(u64, String)>,
    /// Where the synthetic trainer's experts live (`<dir>/<task>.safetensors`).
    pub models_dir: Option<PathBuf>,
    /// Sees every step, query and answer (the recording), if any.
    pub observer: Option<Box<dyn Observer>>,
    /// The env, connected, when the session's is in another process (`spec.env`).
    pub remote: Option<RemoteSession>,
}

/// Run the session to its end and report how it ended (also sent as `SessionEvent::Ended`).
/// On a remote env, `plan` is the one on the env connected in `ctx`
/// ([`SessionPlan::on_remote`]).
///
/// The learner computes with the session's kernels (or kernels of the same numerics) on this
/// thread, and counts as active while it runs, so that sessions running at once share the
/// cores between their products.
pub fn run_session(plan: SessionPlan, ctx: SessionContext) -> Ending {
    let sink = ctx.sink.clone();
    let ending = match session_kernels(&plan) {
        Ok(path) => {
            let _active = kernels::ActiveLearner::register();
            match kernels::with_path(path, || run(plan, ctx)) {
                Ok(ending) => ending,
                Err(e) => Ending::Failed(e.to_string()),
            }
        }
        Err(e) => Ending::Failed(e.to_string()),
    };
    sink.send(SessionEvent::Ended(ending.clone()));
    ending
}

/// The kernels to run `plan` with: those it was launched with, or others of the same numerics.
fn session_kernels(plan: &SessionPlan) -> Result<KernelPath, SessionError> {
    match plan.settings.kernels {
        None => Ok(kernels::default_path()),
        Some(path) => path
            .available_equivalent()
            .ok_or(SessionError::KernelsUnavailable(path)),
    }
}

/// Builds the run and drives it. The observer (the recording) goes with the trainer and is
/// dropped, and so flushed, before the session reports its end.
fn run(plan: SessionPlan, mut ctx: SessionContext) -> Result<Ending, SessionError> {
    let observer = ctx.observer.take();
    let remote = ctx.remote.take();
    if plan.spec.env.is_some() != remote.is_some() {
        return Err(SessionError::RemoteNotConnected);
    }
    let SessionPlan {
        spec,
        settings,
        run,
        ..
    } = plan;
    match run {
        RunConfig::Evaluative(config) => {
            evaluative_loop::run(&spec, settings, *config, remote, ctx, observer)
        }
        RunConfig::Preference(config) => {
            preference_loop::run(&spec, *config, remote, ctx, observer)
        }
    }
}

/// FNV-1a over bytes, as hex: a digest that is stable across builds and platforms.
pub fn digest(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{hash:016x}")
}

/// Ends the loop early when the replay does not reproduce the checkpoint it resumes from.
pub(super) fn check_replay(
    verify: &Option<(u64, String)>,
    progress: u64,
    digest_now: impl FnOnce() -> String,
) -> Result<(), SessionError> {
    match verify {
        Some((at, expected)) if *at == progress => {
            let got = digest_now();
            if &got == expected {
                Ok(())
            } else {
                Err(SessionError::ReplayDiverged {
                    progress,
                    got,
                    expected: expected.clone(),
                })
            }
        }
        _ => Ok(()),
    }
}

pub(super) fn revised(r: Revision, progress: u64) -> SessionEvent {
    SessionEvent::Revised {
        seq: r.seq,
        revision: r.revision,
        progress,
    }
}

pub(super) fn halt_ending(h: Halt) -> Ending {
    match h {
        Halt::Stop => Ending::Stopped,
        Halt::Shutdown => Ending::Interrupted,
    }
}
