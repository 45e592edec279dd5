//! A session's owner: one tokio task per session that alone holds its live state. It waits for
//! a slot while queued, starts the session thread, and then takes, in one `select!`, the
//! thread's events, the commands of sockets and routes (answers, undos, joins, stop) and the
//! answer deadlines. Status changes go through [`Owner::set_status`], which writes the database
//! and the published snapshot together.

use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::mpsc::Sender;
use std::time::Duration;

use tokio::sync::mpsc::{UnboundedReceiver, UnboundedSender};
use tokio::sync::{broadcast, watch};
use tokio::time::Instant;

use super::Hub;
use super::answers::Undoable;
use super::bus::{self, Envelope, Reply};
use super::episode_frames::EpisodeFrames;
use super::handle::{Command, Identity, Joined, SessionHandle, Snapshot};
use crate::protocol::{ProgressMessage, QueryId, QueryKind, ServerMessage, WithdrawReason};
use crate::session::{AnswerValue, Control, Ending, SessionEvent, SessionPlan};
use crate::settings::Combine;
use crate::sim::Geometry;
use crate::store::{Status, Store, SyntheticAnswer, TrainerRef};

/// Messages kept for a browser that falls behind before it must catch up again.
const BROADCAST_CAPACITY: usize = 256;
/// Returns kept for the trainer's live curve.
const RECENT_RETURNS: usize = 50;
/// Answers kept in memory after their query closed, so repeats need no database read.
const RECENT_ANSWERS: usize = 256;

/// A query open for answers.
#[derive(Clone, Debug)]
pub(super) struct Open {
    /// The session's query number: the query's id on the wire.
    pub id: QueryId,
    /// Its row in the database's `queries` table.
    pub row: i64,
    /// The query message, serialised once for every browser.
    pub text: Arc<str>,
    pub asked: Instant,
    pub deadline: Instant,
    /// The named trainers' own answers so far (sessions that take several per query).
    pub votes: Vec<(TrainerRef, AnswerValue)>,
}

impl Open {
    pub fn new(id: QueryId, row: i64, text: Arc<str>, timeout: Duration) -> Self {
        let asked = Instant::now();
        Self {
            id,
            row,
            text,
            asked,
            deadline: asked + timeout,
            votes: Vec::new(),
        }
    }

    /// Whether the named trainer `who` has answered it.
    pub fn answered_by(&self, who: &Identity) -> bool {
        who.trainer()
            .is_some_and(|t| self.votes.iter().any(|(v, _)| v.id == t.id))
    }
}

pub(super) struct Owner {
    pub hub: Arc<Hub>,
    /// The handle's id: the hub's map forgets a session only under the owner that put it there.
    key: Arc<str>,
    pub store: Store,
    pub id: String,
    /// The session, read and checked when it was launched or resumed.
    pub plan: Arc<SessionPlan>,
    pub kind: QueryKind,
    pub answer_timeout: Duration,
    /// Answers each query takes from different named trainers (1: the first one wins).
    pub answers_per_query: usize,
    /// How they combine.
    pub combine: Combine,
    pub status: Status,
    pub reason: Option<String>,
    pub progress: ProgressMessage,
    pub geometry: Option<Geometry>,
    /// The session's scene graph, once its thread started.
    pub graph: Option<crate::scene_graph::SceneGraph>,
    /// The query the session thread waits on.
    pub pending: Option<Open>,
    /// A query open again after an undo (the session may meanwhile wait on `pending`).
    pub reopened: Option<Open>,
    /// The latest committed answers, newest last.
    pub recent: VecDeque<(QueryId, AnswerValue)>,
    /// The latest answer a trainer gave (not a timeout's), until undone or too old.
    pub undoable: Option<Undoable>,
    /// The session thread's controls, while it runs.
    pub control: Option<Sender<Control>>,
    broadcast: broadcast::Sender<Arc<str>>,
    snapshot: watch::Sender<Snapshot>,
    /// Synthetic answers waiting to be stored in one transaction.
    pub batch: Vec<SyntheticAnswer>,
    pub stored_progress_at: std::time::Instant,
    /// Steps or queries the session had done before this start (a resume): what it reports
    /// until its run is past them again (a replay of stored answers, or a remote session's run
    /// resumed from an earlier checkpoint, counts up from below).
    pub resumed_at: u64,
    /// The running episode's frames, written to the data dir when it ends (for replay).
    pub episode_frames: EpisodeFrames,
    pub ending: Ending,
    /// The other servers whose sockets joined (PostgreSQL): they get every broadcast and
    /// snapshot too, through the bus, until they leave.
    remote: Vec<String>,
}

