//! A session that runs on another server (PostgreSQL), as this server's sockets and routes
//! reach it: a relay task stands in for its owner behind an ordinary [`SessionHandle`], so the
//! websocket and the routes work the same whichever server runs the session. The relay sends
//! each command to the owner's server (`bus`) and hands back its reply; it keeps the owner's
//! latest snapshot and passes its broadcasts to the sockets here, in the order the owner made
//! them. A socket that joins gets the owner's catch-up and, from the relay's next message on,
//! the broadcast: the owner sends the catch-up and its later broadcasts in order, and the relay
//! takes both from one queue.
//!
//! A relay ends when its session ends (its `ended` came through), when the owner's server no
//! longer runs it (the owner said so, its lease ran out, or a reply did not come within
//! [`ASK_TIMEOUT`]), or when no socket has used it for [`IDLE`]. Its sockets then close
//! without `ended` and connect again, reaching the session wherever it runs next; an answer
//! in flight is refused as not taken (the trainer sends it again), never acknowledged unseen.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use tokio::sync::mpsc::{UnboundedReceiver, UnboundedSender, unbounded_channel};
use tokio::sync::{broadcast, oneshot, watch};
use tokio::time::{Instant, MissedTickBehavior};

use super::bus::{ASK_TIMEOUT, Ask, Envelope, Reply, ask};
use super::handle::{AnswerReply, Command, Identity, Joined, SessionHandle, Snapshot};
use super::{Hub, plan_of};
use crate::protocol::{ErrorCode, ProtocolError};
use crate::store::{SessionRow, Status};

/// How long a relay no socket uses stays up (a page that reloads finds it again).
const IDLE: Duration = Duration::from_secs(30);
/// How often a relay looks at its deadlines.
const TICK: Duration = Duration::from_millis(250);
/// Messages kept for a socket that falls behind (as the owner's broadcast keeps).
const BROADCAST_CAPACITY: usize = 256;

/// How a socket or a route reaches a session.
pub enum Reach {
    /// Its owner here, or a relay to the server that runs it.
    Live(SessionHandle),
    /// Active, but no server runs it at this moment (queued for a free slot, or its server
    /// stopped and another has not taken it over yet): try again shortly.
    Between,
    /// It does not run: its stored row says how it ended.
    NotRunning,
}

/// What the bus brings a relay.
pub(super) enum Inbound {
    Reply { req: u64, reply: Reply },
    Cast(String),
    Snapshot(Box<Snapshot>),
    Moved,
}

/// A relay as the hub keeps it.
pub(super) struct RelayEntry {
    handle: SessionHandle,
    inbox: UnboundedSender<Inbound>,
    /// The server the relay talks to.
    owner: String,
    /// Becomes true when the owner's first reply (its snapshot) came.
    ready: watch::Receiver<bool>,
}

/// What a command from here waits for.
enum Waiting {
    /// The relay's own first join: the snapshot.
    Ready,
    Join(oneshot::Sender<Joined>),
    Answer(oneshot::Sender<AnswerReply>),
    Undo(oneshot::Sender<Result<(), ProtocolError>>),
    Stop(oneshot::Sender<()>),
}

/// Why a relay ends.
#[derive(Debug, PartialEq)]
enum End {
    /// The session ended (`ended` came through).
    Ended,
    /// The owner's server no longer runs it, or does not answer.
    Moved,
    /// No socket used it for a while.
    Idle,
}

struct Relay {
    hub: Arc<Hub>,
    key: Arc<str>,
    id: String,
    owner: String,
    waiting: HashMap<u64, (Waiting, Instant)>,
    next_req: u64,
    broadcast: broadcast::Sender<Arc<str>>,
    snapshot: watch::Sender<Snapshot>,
    ready: watch::Sender<bool>,
    idle_since: Option<Instant>,
}

/// The refusal of an answer whose fate the owner's server did not confirm.
fn not_taken() -> ProtocolError {
    ProtocolError::new(
        ErrorCode::StoreFailed,
        "the server running this session did not confirm the answer, so it was not taken: send it again",
    )
}

