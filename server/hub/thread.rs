//! Starting a session's thread: its stored answers and revisions to replay, the checkpoint to
//! verify against, its recording, and the thread itself (the training loop never runs on the
//! async runtime).

use std::sync::Arc;

use tokio::sync::mpsc::UnboundedReceiver;

use super::owner::Owner;
use super::remote::{RemotePlan, keep_earlier_recording};
use super::{recording, sink};
use crate::record::RecordingOptions;
use crate::session::{Controls, Ending, SessionContext, SessionEvent, SessionPlan, run_session};

/// Why a session's thread could not start: the failed session's reason.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// Its stored answers, revisions or latest checkpoint do not read.
    #[error("reading the session's answers: {0}")]
    Answers(sqlx::Error),
    /// Its stored queries (a remote session's) do not read.
    #[error("reading the session's queries: {0}")]
    Queries(sqlx::Error),
    #[error("the session's thread could not start: {0}")]
    Spawn(std::io::Error),
}

impl Owner {
    /// Start the session thread; its events arrive on the returned channel, which closes when
    /// the thread has ended. `Err`: why it could not start.
    pub(super) async fn start_thread(
        &mut self,
    ) -> Result<UnboundedReceiver<SessionEvent>, StartError> {
        let id = self.id.clone();
        let (stored_answers, stored_revisions, checkpoint) = match (
            self.store.replay_answers(&id).await,
            self.store.replay_revisions(&id).await,
            self.store.latest_checkpoint(&id).await,
        ) {
            (Ok(a), Ok(r), Ok(c)) => (a, r, c),
            (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => {
                return Err(StartError::Answers(e));
            }
        };
        // A checkpoint is checked only if the replay reaches it with stored answers alone (a
        // session on a remote env resumes from its checkpoint instead).
        let plan = SessionPlan::clone(&self.plan);
        let verify = checkpoint
            .filter(|c| c.answers as usize <= stored_answers.len() && plan.spec.env.is_none())
            .map(|c| (c.progress as u64, c.digest));
        let settings = &plan.settings;
        let remote = match &plan.spec.env {
            None => None,
            Some(target) => Some(RemotePlan {
                target: target.clone(),
                timeout_s: settings.env_timeout_s,
                resume_path: self.hub.resume_path(&id),
                stored_queries: self
                    .store
                    .query_count(&id)
                    .await
                    .map_err(StartError::Queries)?,
                stored_moments: if plan.spec.method.is_preference() {
                    Vec::new()
                } else {
                    self.store
                        .stored_moments(&id)
                        .await
                        .map_err(StartError::Queries)?
                },
            }),
        };
        let options = RecordingOptions {
            path: settings.record.then(|| self.hub.recording_path(&id)),
            connect: settings
                .rerun_connect
                .clone()
                .or_else(|| self.hub.config.rerun_connect.clone()),
        };
        let (control_tx, control_rx) = std::sync::mpsc::channel();
        let (event_tx, event_rx) = tokio::sync::mpsc::unbounded_channel();
        let ctx = SessionContext {
            sink: Arc::new(sink::ChannelSink(event_tx.clone())),
            controls: Controls::new(control_rx),
            stored_answers,
            stored_revisions,
            verify,
            models_dir: self.hub.config.models_dir.clone(),
            observer: None,
            remote: None,
        };
        let mut builder = std::thread::Builder::new().name(format!("session-{id}"));
        if let Some(bytes) = self.hub.config.session_stack_size {
            builder = builder.stack_size(bytes);
        }
        let failed = move |reason: String| {
            let _ = event_tx.send(SessionEvent::Ended(Ending::Failed(reason)));
        };
        builder
            .spawn(move || {
                let mut ctx = ctx;
                let mut plan = plan;
                // Reaching a remote env is blocking IO too: here, with a deadline.
                if let Some(remote) = remote {
                    match remote.connect(&plan.spec) {
                        Ok(r) => {
                            plan = match plan.on_remote(&r.description) {
                                Ok(plan) => plan,
                                Err(e) => return failed(e.to_string()),
                            };
                            let from_checkpoint =
                                r.resume_from.is_some() && !plan.spec.method.is_preference();
                            if let (true, Some(path)) = (from_checkpoint, &options.path)
                                && let Err(e) = keep_earlier_recording(path)
                            {
                                return failed(format!("keeping the recording so far: {e}"));
                            }
                            ctx.remote = Some(r);
                        }
                        Err(e) => return failed(e.to_string()),
                    }
                }
                // Opening the file (and a viewer connection) is blocking IO: here, not on the
                // async runtime.
                match recording::start(&id, plan.graph, &options) {
                    Ok(observer) => ctx.observer = observer,
                    Err(e) => return failed(format!("the recording could not start: {e:#}")),
                }
                let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    run_session(plan, ctx)
                }));
                if let Err(panic) = result {
                    let what = panic
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_else(|| "unknown".into());
                    failed(format!("the session panicked: {what}"));
                }
            })
            .map_err(StartError::Spawn)?;
        self.control = Some(control_tx);
        Ok(event_rx)
    }
}