impl Owner {
    /// A queued session's owner and the handle to reach it; `resumed_at`: the progress the
    /// session had stored (0 for a new one).
    pub fn new(
        hub: Arc<Hub>,
        id: String,
        plan: SessionPlan,
        answer_timeout: Duration,
        resumed_at: u64,
    ) -> (Self, SessionHandle, UnboundedReceiver<Command>) {
        let plan = Arc::new(plan);
        let (answers_per_query, combine) = (plan.settings.answers_per_query, plan.settings.combine);
        let initial = Snapshot::initial(&plan, Status::Queued, resumed_at);
        let progress = initial.progress.clone();
        let (snapshot, snapshot_rx) = watch::channel(initial);
        let (commands, commands_rx): (UnboundedSender<Command>, _) =
            tokio::sync::mpsc::unbounded_channel();
        let (broadcast, _) = broadcast::channel(BROADCAST_CAPACITY);
        let handle = SessionHandle {
            id: id.as_str().into(),
            commands,
            snapshot: snapshot_rx,
            plan: plan.clone(),
        };
        let owner = Self {
            key: handle.id.clone(),
            store: hub.store.clone(),
            hub,
            kind: plan.kind,
            id,
            plan,
            answer_timeout,
            answers_per_query,
            combine,
            status: Status::Queued,
            reason: None,
            progress,
            geometry: None,
            graph: None,
            pending: None,
            reopened: None,
            recent: VecDeque::new(),
            undoable: None,
            control: None,
            broadcast,
            snapshot,
            batch: Vec::new(),
            stored_progress_at: std::time::Instant::now(),
            resumed_at,
            episode_frames: EpisodeFrames::default(),
            ending: Ending::Failed("the session thread ended without a word".into()),
            remote: Vec::new(),
        };
        (owner, handle, commands_rx)
    }

    /// The session's whole life: queued, running, ended.
    pub async fn run(mut self, mut commands: UnboundedReceiver<Command>) {
        let slots = self.hub.slots.clone();
        let _slot = loop {
            tokio::select! {
                slot = slots.clone().acquire_owned() => match slot {
                    Ok(slot) => break slot,
                    // The hub shuts down: the session stays queued for the next start.
                    Err(_) => return self.forget(),
                },
                command = commands.recv() => match command {
                    Some(Command::Stop(reply)) => {
                        self.set_status(Status::Stopped, Some("stopped while queued".into())).await;
                        let _ = reply.send(());
                        return self.forget();
                    }
                    // Another server has it now: it was never started here.
                    Some(Command::Lost) => return self.forget(),
                    Some(command) => self.command(command).await,
                    None => return,
                },
            }
        };
        match self.start_thread().await {
            Ok(events) => self.serve(events, commands).await,
            Err(e) => {
                tracing::error!(session = %self.id, "{e}");
                self.set_status(Status::Failed, Some(e.to_string())).await;
                self.broadcast_ended();
                self.forget();
            }
        }
    }

    /// While the session thread runs: its events, the commands and the answer deadlines, in
    /// one loop, until the thread's channel closes; then the end is stored.
    pub async fn serve(
        mut self,
        mut events: UnboundedReceiver<SessionEvent>,
        mut commands: UnboundedReceiver<Command>,
    ) {
        loop {
            let deadline = self.next_deadline();
            tokio::select! {
                event = events.recv() => match event {
                    Some(event) => self.apply(event, events.is_empty()).await,
                    None => break,
                },
                Some(command) = commands.recv() => match command {
                    Command::Lost => return self.lose(events).await,
                    command => self.command(command).await,
                },
                () = sleep_until(deadline), if deadline.is_some() => self.expire_due().await,
            }
        }
        self.finish().await;
    }

