//! Applies one session's events: stores queries, synthetic answers, episodes and checkpoints;
//! keeps the live state that browsers join from; broadcasts frames and progress; starts each
//! query's answer timeout.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::mpsc::UnboundedReceiver;

use super::Hub;
use super::live::{Live, Pending};
use crate::session::{Ending, SessionEvent, TrainerKind};
use crate::store::{AlignmentRow, Status, SyntheticAnswer};
use crate::ws::protocol::{QueryMessage, ServerMessage};

/// Synthetic answers stored per transaction at most.
const BATCH: usize = 512;
/// How often progress reaches the database (the live state has it at once).
const PROGRESS_TO_STORE_EVERY: Duration = Duration::from_secs(1);

pub(super) async fn consume(
    hub: Arc<Hub>,
    live: Arc<Live>,
    mut rx: UnboundedReceiver<SessionEvent>,
) {
    let store = hub.store.clone();
    let id = live.id.clone();
    let mut batch: Vec<SyntheticAnswer> = Vec::new();
    let mut stored_progress_at = Instant::now();
    let mut ending = Ending::Failed("the session thread ended without a word".into());
    // The running episode's frames, written to the data dir when it ends (for replay in review).
    let mut episode_frames = EpisodeFrames::default();
    while let Some(event) = rx.recv().await {
        let result: Result<(), sqlx::Error> = async {
            match event {
                SessionEvent::Started { replayed } => {
                    live.lock().status = Status::Running;
                    live.lock().progress.answered = replayed;
                    store.set_status(&id, Status::Running, None).await?;
                }
                SessionEvent::Frame(frame) => {
                    if let Some(g) = &frame.geometry {
                        live.lock().geometry = Some(g.clone());
                    }
                    episode_frames.push(&frame, live.lock().geometry.as_ref());
                    live.broadcast_message(&ServerMessage::Frame(*frame));
                }
                SessionEvent::Query {
                    seq,
                    step,
                    abstract_state,
                    content,
                } => {
                    let payload =
                        serde_json::to_string(&content).expect("query content serialises");
                    let query_id = store
                        .upsert_query(&id, seq, live.kind, step, abstract_state, &payload)
                        .await?;
                    let timeout = live.answer_timeout;
                    let text: Arc<str> = ServerMessage::Query(QueryMessage {
                        id: query_id,
                        seq,
                        step,
                        abstract_state,
                        expires_in_ms: timeout.as_millis() as u64,
                        content: *content,
                    })
                    .to_text()
                    .into();
                    let now = Instant::now();
                    {
                        let mut s = live.lock();
                        s.pending = Some(Pending::new(
                            query_id,
                            seq,
                            live.kind,
                            text.clone(),
                            now,
                            timeout,
                        ));
                        s.status = Status::Waiting;
                    }
                    live.broadcast(text);
                    live.expire_after(store.clone(), query_id, timeout);
                }
                SessionEvent::Answered {
                    seq,
                    step,
                    abstract_state,
                    kind,
                    value,
                } => {
                    batch.push(SyntheticAnswer {
                        seq,
                        kind,
                        step,
                        abstract_state,
                        value,
                    });
                    live.lock().progress.answered += 1;
                }
                SessionEvent::Episode(e) => {
                    store.insert_episode(&id, &e).await?;
                    if let Some(clip) = episode_frames.take(e.episode) {
                        let path = hub.frames_path(&id, e.episode);
                        tokio::task::spawn_blocking(move || write_json(&path, &clip));
                    }
                    live.push_return(e.episode_return);
                    live.lock().progress.feedback_fraction = e.feedback_fraction;
                    live.broadcast_message(&live.progress_message());
                }
                SessionEvent::Alignment {
                    queries,
                    alignment,
                    alignment_of_mean,
                } => {
                    // Against the synthetic trainer's theta: meaningless for people.
                    if live.spec.trainer == TrainerKind::Synthetic {
                        live.lock().progress.alignment = Some(alignment);
                        let row = AlignmentRow {
                            queries: queries as i64,
                            alignment,
                            alignment_of_mean,
                        };
                        store.record_alignment(&id, row).await?;
                    }
                }
                SessionEvent::Progress { progress } => {
                    {
                        let mut s = live.lock();
                        s.progress.progress = progress;
                        // Between episode ends too: the share of steps asked so far (every
                        // asked query is answered, by a person or by its timeout).
                        if s.progress.unit == "steps" && progress > 0 {
                            s.progress.feedback_fraction =
                                s.progress.answered as f64 / progress as f64;
                        }
                    }
                    live.broadcast_message(&live.progress_message());
                    if stored_progress_at.elapsed() >= PROGRESS_TO_STORE_EVERY {
                        stored_progress_at = Instant::now();
                        let latest =
                            serde_json::to_value(&live.lock().progress).unwrap_or_default();
                        store.set_progress(&id, progress, &latest).await?;
                    }
                }
                SessionEvent::Checkpoint(c) => {
                    // Answers the checkpoint relies on must be stored before it is.
                    flush(&hub, &id, &mut batch).await?;
                    let file = match &c.weights {
                        Some(bytes) => Some(hub.write_checkpoint(&id, bytes.clone()).await),
                        None => None,
                    };
                    let file = file.transpose().unwrap_or_else(|e| {
                        tracing::error!(session = %id, "writing a checkpoint: {e}");
                        None
                    });
                    store
                        .insert_checkpoint(&id, c.progress, c.answers, &c.digest, file.as_deref())
                        .await?;
                }
                SessionEvent::Revised {
                    seq,
                    revision,
                    progress,
                } => {
                    store.revision_applied(&id, seq, revision, progress).await?;
                }
                SessionEvent::Ended(e) => ending = e,
            }
            if batch.len() >= BATCH || (rx.is_empty() && !batch.is_empty()) {
                flush(&hub, &id, &mut batch).await?;
            }
            Ok(())
        }
        .await;
        if let Err(e) = result {
            tracing::error!(session = %id, "storing a session event failed: {e}");
        }
    }
    if let Err(e) = flush(&hub, &id, &mut batch).await {
        tracing::error!(session = %id, "storing synthetic answers failed: {e}");
    }
    finish(&hub, &live, ending).await;
}

