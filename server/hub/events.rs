//! A session thread's events, applied by its owner: queries (with a remote session's steps as
//! its run stored them), synthetic answers, episodes and checkpoints go to the store; frames
//! and progress to the browsers; each query's deadline starts.

use std::sync::Arc;
use std::time::Duration;

use super::episode_frames::write_json;
use super::owner::{Open, Owner};
use crate::protocol::{QueryMessage, ServerMessage};
use crate::session::{QueryRecord, SessionEvent, TrainerKind};
use crate::store::{AlignmentRow, Status, SyntheticAnswer};

/// Synthetic answers stored per transaction at most.
const BATCH: usize = 512;
/// How often progress reaches the database (the snapshot has it at once).
const PROGRESS_TO_STORE_EVERY: Duration = Duration::from_secs(1);

impl Owner {
    /// Apply one event; `drained`: no other event waits, so buffered answers are stored now.
    pub(super) async fn apply(&mut self, event: SessionEvent, drained: bool) {
        if let Err(e) = self.apply_event(event).await {
            tracing::error!(session = %self.id, "storing a session event failed: {e}");
        }
        if (self.batch.len() >= BATCH || (drained && !self.batch.is_empty()))
            && let Err(e) = self.flush().await
        {
            tracing::error!(session = %self.id, "storing synthetic answers failed: {e}");
        }
    }

    async fn apply_event(&mut self, event: SessionEvent) -> Result<(), sqlx::Error> {
        match event {
            SessionEvent::Started { replayed, graph } => {
                self.progress.answered = replayed;
                self.graph = Some(graph);
                self.set_status(Status::Running, None).await;
            }
            SessionEvent::Frame(frame) => {
                if let Some(g) = &frame.geometry {
                    self.geometry = Some(g.clone());
                    self.publish();
                }
                self.episode_frames.push(&frame, self.geometry.as_ref());
                self.broadcast_message(&ServerMessage::Frame(*frame));
            }
            SessionEvent::Query {
                seq,
                step,
                abstract_state,
                content,
                record,
            } => {
                let payload = serde_json::to_string(&content).expect("query content serialises");
                let data = serde_json::to_string(&record.data).expect("query data serialises");
                let row = self
                    .store
                    .upsert_query(
                        &self.id,
                        seq,
                        self.kind,
                        step,
                        abstract_state,
                        &payload,
                        Some(&data),
                    )
                    .await?;
                // Before the query reaches anyone: every answer it gets has its step stored.
                if let Some(asked) = &record.asked {
                    self.store.store_asked_step(row, &self.id, asked).await?;
                }
                let timeout = self.answer_timeout;
                let text: Arc<str> = ServerMessage::Query(Box::new(QueryMessage {
                    id: seq,
                    step,
                    abstract_state,
                    expires_in_ms: timeout.as_millis() as u64,
                    content: *content,
                }))
                .to_text()
                .into();
                self.pending = Some(Open::new(seq, row, text.clone(), timeout));
                self.set_status(Status::Waiting, None).await;
                self.broadcast(text);
                if self.answers_per_query > 1 {
                    let votes = self.store.query_votes(row).await?;
                    if !votes.is_empty() {
                        self.restore_votes(votes).await;
                    }
                }
            }
            SessionEvent::Answered {
                seq,
                step,
                abstract_state,
                kind,
                value,
                record,
            } => {
                let QueryRecord { data, asked } = *record;
                self.batch.push(SyntheticAnswer {
                    seq,
                    kind,
                    step,
                    abstract_state,
                    value,
                    data: Some(serde_json::to_string(&data).expect("query data serialises")),
                    asked,
                });
                self.progress.answered += 1;
            }
            SessionEvent::Episode(e) => {
                self.store.insert_episode(&self.id, &e).await?;
                if let Some(clip) = self.episode_frames.take(e.episode) {
                    let path = self.hub.frames_path(&self.id, e.episode);
                    tokio::task::spawn_blocking(move || write_json(&path, &clip));
                }
                self.push_return(e.episode_return);
                self.progress.feedback_fraction = e.feedback_fraction;
                self.progress.pacing.get_or_insert_default().episode(&e);
                self.publish();
                self.broadcast_progress();
            }
            SessionEvent::Alignment {
                queries,
                alignment,
                alignment_of_mean,
            } => {
                // Against the synthetic trainer's theta: meaningless for people.
                if self.plan.spec.trainer == TrainerKind::Synthetic {
                    self.progress.alignment = Some(alignment);
                    let row = AlignmentRow {
                        queries: queries as i64,
                        alignment,
                        alignment_of_mean,
                    };
                    self.store.record_alignment(&self.id, row).await?;
                }
            }
            SessionEvent::Progress { progress } => {
                let progress = progress.max(self.resumed_at);
                self.progress.progress = progress;
                // Between episode ends too: the share of steps asked so far (every asked query
                // is answered, by a person or by its timeout).
                if self.progress.unit == "steps" && progress > 0 {
                    self.progress.feedback_fraction =
                        self.progress.answered as f64 / progress as f64;
                }
                self.publish();
                self.broadcast_progress();
                if self.stored_progress_at.elapsed() >= PROGRESS_TO_STORE_EVERY {
                    self.stored_progress_at = std::time::Instant::now();
                    let latest = serde_json::to_value(&self.progress).unwrap_or_default();
                    self.store.set_progress(&self.id, progress, &latest).await?;
                }
            }
            SessionEvent::Checkpoint(c) => {
                // Answers the checkpoint relies on must be stored before it is.
                self.flush().await?;
                if let Some(bytes) = c.resume {
                    // Before its row: the row says the session got this far. On PostgreSQL in
                    // the database too, for a server that takes the session over.
                    self.store.save_resume(&self.id, &bytes).await?;
                    if let Err(e) = self.hub.write_checkpoint(&self.id, "resume", bytes).await {
                        tracing::error!(session = %self.id, "writing a resume checkpoint: {e}");
                    }
                }
                let file = match c.weights {
                    Some(bytes) => Some(
                        self.hub
                            .write_checkpoint(&self.id, "safetensors", bytes)
                            .await,
                    ),
                    None => None,
                };
                let file = file.transpose().unwrap_or_else(|e| {
                    tracing::error!(session = %self.id, "writing a checkpoint: {e}");
                    None
                });
                self.store
                    .insert_checkpoint(&self.id, c.progress, c.answers, &c.digest, file.as_deref())
                    .await?;
            }
            SessionEvent::Revised {
                seq,
                revision,
                progress,
            } => {
                self.store
                    .revision_applied(&self.id, seq, revision, progress)
                    .await?;
            }
            SessionEvent::Ended(e) => self.ending = e,
        }
        Ok(())
    }

    /// Store the buffered synthetic answers in one transaction.
    pub(super) async fn flush(&mut self) -> Result<(), sqlx::Error> {
        if self.batch.is_empty() {
            return Ok(());
        }
        self.store.insert_synthetic(&self.id, &self.batch).await?;
        self.batch.clear();
        Ok(())
    }
}