    /// The lease is gone (PostgreSQL): another server runs the session from its stored state.
    /// The thread is told to end, and its events are drained unapplied: this copy writes
    /// nothing more, neither answers nor checkpoints nor its end. Browsers here hear no
    /// `ended` (the session goes on): their sockets close and connect again, reaching the next
    /// owner; other servers' relays hear `moved` and do the same.
    async fn lose(mut self, mut events: UnboundedReceiver<SessionEvent>) {
        tracing::warn!(session = %self.id, "lease lost: another server runs this session now");
        if let Some(control) = self.control.take() {
            let _ = control.send(Control::Shutdown);
        }
        self.batch.clear();
        self.pending = None;
        self.reopened = None;
        for server in std::mem::take(&mut self.remote) {
            self.hub.bus_send(
                &server,
                Envelope::Moved {
                    session: self.id.clone(),
                },
            );
        }
        self.forget();
        while events.recv().await.is_some() {}
    }

    async fn command(&mut self, command: Command) {
        match command {
            Command::Join { who, reply } => {
                let _ = reply.send(self.join(&who));
            }
            Command::RemoteJoin { who, server, req } => {
                let catch_up = self.join(&who).catch_up;
                let joined = Reply::Joined {
                    catch_up: catch_up.iter().map(|m| m.to_string()).collect(),
                    snapshot: Box::new(self.snapshot.borrow().clone()),
                };
                self.hub
                    .bus_send(&server, bus::reply(&self.id, req, joined));
                if !self.remote.contains(&server) {
                    self.remote.push(server);
                }
            }
            Command::Leave { server } => self.remote.retain(|s| *s != server),
            Command::Answer {
                id,
                value,
                who,
                reply,
            } => {
                let (answer, delivery) = self.answer(id, value, who).await;
                // Acknowledged once committed; the session and the other browsers hear after.
                let _ = reply.send(answer);
                if let Some(delivery) = delivery {
                    self.deliver(delivery).await;
                }
            }
            Command::Undo { id, who, reply } => {
                let _ = reply.send(self.undo(id, &who).await);
            }
            Command::Stop(reply) => {
                if let Some(control) = &self.control {
                    let _ = control.send(Control::Stop);
                }
                let _ = reply.send(());
            }
            Command::Shutdown => {
                if let Some(control) = &self.control {
                    let _ = control.send(Control::Shutdown);
                }
            }
            // Taken in `run` and `serve`, where the owner can end.
            Command::Lost => {}
        }
    }

    /// The one place a status changes: in the database, then in the published snapshot.
    ///
    /// `waiting` is `running` with a query open: it flips twice per query, so only memory holds
    /// it (the API reads a live session's status from the snapshot) and the database keeps
    /// `running`. Writing every flip put two writes per query on the one SQLite writer, ahead
    /// of the answers' commits, and tripled the loadtest's p99 ack latency.
    pub async fn set_status(&mut self, status: Status, reason: Option<String>) {
        let live_only = |s: Status| matches!(s, Status::Running | Status::Waiting);
        let stored_already = live_only(status) && live_only(self.status) && reason == self.reason;
        if !stored_already
            && let Err(e) = self
                .store
                .set_status(&self.id, status.stored(), reason.as_deref())
                .await
        {
            tracing::error!(session = %self.id, "storing status {}: {e}", status.as_str());
        }
        self.status = status;
        self.reason = reason;
        self.publish();
    }

    /// Publish the state HTTP views and joining sockets read.
    pub fn publish(&self) {
        let snapshot = Snapshot {
            status: self.status,
            reason: self.reason.clone(),
            progress: self.progress.clone(),
            geometry: self.geometry.clone(),
            graph: self.graph,
        };
        for server in &self.remote {
            self.hub.bus_send(
                server,
                Envelope::Snapshot {
                    session: self.id.clone(),
                    snapshot: Box::new(snapshot.clone()),
                },
            );
        }
        self.snapshot.send_replace(snapshot);
    }

    /// Send to every connected browser (none connected is fine), here and on the servers
    /// whose sockets joined.
    pub fn broadcast(&self, text: Arc<str>) {
        for server in &self.remote {
            self.hub.bus_send(
                server,
                Envelope::Cast {
                    session: self.id.clone(),
                    from: self.hub.server_id.clone(),
                    text: text.to_string(),
                },
            );
        }
        let _ = self.broadcast.send(text);
    }

    pub fn broadcast_message(&self, m: &ServerMessage) {
        self.broadcast(m.to_text().into());
    }

