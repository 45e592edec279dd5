//! One running (or recently ended) session as the async side sees it: the pending query, the
//! broadcast to watching browsers, and the answer path. An answer is forwarded to the session
//! thread and acknowledged only after the store committed it; the first committed answer wins.
//! A trainer may undo the latest answer (module `undo`).

use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use tokio::sync::broadcast;

use crate::session::{AnswerValue, Control, SessionSpec};
use crate::sim::Geometry;
use crate::store::{CommitOutcome, Status, Store};

use super::undo::Undoable;
use crate::ws::protocol::{ProgressMessage, ProtocolError, ServerMessage};

/// Messages kept for a browser that falls behind before it must catch up from `hello`.
const BROADCAST_CAPACITY: usize = 256;
/// Returns kept for the trainer's live curve.
const RECENT_RETURNS: usize = 50;

/// The query a session waits on.
#[derive(Clone, Debug)]
pub struct Pending {
    pub id: i64,
    pub seq: u64,
    pub kind: &'static str,
    /// The query message, serialised once for every browser.
    pub text: Arc<str>,
    pub asked: Instant,
    pub deadline: Instant,
    /// Held while an answer commits; then holds the stored answer. Trainers answering at the
    /// same moment queue here instead of racing to the database, and get the stored answer.
    pub commit: Arc<tokio::sync::Mutex<Option<AnswerValue>>>,
}

impl Pending {
    pub fn new(
        id: i64,
        seq: u64,
        kind: &'static str,
        text: Arc<str>,
        asked: Instant,
        timeout: std::time::Duration,
    ) -> Self {
        Self {
            id,
            seq,
            kind,
            text,
            asked,
            deadline: asked + timeout,
            commit: Arc::new(tokio::sync::Mutex::new(None)),
        }
    }
}

/// Answers kept in memory after their query closed, so repeats need no database read.
const RECENT_ANSWERS: usize = 256;

/// What browsers need to (re)join.
#[derive(Debug)]
pub struct LiveState {
    pub status: Status,
    pub reason: Option<String>,
    pub pending: Option<Pending>,
    pub geometry: Option<Geometry>,
    pub progress: ProgressMessage,
    pub control: Option<Sender<Control>>,
    /// Set by `stop` before the session thread exists (a queued session).
    pub stop_requested: bool,
    /// The latest committed answers, newest last.
    pub recent: std::collections::VecDeque<(i64, AnswerValue)>,
    /// The latest answer a trainer gave (not a timeout's), until undone or too old.
    pub undoable: Option<Undoable>,
    /// A query open again after an undo (besides `pending`, which the session may be waiting
    /// on meanwhile).
    pub reopened: Option<Pending>,
}

impl LiveState {
    /// A committed answer to `query`: counted, kept for repeats, and undoable if a trainer
    /// gave it.
    pub(super) fn remember(&mut self, query: &Pending, value: AnswerValue, reason: &str) {
        self.progress.answered += 1;
        if self.recent.len() == RECENT_ANSWERS {
            self.recent.pop_front();
        }
        self.recent.push_back((query.id, value));
        if reason == "answered" {
            self.undoable = Some(Undoable {
                query: query.clone(),
                at: Instant::now(),
            });
        }
    }
}

/// The refusal for a value of the wrong kind.
fn bad_value(id: i64, kind: &str) -> ProtocolError {
    ProtocolError::new(
        "bad_value",
        format!(
            "query {id} is {kind}: answer {}",
            if kind == "evaluative" {
                "1, 0 or -1"
            } else {
                "\"left\", \"right\", \"equal\" or \"skip\""
            }
        ),
    )
}

/// A session known to the hub.
#[derive(Debug)]
pub struct Live {
    pub id: String,
    pub spec: SessionSpec,
    pub trainer_token: String,
    pub kind: &'static str,
    pub answer_timeout: std::time::Duration,
    pub state: Mutex<LiveState>,
    tx: broadcast::Sender<Arc<str>>,
}