impl Hub {
    /// The session as a socket or a route reaches it: its owner here, or (PostgreSQL) a relay
    /// to the server that holds its lease, made on first use and shared.
    pub async fn reach(self: &Arc<Self>, row: &SessionRow) -> Reach {
        if let Some(h) = self.owned(&row.id) {
            return Reach::Live(h);
        }
        if !self.store.is_shared() {
            return Reach::NotRunning;
        }
        let holder = match self
            .store
            .lease_holders(std::slice::from_ref(&row.id))
            .await
        {
            Ok(mut h) => h.pop(),
            Err(e) => {
                tracing::warn!(session = %row.id, "reading who runs it: {e}");
                return Reach::Between;
            }
        };
        let Some(holder) = holder.filter(|h| h.status.is_active()) else {
            return Reach::NotRunning;
        };
        // Claimed here meanwhile?
        if let Some(h) = self.owned(&row.id) {
            return Reach::Live(h);
        }
        let owner = match holder.owner {
            Some(o) if holder.live && o != self.server_id => o,
            _ => return Reach::Between,
        };
        let Some((handle, mut ready)) = self.relay_to(row, &owner) else {
            return Reach::Between;
        };
        match tokio::time::timeout(ASK_TIMEOUT, ready.wait_for(|r| *r)).await {
            Ok(Ok(_)) => Reach::Live(handle),
            _ => Reach::Between,
        }
    }

    /// The relay to `owner` for `row`'s session: the one there is, or a new one.
    fn relay_to(
        self: &Arc<Self>,
        row: &SessionRow,
        owner: &str,
    ) -> Option<(SessionHandle, watch::Receiver<bool>)> {
        let mut relays = self.relays.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(r) = relays.get(&row.id) {
            if r.owner == owner && !r.inbox.is_closed() {
                return Some((r.handle.clone(), r.ready.clone()));
            }
            let _ = r.inbox.send(Inbound::Moved);
        }
        let plan = match plan_of(row) {
            Ok(p) => Arc::new(p),
            Err(e) => {
                tracing::error!(session = %row.id, "{e}");
                return None;
            }
        };
        let (commands, commands_rx) = unbounded_channel();
        let (inbox, inbox_rx) = unbounded_channel();
        let (ready, ready_rx) = watch::channel(false);
        let progress = u64::try_from(row.progress).unwrap_or(0);
        let (snapshot, snapshot_rx) =
            watch::channel(Snapshot::initial(&plan, row.status, progress));
        let handle = SessionHandle {
            id: row.id.as_str().into(),
            commands,
            snapshot: snapshot_rx,
            plan,
        };
        let relay = Relay {
            hub: self.clone(),
            key: handle.id.clone(),
            id: row.id.clone(),
            owner: owner.to_owned(),
            waiting: HashMap::new(),
            next_req: 1,
            broadcast: broadcast::channel(BROADCAST_CAPACITY).0,
            snapshot,
            ready,
            idle_since: None,
        };
        relays.insert(
            row.id.clone(),
            RelayEntry {
                handle: handle.clone(),
                inbox,
                owner: owner.to_owned(),
                ready: ready_rx.clone(),
            },
        );
        tokio::spawn(relay.run(commands_rx, inbox_rx));
        Some((handle, ready_rx))
    }

    /// The relay of session `id`, if this server has one.
    pub(super) fn relay(&self, id: &str) -> Option<SessionHandle> {
        self.relays
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(id)
            .map(|r| r.handle.clone())
    }