    pub fn broadcast_progress(&self) {
        self.broadcast_message(&ServerMessage::Progress(self.progress.clone()));
    }

    fn broadcast_ended(&self) {
        self.broadcast_message(&ServerMessage::Ended {
            status: self.status,
            reason: self.reason.clone(),
        });
    }

    /// What a joining browser gets after `hello`: the progress, the open queries (with their
    /// time left) that `who` has not answered yet, and the end if it came.
    fn join(&self, who: &Identity) -> Joined {
        let broadcast = self.broadcast.subscribe();
        let mut catch_up: Vec<Arc<str>> = vec![
            ServerMessage::Progress(self.progress.clone())
                .to_text()
                .into(),
        ];
        if let Some(p) = self.pending.as_ref().filter(|p| !p.answered_by(who)) {
            catch_up.push(p.text.clone());
        }
        // Last, so that a page showing one query at a time shows the one the trainer reopened.
        if let Some(p) = &self.reopened {
            catch_up.push(p.text.clone());
        }
        if !self.status.is_active() {
            catch_up.push(
                ServerMessage::Ended {
                    status: self.status,
                    reason: self.reason.clone(),
                }
                .to_text()
                .into(),
            );
        }
        Joined {
            catch_up,
            broadcast,
        }
    }

    pub fn push_return(&mut self, r: f64) {
        let returns = &mut self.progress.recent_returns;
        returns.push(r);
        if returns.len() > RECENT_RETURNS {
            returns.remove(0);
        }
    }

    /// A committed answer to query `open`: counted, kept for repeats, and undoable if a
    /// trainer (`who`) gave it.
    pub fn remember(
        &mut self,
        open: &Open,
        value: AnswerValue,
        reason: WithdrawReason,
        who: Identity,
    ) {
        self.progress.answered += 1;
        if self.recent.len() == RECENT_ANSWERS {
            self.recent.pop_front();
        }
        self.recent.push_back((open.id, value));
        // Several trainers' combined answers stand (no undo).
        if reason == WithdrawReason::Answered && self.answers_per_query == 1 {
            self.undoable = Some(Undoable {
                query: open.clone(),
                at: Instant::now(),
                by: who,
            });
        }
    }

    /// The session thread is done: store the final state and tell the browsers.
    async fn finish(&mut self) {
        if let Err(e) = self.flush().await {
            tracing::error!(session = %self.id, "storing synthetic answers failed: {e}");
        }
        let (status, reason) = match std::mem::replace(&mut self.ending, Ending::Finished) {
            Ending::Finished => (Status::Finished, None),
            Ending::Stopped => (Status::Stopped, None),
            Ending::Interrupted => (
                Status::Interrupted,
                Some("the server shut down".to_string()),
            ),
            Ending::Failed(r) => (Status::Failed, Some(r)),
        };
        self.control = None;
        self.undoable = None;
        // A reopened query stays undone: its answer stands as "no feedback" (or a skip).
        let open = [self.pending.take(), self.reopened.take()];
        let latest = serde_json::to_value(&self.progress).unwrap_or_default();
        if let Err(e) = self
            .store
            .set_progress(&self.id, self.progress.progress, &latest)
            .await
        {
            tracing::error!(session = %self.id, "storing progress: {e}");
        }
        self.set_status(status, reason).await;
        for p in open.into_iter().flatten() {
            self.broadcast_message(&ServerMessage::Withdrawn {
                id: p.id,
                reason: WithdrawReason::Ended,
            });
        }
        self.broadcast_progress();
        self.broadcast_ended();
        tracing::info!(session = %self.id, status = status.as_str(), "session ended");
        self.forget();
    }

    /// From here the store has the final state: the hub lets go of the session (connected
    /// sockets see their commands refused and the broadcast close).
    fn forget(&self) {
        self.hub.forget(&self.key);
    }

    /// The earliest answer deadline of the open queries.
    fn next_deadline(&self) -> Option<Instant> {
        [&self.pending, &self.reopened]
            .into_iter()
            .flatten()
            .map(|p| p.deadline)
            .min()
    }
}

async fn sleep_until(deadline: Option<Instant>) {
    match deadline {
        Some(d) => tokio::time::sleep_until(d).await,
        None => std::future::pending().await,
    }
}
