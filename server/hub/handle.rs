//! How the rest of the server reaches a session: a [`SessionHandle`] sends [`Command`]s to the
//! session's owner task and reads the [`Snapshot`] the owner publishes. Nothing outside the
//! owner changes a session's live state.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use tokio::sync::{broadcast, mpsc, oneshot, watch};

use crate::protocol::{ProgressMessage, ProtocolError, QueryId};
use crate::session::{AnswerValue, SessionPlan};
use crate::sim::Geometry;
use crate::store::{Status, TrainerRef};

/// Who is on the other end of a socket (or a route): a researcher, a trainer on the session's
/// shared link without a name, or a named trainer.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Identity {
    Researcher,
    Anonymous,
    Trainer(TrainerRef),
}

impl Identity {
    /// The named trainer's id (none for the anonymous trainer and researchers).
    pub fn trainer_id(&self) -> Option<i64> {
        match self {
            Identity::Trainer(t) => Some(t.id),
            _ => None,
        }
    }

    pub fn trainer(&self) -> Option<&TrainerRef> {
        match self {
            Identity::Trainer(t) => Some(t),
            _ => None,
        }
    }
}

/// Commands a session's owner takes, each answered on its own channel.
#[derive(Debug)]
pub(super) enum Command {
    /// A browser joins: what it needs to catch up (the open queries `who` has not answered),
    /// and the broadcast from then on.
    Join {
        who: Identity,
        reply: oneshot::Sender<Joined>,
    },
    /// A trainer's answer to query `id`.
    Answer {
        id: QueryId,
        value: AnswerValue,
        who: Identity,
        reply: oneshot::Sender<AnswerReply>,
    },
    /// A trainer takes back the answer to query `id`.
    Undo {
        id: QueryId,
        who: Identity,
        reply: oneshot::Sender<Result<(), ProtocolError>>,
    },
    /// A browser on another server joins (PostgreSQL, `bus`): the owner sends that server the
    /// catch-up, then every broadcast after it, in order, until it leaves.
    RemoteJoin {
        who: Identity,
        server: String,
        req: u64,
    },
    /// That server has no browser of the session left.
    Leave { server: String },
    /// A researcher stops the session (queued or running).
    Stop(oneshot::Sender<()>),
    /// The server shuts down: checkpoint and end as interrupted.
    Shutdown,
    /// This server lost the session's lease (PostgreSQL: another server took it over, or the
    /// lease could not be renewed in time): end this copy without writing anything more.
    Lost,
}

/// What a joining browser gets: the messages that bring it up to date (progress, the open
/// queries, the end if it came), then everything broadcast after them, with nothing between.
#[derive(Debug)]
pub struct Joined {
    pub catch_up: Vec<Arc<str>>,
    pub broadcast: broadcast::Receiver<Arc<str>>,
}

/// What a trainer's answer got.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum AnswerReply {
    Ack(AnswerValue),
    Refused(ProtocolError),
}

/// The session's state as the owner last published it, for HTTP views and `hello`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Snapshot {
    pub status: Status,
    pub reason: Option<String>,
    pub progress: ProgressMessage,
    pub geometry: Option<Geometry>,
    /// The scene graph the running session phrases its queries in (a remote env's own task
    /// declares it when the session starts).
    pub graph: Option<crate::scene_graph::SceneGraph>,
}

impl Snapshot {
    /// Before anything ran: `status`, at `progress` of the plan's budget.
    pub(super) fn initial(plan: &SessionPlan, status: Status, progress: u64) -> Self {
        Self {
            status,
            reason: None,
            progress: ProgressMessage {
                progress,
                budget: plan.spec.budget,
                unit: plan.spec.method.budget_unit().into(),
                ..Default::default()
            },
            geometry: None,
            graph: None,
        }
    }
}

/// A live session, as the HTTP routes and sockets hold it. Cheap to clone.
#[derive(Clone, Debug)]
pub struct SessionHandle {
    pub id: Arc<str>,
    pub(super) commands: mpsc::UnboundedSender<Command>,
    pub(super) snapshot: watch::Receiver<Snapshot>,
    /// The session as it was launched or resumed (what the trainer's `hello` says).
    pub plan: Arc<SessionPlan>,
}

impl SessionHandle {
    pub fn snapshot(&self) -> Snapshot {
        self.snapshot.borrow().clone()
    }

    pub fn status(&self) -> Status {
        self.snapshot.borrow().status
    }

    /// Join the session's broadcast as `who` (`None`: the session has ended).
    pub async fn join(&self, who: &Identity) -> Option<Joined> {
        let (reply, answer) = oneshot::channel();
        let who = who.clone();
        self.commands.send(Command::Join { who, reply }).ok()?;
        answer.await.ok()
    }

    /// `who` answers query `id`; the reply comes after the answer is committed (or refused).
    pub async fn answer(&self, id: QueryId, value: AnswerValue, who: &Identity) -> AnswerReply {
        self.send_answer(id, value, who.clone())
            .await
            .unwrap_or(AnswerReply::Refused(ProtocolError::session_ended()))
    }

    /// Hand the owner an answer now; its reply comes on the returned channel (closed: the
    /// session has ended). Commands sent one after another reach the owner in that order.
    pub(super) fn send_answer(
        &self,
        id: QueryId,
        value: AnswerValue,
        who: Identity,
    ) -> oneshot::Receiver<AnswerReply> {
        let (reply, answer) = oneshot::channel();
        let _ = self.commands.send(Command::Answer {
            id,
            value,
            who,
            reply,
        });
        answer
    }

    /// `who` takes back the answer to query `id`.
    pub async fn undo(&self, id: QueryId, who: &Identity) -> Result<(), ProtocolError> {
        self.send_undo(id, who.clone())
            .await
            .map_err(|_| ProtocolError::session_ended())?
    }

    pub(super) fn send_undo(
        &self,
        id: QueryId,
        who: Identity,
    ) -> oneshot::Receiver<Result<(), ProtocolError>> {
        let (reply, answer) = oneshot::channel();
        let _ = self.commands.send(Command::Undo { id, who, reply });
        answer
    }

    /// Ask the owner to stop the session; `false` if it had already gone.
    pub(super) async fn stop(&self) -> bool {
        self.send_stop().await.is_ok()
    }

    pub(super) fn send_stop(&self) -> oneshot::Receiver<()> {
        let (reply, answer) = oneshot::channel();
        let _ = self.commands.send(Command::Stop(reply));
        answer
    }

    /// A browser on `server` joins as `who`; the owner replies to `req` through the bus.
    pub(super) fn remote_join(&self, who: Identity, server: String, req: u64) {
        let _ = self.commands.send(Command::RemoteJoin { who, server, req });
    }

    /// `server` has no browser of the session left.
    pub(super) fn leave(&self, server: String) {
        let _ = self.commands.send(Command::Leave { server });
    }

    pub(super) fn shutdown(&self) {
        let _ = self.commands.send(Command::Shutdown);
    }

    pub(super) fn lost(&self) {
        let _ = self.commands.send(Command::Lost);
    }
}
