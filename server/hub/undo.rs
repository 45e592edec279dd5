//! Undo: a trainer takes back the latest answer within [`UNDO_WINDOW`]. The undo commits, the
//! session is told (its learner drops the answer), and the query opens again beside any query
//! the session waits on; the new answer commits as the answer's next revision.

use std::sync::Arc;
use std::time::Instant;

use super::live::{AnswerReply, Live, Pending};
use crate::session::events::Revision;
use crate::session::{AnswerValue, Control};
use crate::store::{ReanswerOutcome, Store, UndoOutcome};
use crate::ws::protocol::{ProtocolError, ServerMessage};

/// How long after it was given an answer can be undone (the trainer page offers 6 s; the rest
/// is slack for a slow network).
pub const UNDO_WINDOW: std::time::Duration = std::time::Duration::from_secs(30);

/// The latest answer a trainer gave, while it can still be undone.
#[derive(Clone, Debug)]
pub struct Undoable {
    pub query: Pending,
    pub at: Instant,
}

impl Live {
    /// Answer a query reopened by an undo: committed as the answer's next revision, then the
    /// session relabels (or re-adds) it.
    pub(super) async fn reanswer(
        &self,
        store: &Store,
        reopened: &Pending,
        value: AnswerValue,
        who: &str,
    ) -> AnswerReply {
        let id = reopened.id;
        let mut committed = reopened.commit.lock().await;
        if let Some(stored) = *committed {
            return self.repeat(id, value, stored);
        }
        let latency_ms = reopened.asked.elapsed().as_millis() as u64;
        let revision = match store.reanswer(id, value, who, latency_ms).await {
            Ok(ReanswerOutcome::Committed(r)) => r,
            Ok(ReanswerOutcome::Stands(stored)) => {
                *committed = Some(stored);
                return self.repeat(id, value, stored);
            }
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing an answer again failed: {e}");
                return AnswerReply::Refused(ProtocolError::new(
                    "store_failed",
                    "the answer could not be stored; try again",
                ));
            }
        };
        *committed = Some(value);
        let reason = if who == "timeout" {
            "expired"
        } else {
            "answered"
        };
        let still_pending = {
            let mut s = self.lock();
            if s.reopened.as_ref().map(|p| p.id) == Some(id) {
                s.reopened = None;
            }
            s.remember(reopened, value, reason);
            if let Some(control) = &s.control {
                let _ = control.send(Control::Revise(Revision {
                    seq: reopened.seq,
                    revision,
                    value: Some(value),
                }));
            }
            s.pending.as_ref().map(|p| p.text.clone())
        };
        self.broadcast_message(&ServerMessage::Withdrawn { id, reason });
        // The query the session waits on comes back to pages that showed the reopened one.
        if let Some(text) = still_pending {
            self.broadcast(text);
        }
        AnswerReply::Ack(value)
    }

    /// Take back the answer to `id`: allowed for the latest answer a trainer gave, within
    /// [`UNDO_WINDOW`], while the session runs. Every browser gets `undone` and the query
    /// again, which times out like any query.
    pub async fn undo(self: &Arc<Self>, store: &Store, id: i64) -> Result<(), ProtocolError> {
        let unavailable = |message: String| ProtocolError::new("undo_unavailable", message);
        // Taken out while the undo commits, so two trainers cannot undo the same answer twice.
        let undoable = {
            let mut s = self.lock();
            if !s.status.is_active() {
                return Err(unavailable(
                    "the session is not running; the answer stands".into(),
                ));
            }
            match s.undoable.take() {
                Some(u) if u.query.id == id && u.at.elapsed() <= UNDO_WINDOW => u,
                Some(u) if u.query.id == id => {
                    return Err(unavailable(format!(
                        "answers can be undone for {} s; this one stands",
                        UNDO_WINDOW.as_secs()
                    )));
                }
                other => {
                    s.undoable = other;
                    return Err(unavailable(format!(
                        "only the latest answer a trainer gave can be undone; query {id}'s stands"
                    )));
                }
            }
        };
        let q = &undoable.query;
        let revision = match store.undo_answer(id, &self.id, q.kind).await {
            Ok(UndoOutcome::Undone(r)) => r,
            Ok(UndoOutcome::NotAnswered | UndoOutcome::AlreadyUndone) => {
                return Err(unavailable(format!("query {id} has no answer to undo")));
            }
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing an undo failed: {e}");
                self.lock().undoable.get_or_insert(undoable);
                return Err(ProtocolError::new(
                    "store_failed",
                    "the undo could not be stored; the answer stands; try again",
                ));
            }
        };
        let reopened = Pending::new(
            id,
            q.seq,
            q.kind,
            q.text.clone(),
            Instant::now(),
            self.answer_timeout,
        );
        {
            let mut s = self.lock();
            s.progress.answered = s.progress.answered.saturating_sub(1);
            s.recent.retain(|(q, _)| *q != id);
            s.reopened = Some(reopened.clone());
            if let Some(control) = &s.control {
                let _ = control.send(Control::Revise(Revision {
                    seq: q.seq,
                    revision,
                    value: None,
                }));
            }
        }
        self.broadcast_message(&ServerMessage::Undone { id });
        self.broadcast(reopened.text.clone());
        self.expire_after(store.clone(), id, self.answer_timeout);
        Ok(())
    }
}