/// What a trainer's answer got.
#[derive(Clone, Debug, PartialEq)]
pub enum AnswerReply {
    Ack(AnswerValue),
    Refused(ProtocolError),
}

impl Live {
    pub fn new(
        id: String,
        spec: SessionSpec,
        trainer_token: String,
        answer_timeout: std::time::Duration,
    ) -> Self {
        let (tx, _) = broadcast::channel(BROADCAST_CAPACITY);
        let kind = spec.method.query_kind();
        let progress = ProgressMessage {
            budget: spec.budget,
            unit: spec.method.budget_unit(),
            ..Default::default()
        };
        Self {
            id,
            spec,
            trainer_token,
            kind,
            answer_timeout,
            state: Mutex::new(LiveState {
                status: Status::Queued,
                reason: None,
                pending: None,
                geometry: None,
                progress,
                control: None,
                stop_requested: false,
                recent: std::collections::VecDeque::new(),
                undoable: None,
                reopened: None,
            }),
            tx,
        }
    }

    pub fn lock(&self) -> std::sync::MutexGuard<'_, LiveState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    pub fn subscribe(&self) -> broadcast::Receiver<Arc<str>> {
        self.tx.subscribe()
    }

    /// Send to every connected browser (none connected is fine).
    pub fn broadcast(&self, text: Arc<str>) {
        let _ = self.tx.send(text);
    }

    pub fn broadcast_message(&self, m: &ServerMessage) {
        self.broadcast(m.to_text().into());
    }

    /// What a joining browser gets after `hello`: the pending query (with its time left) and
    /// the progress.
    pub fn catch_up(&self) -> Vec<Arc<str>> {
        let s = self.lock();
        let mut out = vec![ServerMessage::Progress(s.progress.clone()).to_text().into()];
        if let Some(p) = &s.pending {
            out.push(p.text.clone());
        }
        // Last, so that a page showing one query at a time shows the one the trainer reopened.
        if let Some(p) = &s.reopened {
            out.push(p.text.clone());
        }
        if !s.status.is_active() {
            out.push(
                ServerMessage::Ended {
                    status: s.status,
                    reason: s.reason.clone(),
                }
                .to_text()
                .into(),
            );
        }
        out
    }

    pub fn push_return(&self, r: f64) {
        let mut s = self.lock();
        let returns = &mut s.progress.recent_returns;
        returns.push(r);
        if returns.len() > RECENT_RETURNS {
            returns.remove(0);
        }
    }

    pub fn progress_message(&self) -> ServerMessage {
        ServerMessage::Progress(self.lock().progress.clone())
    }

    /// Answer query `id` with `value` on behalf of `who` (`trainer` or `timeout`).
    pub async fn answer(
        &self,
        store: &Store,
        id: i64,
        value: AnswerValue,
        who: &str,
    ) -> AnswerReply {
        let refuse =
            |code, message: String| AnswerReply::Refused(ProtocolError::new(code, message));
        let (pending, reopened) = {
            let s = self.lock();
            (s.pending.clone(), s.reopened.clone())
        };
        let (pending, reopened) = match (pending, reopened) {
            (_, Some(p)) if p.id == id => (p, true),
            (Some(p), _) if p.id == id => (p, false),
            _ => return self.answer_not_pending(store, id, value).await,
        };
        if !value.fits(pending.kind) {
            return AnswerReply::Refused(bad_value(id, pending.kind));
        }
        if reopened {
            return self.reanswer(store, &pending, value, who).await;
        }
        let latency_ms = pending.asked.elapsed().as_millis() as u64;
        let mut committed = pending.commit.lock().await;
        if let Some(stored) = *committed {
            return self.repeat(id, value, stored);
        }
        let outcome = match store
            .commit_answer(id, &self.id, value, who, latency_ms)
            .await
        {
            Ok(o) => o,
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing an answer failed: {e}");
                return refuse(
                    "store_failed",
                    "the answer could not be stored; try again".into(),
                );
            }
        };
        match outcome {
            CommitOutcome::Committed => {
                *committed = Some(value);
                self.deliver(
                    &pending,
                    value,
                    if who == "timeout" {
                        "expired"
                    } else {
                        "answered"
                    },
                );
                AnswerReply::Ack(value)
            }
            CommitOutcome::AlreadyAnswered(stored) => {
                *committed = Some(stored);
                self.repeat(id, value, stored)
            }
        }
    }

    /// The committed answer goes to the session thread; the other browsers see the query go.
    fn deliver(&self, pending: &Pending, value: AnswerValue, reason: &'static str) {
        let mut s = self.lock();
        if s.pending.as_ref().map(|p| p.id) == Some(pending.id) {
            s.pending = None;
            if s.status == Status::Waiting {
                s.status = Status::Running;
            }
        }
        s.remember(pending, value, reason);
        if let Some(control) = &s.control {
            let _ = control.send(Control::Answer {
                seq: pending.seq,
                value,
            });
        }
        drop(s);
        self.broadcast_message(&ServerMessage::Withdrawn {
            id: pending.id,
            reason,
        });
    }

    /// After `timeout` an open query (pending or reopened) counts as "no feedback" (a skipped
    /// pair), committed like any answer so that exactly one answer stands.
    pub fn expire_after(
        self: &Arc<Self>,
        store: Store,
        query_id: i64,
        timeout: std::time::Duration,
    ) {
        let live = self.clone();
        tokio::spawn(async move {
            tokio::time::sleep(timeout).await;
            let still_open = {
                let s = live.lock();
                [&s.pending, &s.reopened]
                    .iter()
                    .any(|p| p.as_ref().map(|p| p.id) == Some(query_id))
            };
            if still_open {
                let value = AnswerValue::timeout(live.kind);
                let _ = live.answer(&store, query_id, value, "timeout").await;
            }
        });
    }

    pub(super) fn repeat(&self, id: i64, value: AnswerValue, stored: AnswerValue) -> AnswerReply {
        if stored == value {
            AnswerReply::Ack(value)
        } else {
            AnswerReply::Refused(ProtocolError::new(
                "already_answered",
                format!(
                    "query {id} was already answered with {}",
                    serde_json::to_string(&stored).unwrap_or_default()
                ),
            ))
        }
    }

    /// An answer for a query that is not the open one: a repeat, someone else's, or nonsense.
    async fn answer_not_pending(&self, store: &Store, id: i64, value: AnswerValue) -> AnswerReply {
        let recent = self
            .lock()
            .recent
            .iter()
            .rev()
            .find(|(q, _)| *q == id)
            .map(|(_, v)| *v);
        if let Some(stored) = recent {
            return self.repeat(id, value, stored);
        }
        let refuse =
            |code, message: String| AnswerReply::Refused(ProtocolError::new(code, message));
        let query = match store.query(id).await {
            Ok(q) => q,
            Err(e) => {
                tracing::error!("looking up query {id}: {e}");
                return refuse(
                    "store_failed",
                    "the query could not be looked up; try again".into(),
                );
            }
        };
        match query {
            Some(q) if q.session_id == self.id => match store.answer_value(id).await {
                // Answered already (by this trainer, another one, or a timeout).
                Ok(Some(stored)) => self.repeat(id, value, stored),
                // Asked and not open: its session ended while it waited; a resume asks again.
                Ok(None) => refuse(
                    "expired",
                    format!("query {id} is no longer open; the session asks again when it resumes"),
                ),
                Err(e) => {
                    tracing::error!("looking up the answer to query {id}: {e}");
                    refuse(
                        "store_failed",
                        "the answer could not be looked up; try again".into(),
                    )
                }
            },
            _ => refuse(
                "unknown_query",
                format!("query {id} does not belong to this session"),
            ),
        }
    }
}