    /// Hand an envelope to its session's relay; whether there was one.
    pub(super) fn to_relay(&self, session: &str, envelope: Envelope) -> bool {
        let inbound = match envelope {
            Envelope::Reply { req, reply, .. } => Inbound::Reply { req, reply },
            Envelope::Cast { text, .. } => Inbound::Cast(text),
            Envelope::Snapshot { snapshot, .. } => Inbound::Snapshot(snapshot),
            Envelope::Moved { .. } => Inbound::Moved,
            Envelope::Ask { .. } | Envelope::Stored { .. } => return false,
        };
        let relays = self.relays.lock().unwrap_or_else(|e| e.into_inner());
        relays
            .get(session)
            .is_some_and(|r| r.inbox.send(inbound).is_ok())
    }

    /// End the relays of `ids` (all of them for `None`): their sockets connect again.
    pub(super) fn relays_moved(&self, ids: Option<&[String]>) {
        let relays = self.relays.lock().unwrap_or_else(|e| e.into_inner());
        for (id, r) in relays.iter() {
            if ids.is_none_or(|ids| ids.contains(id)) {
                let _ = r.inbox.send(Inbound::Moved);
            }
        }
    }

    /// End the relays whose owner's lease ran out or went to another server (a killed server
    /// replies to nothing: this is how its relays learn it).
    pub(super) async fn check_relays(&self) {
        let relayed: Vec<(String, String)> = self
            .relays
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .map(|(id, r)| (id.clone(), r.owner.clone()))
            .collect();
        if relayed.is_empty() {
            return;
        }
        let ids: Vec<String> = relayed.iter().map(|(id, _)| id.clone()).collect();
        let holders = match self.store.lease_holders(&ids).await {
            Ok(h) => h,
            Err(e) => return tracing::warn!("reading who runs the relayed sessions: {e}"),
        };
        let gone: Vec<String> = relayed
            .into_iter()
            .filter(|(id, owner)| {
                !holders
                    .iter()
                    .any(|h| h.id == *id && h.live && h.owner.as_deref() == Some(owner))
            })
            .map(|(id, _)| id)
            .collect();
        if !gone.is_empty() {
            self.relays_moved(Some(&gone));
        }
    }

    /// Drop an ended relay from the map (unless a newer one replaced it).
    fn forget_relay(&self, key: &Arc<str>) {
        let mut relays = self.relays.lock().unwrap_or_else(|e| e.into_inner());
        if relays
            .get(&**key)
            .is_some_and(|r| Arc::ptr_eq(&r.handle.id, key))
        {
            relays.remove(&**key);
        }
    }
}

impl Relay {
    async fn run(
        mut self,
        mut commands: UnboundedReceiver<Command>,
        mut inbox: UnboundedReceiver<Inbound>,
    ) {
        self.ask(
            Ask::Join {
                who: Identity::Researcher,
            },
            Waiting::Ready,
        );
        let mut tick = tokio::time::interval(TICK);
        tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
        let end = loop {
            tokio::select! {
                Some(m) = inbox.recv() => if let Some(end) = self.inbound(m) {
                    break end;
                },
                command = commands.recv() => match command {
                    Some(c) => if let Some(end) = self.command(c) {
                        break end;
                    },
                    None => break End::Idle,
                },
                _ = tick.tick() => if let Some(end) = self.tick() {
                    break end;
                },
            }
        };
        self.end(end);
    }

    /// Send `what` to the owner's server; the reply is awaited as `waiting`.
    fn ask(&mut self, what: Ask, waiting: Waiting) {
        let req = self.next_req;
        self.next_req += 1;
        self.waiting
            .insert(req, (waiting, Instant::now() + ASK_TIMEOUT));
        self.hub
            .bus_send(&self.owner, ask(&self.id, &self.hub.server_id, req, what));
    }

    fn command(&mut self, command: Command) -> Option<End> {
        match command {
            Command::Join { who, reply } => self.ask(Ask::Join { who }, Waiting::Join(reply)),
            Command::Answer {
                id,
                value,
                who,
                reply,
            } => self.ask(Ask::Answer { id, value, who }, Waiting::Answer(reply)),
            Command::Undo { id, who, reply } => {
                self.ask(Ask::Undo { id, who }, Waiting::Undo(reply));
            }
            Command::Stop(reply) => self.ask(Ask::Stop, Waiting::Stop(reply)),
            // This server shuts down, or no longer should relay: its sockets go elsewhere.
            Command::Shutdown | Command::Lost => return Some(End::Moved),
            // Owners take these; nothing sends them to a relay.
            Command::RemoteJoin { .. } | Command::Leave { .. } => {}
        }
        None
    }