async fn flush(hub: &Hub, id: &str, batch: &mut Vec<SyntheticAnswer>) -> Result<(), sqlx::Error> {
    if batch.is_empty() {
        return Ok(());
    }
    hub.store.insert_synthetic(id, batch).await?;
    batch.clear();
    Ok(())
}

/// The session thread is done: store the final state and tell the browsers.
async fn finish(hub: &Hub, live: &Arc<Live>, ending: Ending) {
    let (status, reason) = match ending {
        Ending::Finished => (Status::Finished, None),
        Ending::Stopped => (Status::Stopped, None),
        Ending::Interrupted => (
            Status::Interrupted,
            Some("the server shut down".to_string()),
        ),
        Ending::Failed(r) => (Status::Failed, Some(r)),
    };
    let open = {
        let mut s = live.lock();
        s.status = status;
        s.reason = reason.clone();
        s.control = None;
        s.undoable = None;
        // A reopened query stays undone: its answer stands as "no feedback" (or a skip).
        [s.pending.take(), s.reopened.take()]
    };
    let latest = serde_json::to_value(&live.lock().progress).unwrap_or_default();
    let progress = live.lock().progress.progress;
    if let Err(e) = hub.store.set_progress(&live.id, progress, &latest).await {
        tracing::error!(session = %live.id, "storing progress: {e}");
    }
    if let Err(e) = hub
        .store
        .set_status(&live.id, status, reason.as_deref())
        .await
    {
        tracing::error!(session = %live.id, "storing the final status: {e}");
    }
    for p in open.into_iter().flatten() {
        live.broadcast_message(&ServerMessage::Withdrawn {
            id: p.id,
            reason: "ended",
        });
    }
    live.broadcast_message(&live.progress_message());
    live.broadcast_message(&ServerMessage::Ended { status, reason });
    // From here the store has the final state; connected sockets keep their `Arc` until they go.
    hub.forget(live);
    tracing::info!(session = %live.id, status = status.as_str(), "session ended");
}

/// Frames of the episode being played, in the shape of a query clip.
#[derive(Default)]
struct EpisodeFrames {
    episode: Option<u64>,
    geometry: Option<crate::sim::Geometry>,
    frames: Vec<crate::sim::RenderState>,
}

impl EpisodeFrames {
    fn push(&mut self, frame: &crate::session::Frame, geometry: Option<&crate::sim::Geometry>) {
        if self.episode != Some(frame.episode) {
            self.episode = Some(frame.episode);
            self.frames.clear();
            self.geometry = None;
        }
        if self.geometry.is_none() {
            self.geometry = frame.geometry.clone().or_else(|| geometry.cloned());
        }
        self.frames.push(frame.state.clone());
    }

    /// The frames of `episode`, if they were streamed.
    fn take(&mut self, episode: u64) -> Option<crate::session::Clip> {
        if self.episode != Some(episode) || self.frames.is_empty() {
            return None;
        }
        self.episode = None;
        Some(crate::session::Clip {
            geometry: self.geometry.take()?,
            frames: std::mem::take(&mut self.frames),
        })
    }
}

/// Write JSON atomically (a temporary file renamed into place); failures are logged.
fn write_json(path: &std::path::Path, value: &impl serde::Serialize) {
    let result = (|| -> std::io::Result<()> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let tmp = path.with_extension("json.tmp");
        std::fs::write(
            &tmp,
            serde_json::to_vec(value).map_err(std::io::Error::other)?,
        )?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        tracing::error!("writing {}: {e}", path.display());
    }
}
