//! The answer path, inside a session's owner: commit, then acknowledge, then tell the session
//! thread and the other browsers. Answers arrive one at a time through the owner's command
//! channel, so the first committed answer wins without locks. Also the deadlines ("no
//! feedback" after the answer timeout) and undo: a trainer takes back the latest answer within
//! [`UNDO_WINDOW`], the session is told (its learner drops the answer), and the query opens
//! again beside any query the session waits on; the new answer commits as the answer's next
//! revision. Only the trainer who gave an answer (or a researcher) may undo it. Sessions that
//! take several answers per query go through `votes` instead.

use tokio::time::Instant;

use super::handle::{AnswerReply, Identity};
use super::owner::{Open, Owner};
use crate::protocol::{ErrorCode, ProtocolError, QueryId, ServerMessage, WithdrawReason};
use crate::session::events::Revision;
use crate::session::{AnswerValue, Answerer, Control, QueryKind};
use crate::store::{CommitOutcome, ReanswerOutcome, Status, UndoOutcome};

/// How long after it was given an answer can be undone (the trainer page offers 6 s; the rest
/// is slack for a slow network).
pub const UNDO_WINDOW: std::time::Duration = std::time::Duration::from_secs(30);

/// The latest answer a trainer gave, while it can still be undone.
#[derive(Clone, Debug)]
pub(super) struct Undoable {
    pub query: Open,
    pub at: Instant,
    /// Who gave it.
    pub by: Identity,
}

/// A committed answer on its way to the session thread and the browsers.
pub(super) struct Delivery {
    pub open: Open,
    pub value: AnswerValue,
    pub reason: WithdrawReason,
    pub who: Identity,
}

pub(super) fn refuse(code: ErrorCode, message: impl Into<String>) -> AnswerReply {
    AnswerReply::Refused(ProtocolError::new(code, message))
}

/// The refusal for a value of the wrong kind.
pub(super) fn bad_value(id: QueryId, kind: QueryKind) -> ProtocolError {
    ProtocolError::new(
        ErrorCode::BadValue,
        format!(
            "query {id} is {}: answer {}",
            kind.as_str(),
            match kind {
                QueryKind::Evaluative => "1, 0 or -1",
                QueryKind::Preference => "\"left\", \"right\", \"equal\" or \"skip\"",
            }
        ),
    )
}

/// The reply to an answer for a query already answered with `stored`.
pub(super) fn repeat(id: QueryId, value: AnswerValue, stored: AnswerValue) -> AnswerReply {
    if stored == value {
        AnswerReply::Ack(value)
    } else {
        refuse(
            ErrorCode::AlreadyAnswered,
            format!(
                "query {id} was already answered with {}",
                serde_json::to_string(&stored).unwrap_or_default()
            ),
        )
    }
}

impl Owner {
    /// A trainer's answer to query `id`: the reply, and what to deliver once it is sent.
    pub(super) async fn answer(
        &mut self,
        id: QueryId,
        value: AnswerValue,
        who: Identity,
    ) -> (AnswerReply, Option<Delivery>) {
        if !self.status.is_active() {
            return (AnswerReply::Refused(ProtocolError::session_ended()), None);
        }
        if self.answers_per_query > 1 {
            return self.vote(id, value, who).await;
        }
        self.commit(id, value, Answerer::Trainer, who).await
    }

