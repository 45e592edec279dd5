//! Several answers per query (`answers_per_query` = k > 1), inside a session's owner: each
//! named trainer's own answer is committed as it comes (and acknowledged after its commit);
//! once k trainers have answered, or the answer timeout passes with fewer, their answers
//! combine by the session's rule (`session::combine`) into the one answer the learner takes,
//! committed like any answer and delivered to the session thread. A trainer answers a query
//! once; combined answers stand (no undo).

use super::answers::{Delivery, bad_value, refuse, repeat};
use super::handle::{AnswerReply, Identity};
use super::owner::{Open, Owner};
use crate::protocol::{ErrorCode, QueryId, WithdrawReason};
use crate::session::{AnswerValue, Answerer};
use crate::store::{CommitOutcome, TrainerRef, VoteOutcome};

fn store_failed() -> AnswerReply {
    refuse(
        ErrorCode::StoreFailed,
        "the answer could not be stored; try again",
    )
}

impl Owner {
    /// `who`'s own answer to query `id`: the reply, and the combined answer to deliver once
    /// the k-th trainer has answered.
    pub(super) async fn vote(
        &mut self,
        id: QueryId,
        value: AnswerValue,
        who: Identity,
    ) -> (AnswerReply, Option<Delivery>) {
        let Identity::Trainer(trainer) = &who else {
            return (
                refuse(
                    ErrorCode::IdentityRequired,
                    format!(
                        "this session takes {} answers per query from named trainers: open your own trainer link, or join with your name",
                        self.answers_per_query
                    ),
                ),
                None,
            );
        };
        let Some(open) = self.pending.as_ref().filter(|p| p.id == id).cloned() else {
            return (self.vote_not_open(id, value, trainer).await, None);
        };
        if !value.fits(self.kind) {
            return (AnswerReply::Refused(bad_value(id, self.kind)), None);
        }
        if let Some((_, stored)) = open.votes.iter().find(|(t, _)| t.id == trainer.id) {
            return (repeat(id, value, *stored), None);
        }
        let latency_ms = open.asked.elapsed().as_millis() as u64;
        let outcome = self
            .store
            .commit_vote(open.row, &self.id, trainer.id, value, latency_ms)
            .await;
        let (reply, stored) = match outcome {
            Ok(VoteOutcome::Committed) => (AnswerReply::Ack(value), value),
            // Stored by an earlier run of this session.
            Ok(VoteOutcome::AlreadyAnswered(stored)) => (repeat(id, value, stored), stored),
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing an answer failed: {e}");
                return (store_failed(), None);
            }
        };
        let Some(pending) = self.pending.as_mut() else {
            return (reply, None);
        };
        pending.votes.push((trainer.clone(), stored));
        if pending.votes.len() < self.answers_per_query {
            return (reply, None);
        }
        let open = pending.clone();
        match self.combined(open).await {
            Ok(delivery) => (reply, Some(delivery)),
            Err(e) => {
                // The trainer's own answer is stored; the deadline combines them again.
                tracing::error!(session = %self.id, query = id, "storing a combined answer failed: {e}");
                (reply, None)
            }
        }
    }

    /// The answers given to `open` so far, combined and committed as its answer (none given:
    /// the timeout's "no feedback" or skip).
    pub(super) async fn combined(&mut self, open: Open) -> Result<Delivery, sqlx::Error> {
        let values: Vec<AnswerValue> = open.votes.iter().map(|(_, v)| *v).collect();
        let answerer = if values.is_empty() {
            Answerer::Timeout
        } else {
            Answerer::Trainers
        };
        let value = self.combine.combine(self.kind, &values);
        let latency_ms = open.asked.elapsed().as_millis() as u64;
        let outcome = self
            .store
            .commit_answer(open.row, &self.id, value, answerer, None, latency_ms)
            .await?;
        let value = match outcome {
            CommitOutcome::Committed => value,
            CommitOutcome::AlreadyAnswered(stored) => stored,
        };
        Ok(Delivery {
            open,
            value,
            reason: WithdrawReason::answered_by(answerer),
            who: Identity::Anonymous,
        })
    }

    /// Query `id`'s deadline passed: the answers given so far combine into its answer.
    pub(super) async fn close_votes(&mut self, id: QueryId) {
        let Some(open) = self.pending.as_ref().filter(|p| p.id == id).cloned() else {
            return;
        };
        match self.combined(open).await {
            Ok(delivery) => self.deliver(delivery).await,
            Err(e) => {
                tracing::error!(session = %self.id, query = id, "storing a combined answer failed: {e}");
                // Try again shortly rather than leave the session waiting for ever.
                if let Some(p) = self.pending.as_mut() {
                    p.deadline = tokio::time::Instant::now() + std::time::Duration::from_secs(1);
                }
            }
        }
    }

    /// A query asked again (a resumed session) already holds some trainers' answers: they
    /// count, and if k have answered it closes at once.
    pub(super) async fn restore_votes(&mut self, votes: Vec<(TrainerRef, AnswerValue)>) {
        let Some(pending) = self.pending.as_mut() else {
            return;
        };
        pending.votes = votes;
        if pending.votes.len() >= self.answers_per_query {
            let id = pending.id;
            self.close_votes(id).await;
        }
    }

    /// An answer from `trainer` to a query that is not open.
    async fn vote_not_open(
        &self,
        id: QueryId,
        value: AnswerValue,
        trainer: &TrainerRef,
    ) -> AnswerReply {
        let query = match self.store.query_by_number(&self.id, id).await {
            Ok(Some(q)) => q,
            Ok(None) => {
                return refuse(
                    ErrorCode::UnknownQuery,
                    format!("query {id} does not belong to this session"),
                );
            }
            Err(e) => {
                tracing::error!("looking up query {id}: {e}");
                return store_failed();
            }
        };
        let (votes, combined) = match (
            self.store.query_votes(query.id).await,
            self.store.answer_value(query.id).await,
        ) {
            (Ok(v), Ok(a)) => (v, a),
            (Err(e), _) | (_, Err(e)) => {
                tracing::error!("looking up the answers to query {id}: {e}");
                return store_failed();
            }
        };
        if let Some((_, stored)) = votes.iter().find(|(t, _)| t.id == trainer.id) {
            return repeat(id, value, *stored);
        }
        match combined {
            Some(_) => refuse(
                ErrorCode::AlreadyAnswered,
                format!(
                    "query {id} has had its {} answers (or its time ran out) without yours",
                    self.answers_per_query
                ),
            ),
            None => refuse(
                ErrorCode::Expired,
                format!("query {id} is no longer open; the session asks again when it resumes"),
            ),
        }
    }
}