    fn inbound(&mut self, m: Inbound) -> Option<End> {
        match m {
            Inbound::Reply { req, reply } => self.replied(req, reply),
            Inbound::Cast(text) => {
                let ended = ended_status(&text);
                let _ = self.broadcast.send(text.into());
                ended.map(|status| {
                    self.snapshot.send_modify(|s| s.status = status);
                    End::Ended
                })
            }
            Inbound::Snapshot(s) => {
                self.snapshot.send_replace(*s);
                None
            }
            Inbound::Moved => Some(End::Moved),
        }
    }

    fn replied(&mut self, req: u64, reply: Reply) -> Option<End> {
        let Some((waiting, _)) = self.waiting.remove(&req) else {
            // Too late: its socket was told it was not taken.
            return None;
        };
        if let Reply::NotHere = reply {
            self.waiting.insert(req, (waiting, Instant::now()));
            return Some(End::Moved);
        }
        match (waiting, reply) {
            (Waiting::Ready, Reply::Joined { snapshot, .. }) => {
                self.snapshot.send_replace(*snapshot);
                let _ = self.ready.send(true);
            }
            (Waiting::Join(tx), Reply::Joined { catch_up, snapshot }) => {
                self.snapshot.send_replace(*snapshot);
                let _ = tx.send(Joined {
                    catch_up: catch_up.into_iter().map(Arc::from).collect(),
                    broadcast: self.broadcast.subscribe(),
                });
            }
            (Waiting::Answer(tx), Reply::Answer { reply }) => {
                let _ = tx.send(reply);
            }
            (Waiting::Undo(tx), Reply::Undo { result }) => {
                let _ = tx.send(result);
            }
            (Waiting::Stop(tx), Reply::Stopped) => {
                let _ = tx.send(());
            }
            (_, reply) => {
                tracing::error!(session = %self.id, req, "a reply of the wrong kind: {reply:?}");
            }
        }
        None
    }

    /// Deadlines and idleness.
    fn tick(&mut self) -> Option<End> {
        let now = Instant::now();
        if self.waiting.values().any(|(_, deadline)| *deadline <= now) {
            tracing::warn!(session = %self.id, owner = %self.owner, "the owner's server did not reply in time");
            return Some(End::Moved);
        }
        if self.broadcast.receiver_count() > 0 || !self.waiting.is_empty() {
            self.idle_since = None;
            return None;
        }
        let since = *self.idle_since.get_or_insert(now);
        (now - since >= IDLE).then_some(End::Idle)
    }

    fn end(mut self, end: End) {
        for (_, (waiting, _)) in self.waiting.drain() {
            match waiting {
                Waiting::Answer(tx) => {
                    let _ = tx.send(AnswerReply::Refused(not_taken()));
                }
                Waiting::Undo(tx) => {
                    let _ = tx.send(Err(not_taken()));
                }
                // Dropped: a join sees no session (its socket connects again, the status being
                // active), a stop sees it gone.
                Waiting::Ready | Waiting::Join(_) | Waiting::Stop(_) => {}
            }
        }
        if end != End::Ended {
            self.hub.bus_send(
                &self.owner,
                ask(&self.id, &self.hub.server_id, 0, Ask::Leave),
            );
        }
        self.hub.forget_relay(&self.key);
    }
}

/// The status in an `ended` message (every other message: `None`).
fn ended_status(text: &str) -> Option<Status> {
    if !text.starts_with(r#"{"type":"ended""#) {
        return None;
    }
    let v: serde_json::Value = serde_json::from_str(text).ok()?;
    serde_json::from_value(v.get("status")?.clone()).ok()
}