    /// Commit `value` for query `id` on behalf of `answerer` (a trainer, `who`, or the
    /// timeout).
    async fn commit(
        &mut self,
        id: QueryId,
        value: AnswerValue,
        answerer: Answerer,
        who: Identity,
    ) -> (AnswerReply, Option<Delivery>) {
        let (open, reopened) = match (&self.pending, &self.reopened) {
            (_, Some(p)) if p.id == id => (p.clone(), true),
            (Some(p), _) if p.id == id => (p.clone(), false),
            _ => return (self.answer_not_pending(id, value).await, None),
        };
        if !value.fits(self.kind) {
            return (AnswerReply::Refused(bad_value(id, self.kind)), None);
        }
        let reason = WithdrawReason::answered_by(answerer);
        let latency_ms = open.asked.elapsed().as_millis() as u64;
        if reopened {
            return (
                self.reanswer(open, value, answerer, who, latency_ms).await,
                None,
            );
        }
        match self
            .store
            .commit_answer(
                open.row,
                &self.id,
                value,
                answerer,
                who.trainer_id(),
                latency_ms,
            )
            .await
        {
            Ok(CommitOutcome::Committed) => (
                AnswerReply::Ack(value),
                Some(Delivery {
                    open,
                    value,
                    reason,
                    who,
                }),
            ),
            // Stored by an earlier run of this session: the session still waits for it.
            Ok(CommitOutcome::AlreadyAnswered(stored)) => (
                repeat(id, value, stored),
                Some(Delivery {
                    open,
                    value: stored,
                    reason,
                    who,
                }),
            ),
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing an answer failed: {e}");
                (
                    refuse(
                        ErrorCode::StoreFailed,
                        "the answer could not be stored; try again",
                    ),
                    None,
                )
            }
        }
    }

    /// The committed answer goes to the session thread; the other browsers see the query go.
    pub(super) async fn deliver(&mut self, d: Delivery) {
        let Delivery {
            open,
            value,
            reason,
            who,
        } = d;
        self.remember(&open, value, reason, who);
        if let Some(control) = &self.control {
            let _ = control.send(Control::Answer {
                seq: open.id,
                value,
            });
        }
        self.broadcast_message(&ServerMessage::Withdrawn {
            id: open.id,
            reason,
        });
        if self.pending.as_ref().is_some_and(|p| p.id == open.id) {
            self.pending = None;
            if self.status == Status::Waiting {
                self.set_status(Status::Running, None).await;
            }
        }
    }

    /// Every open query past its deadline counts as "no feedback" (a skipped pair), committed
    /// like any answer so that exactly one answer stands.
    pub(super) async fn expire_due(&mut self) {
        let now = Instant::now();
        let due: Vec<QueryId> = [&self.pending, &self.reopened]
            .into_iter()
            .flatten()
            .filter(|p| p.deadline <= now)
            .map(|p| p.id)
            .collect();
        for id in due {
            if self.answers_per_query > 1 {
                self.close_votes(id).await;
                continue;
            }
            let value = AnswerValue::timeout(self.kind);
            let (reply, delivery) = self
                .commit(id, value, Answerer::Timeout, Identity::Anonymous)
                .await;
            match (reply, delivery) {
                (_, Some(d)) => self.deliver(d).await,
                (AnswerReply::Refused(e), None) if e.code == ErrorCode::StoreFailed => {
                    // Try again shortly rather than leave the session waiting for ever.
                    for p in [&mut self.pending, &mut self.reopened]
                        .into_iter()
                        .flatten()
                    {
                        if p.id == id {
                            p.deadline = now + std::time::Duration::from_secs(1);
                        }
                    }
                }
                _ => {}
            }
        }
    }

    /// Answer a query reopened by an undo: committed as the answer's next revision, then the
    /// session relabels (or re-adds) it.
    async fn reanswer(
        &mut self,
        open: Open,
        value: AnswerValue,
        answerer: Answerer,
        who: Identity,
        latency_ms: u64,
    ) -> AnswerReply {
        let id = open.id;
        let revision = match self
            .store
            .reanswer(open.row, value, answerer, who.trainer_id(), latency_ms)
            .await
        {
            Ok(ReanswerOutcome::Committed(r)) => r,
            Ok(ReanswerOutcome::Stands(stored)) => {
                self.reopened = None;
                return repeat(id, value, stored);
            }
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing an answer again failed: {e}");
                return refuse(
                    ErrorCode::StoreFailed,
                    "the answer could not be stored; try again",
                );
            }
        };
        let reason = WithdrawReason::answered_by(answerer);
        self.reopened = None;
        self.remember(&open, value, reason, who);
        if let Some(control) = &self.control {
            let _ = control.send(Control::Revise(Revision {
                seq: id,
                revision,
                value: Some(value),
            }));
        }
        self.broadcast_message(&ServerMessage::Withdrawn { id, reason });
        // The query the session waits on comes back to pages that showed the reopened one.
        if let Some(text) = self.pending.as_ref().map(|p| p.text.clone()) {
            self.broadcast(text);
        }
        AnswerReply::Ack(value)
    }

    /// Take back the answer to `id`: allowed for the latest answer a trainer gave, within
    /// [`UNDO_WINDOW`], while the session runs, to the trainer who gave it (or a researcher).
    /// Every browser gets `undone` and the query again, which times out like any query.
    pub(super) async fn undo(&mut self, id: QueryId, who: &Identity) -> Result<(), ProtocolError> {
        let unavailable = |message: String| ProtocolError::new(ErrorCode::UndoUnavailable, message);
        if !self.status.is_active() {
            return Err(unavailable(
                "the session is not running; the answer stands".into(),
            ));
        }
        if self.answers_per_query > 1 {
            return Err(unavailable(
                "this session combines several trainers' answers; an answer stands once given"
                    .into(),
            ));
        }
        let undoable = match self.undoable.take() {
            Some(u) if u.query.id == id && *who != Identity::Researcher && u.by != *who => {
                self.undoable = Some(u);
                return Err(unavailable(format!(
                    "query {id} was answered by another trainer; only they can undo it"
                )));
            }
            Some(u) if u.query.id == id && u.at.elapsed() <= UNDO_WINDOW => u,
            Some(u) if u.query.id == id => {
                return Err(unavailable(format!(
                    "answers can be undone for {} s; this one stands",
                    UNDO_WINDOW.as_secs()
                )));
            }
            other => {
                self.undoable = other;
                return Err(unavailable(format!(
                    "only the latest answer a trainer gave can be undone; query {id}'s stands"
                )));
            }
        };
        let q = &undoable.query;
        let revision = match self
            .store
            .undo_answer(q.row, &self.id, self.kind, who.trainer_id())
            .await
        {
            Ok(UndoOutcome::Undone(r)) => r,
            Ok(UndoOutcome::NotAnswered | UndoOutcome::AlreadyUndone) => {
                return Err(unavailable(format!("query {id} has no answer to undo")));
            }
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing an undo failed: {e}");
                self.undoable = Some(undoable);
                return Err(ProtocolError::new(
                    ErrorCode::StoreFailed,
                    "the undo could not be stored; the answer stands; try again",
                ));
            }
        };
        let reopened = Open::new(id, q.row, q.text.clone(), self.answer_timeout);
        self.progress.answered = self.progress.answered.saturating_sub(1);
        self.recent.retain(|(q, _)| *q != id);
        self.reopened = Some(reopened.clone());
        if let Some(control) = &self.control {
            let _ = control.send(Control::Revise(Revision {
                seq: id,
                revision,
                value: None,
            }));
        }
        self.broadcast_message(&ServerMessage::Undone { id });
        self.broadcast(reopened.text);
        Ok(())
    }

    /// An answer for a query that is not open: a repeat, someone else's, or nonsense.
    async fn answer_not_pending(&self, id: QueryId, value: AnswerValue) -> AnswerReply {
        if let Some(stored) = self
            .recent
            .iter()
            .rev()
            .find(|(q, _)| *q == id)
            .map(|(_, v)| *v)
        {
            return repeat(id, value, stored);
        }
        let query = match self.store.query_by_number(&self.id, id).await {
            Ok(q) => q,
            Err(e) => {
                tracing::error!("looking up query {id}: {e}");
                return refuse(
                    ErrorCode::StoreFailed,
                    "the query could not be looked up; try again",
                );
            }
        };
        match query {
            Some(q) => match self.store.answer_value(q.id).await {
                // Answered already (by this trainer, another one, or a timeout).
                Ok(Some(stored)) => repeat(id, value, stored),
                // Asked and not open: its session ended while it waited; a resume asks again.
                Ok(None) => refuse(
                    ErrorCode::Expired,
                    format!("query {id} is no longer open; the session asks again when it resumes"),
                ),
                Err(e) => {
                    tracing::error!("looking up the answer to query {id}: {e}");
                    refuse(
                        ErrorCode::StoreFailed,
                        "the answer could not be looked up; try again",
                    )
                }
            },
            _ => refuse(
                ErrorCode::UnknownQuery,
                format!("query {id} does not belong to this session"),
            ),
        }
    }
}
