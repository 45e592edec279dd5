//! Servers on one PostgreSQL talk through it (docs/serving-several.md): a trainer's socket or a
//! researcher's request may reach any server, and the session it names runs on one of them.
//! The server that holds the socket keeps a relay (`relay`) in place of the session's owner;
//! the relay's commands (join, answer, undo, stop) go to the owner's server as [`Envelope::Ask`],
//! the owner's replies come back as [`Envelope::Reply`], and the owner sends every server that
//! joined its broadcasts ([`Envelope::Cast`]) and snapshots, in the order it makes them.
//!
//! The transport is LISTEN/NOTIFY: each server listens on `dualrep_<its id>` and sends on one
//! connection of its own, one task, so that what it sends another server arrives in order
//! (PostgreSQL delivers one connection's notifications in commit order). Messages waiting to go
//! to one server leave together in one notification (a JSON array) up to PostgreSQL's payload
//! limit; a single message above it is kept in `relay_bodies` and named.
//!
//! Nothing here is durable, and nothing needs to be: an answer is acknowledged only after the
//! owner committed it and its reply came back, so a notification lost with a server (or a
//! connection) costs an unacknowledged answer that the trainer sends again, never a lost one.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

use serde::{Deserialize, Serialize};
use tokio::sync::mpsc::{UnboundedReceiver, UnboundedSender, unbounded_channel};

use super::Hub;
use super::handle::{AnswerReply, Identity, Snapshot};
use crate::protocol::{ProtocolError, QueryId};
use crate::session::AnswerValue;
use crate::store::{Notifier, Store};

/// How long a relay waits for the owner's server to reply before it tells its socket that
/// the command was not taken.
pub const ASK_TIMEOUT: Duration = Duration::from_secs(5);
/// PostgreSQL refuses NOTIFY payloads of 8000 bytes or more.
const PAYLOAD_LIMIT: usize = 7900;
/// Messages a sender takes from its queue before it sends them.
const BATCH: usize = 1024;
/// How often the sender drops the kept bodies that are old.
const FORGET_BODIES_EVERY: Duration = Duration::from_secs(30);

/// One message from a server to another.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "t", rename_all = "snake_case")]
pub enum Envelope {
    /// To the owner's server: a command from a socket or a route on `from`.
    Ask {
        session: String,
        from: String,
        req: u64,
        ask: Ask,
    },
    /// Back to the server that asked.
    Reply {
        session: String,
        req: u64,
        reply: Reply,
    },
    /// A broadcast of the session, to every server that joined it (the owner is `from`).
    Cast {
        session: String,
        from: String,
        text: String,
    },
    /// The owner published a new snapshot.
    Snapshot {
        session: String,
        snapshot: Box<Snapshot>,
    },
    /// The session no longer runs on the server that sent this (its lease went): relays close
    /// their sockets, which connect again and reach its next owner.
    Moved { session: String },
    /// A message too large for a notification, kept in `relay_bodies` under `id`.
    Stored { id: i64 },
}

/// A command for the session's owner.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "ask", rename_all = "snake_case")]
pub enum Ask {
    Join {
        who: Identity,
    },
    Answer {
        id: QueryId,
        value: AnswerValue,
        who: Identity,
    },
    Undo {
        id: QueryId,
        who: Identity,
    },
    Stop,
    /// The asking server has no browser of the session left: no more casts to it.
    Leave,
}

/// The owner's reply to an [`Ask`].
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Reply {
    Joined {
        catch_up: Vec<String>,
        snapshot: Box<Snapshot>,
    },
    Answer {
        reply: AnswerReply,
    },
    Undo {
        result: Result<(), ProtocolError>,
    },
    Stopped,
    /// The session does not run on the server asked (any more).
    NotHere,
}

impl Envelope {
    /// The session it is about (none for a kept body's reference).
    fn session(&self) -> Option<&str> {
        match self {
            Envelope::Ask { session, .. }
            | Envelope::Reply { session, .. }
            | Envelope::Cast { session, .. }
            | Envelope::Snapshot { session, .. }
            | Envelope::Moved { session } => Some(session),
            Envelope::Stored { .. } => None,
        }
    }
}

/// The channel server `id` listens on.
pub fn channel(server: &str) -> String {
    format!("dualrep_{server}")
}

/// This server's way to the others: cheap to clone, never blocks (the sending task has the
/// queue).
#[derive(Clone, Debug)]
pub struct Bus {
    out: UnboundedSender<(String, Envelope)>,
}

impl Bus {
    /// Send `envelope` to server `to` (after everything sent to it before).
    pub fn send(&self, to: &str, envelope: Envelope) {
        let _ = self.out.send((to.to_owned(), envelope));
    }
}

impl Hub {
    /// Start listening and sending (PostgreSQL). Listening comes first, so that no reply to
    /// anything this server sends can come before it listens.
    pub(super) async fn start_bus(self: &Arc<Self>) -> anyhow::Result<()> {
        let Some(listener) = self.store.listener(&channel(&self.server_id)).await? else {
            return Ok(());
        };
        let Some(notifier) = self.store.notifier().await? else {
            return Ok(());
        };
        let (out, queue) = unbounded_channel();
        let bus = Bus { out };
        if self.bus.set(bus).is_err() {
            anyhow::bail!("the bus was started twice");
        }
        let sending = tokio::spawn(send_loop(self.store.clone(), notifier, queue));
        let listening = tokio::spawn(self.clone().listen_loop(listener));
        let mut tasks = self.bus_tasks.lock().unwrap_or_else(|e| e.into_inner());
        tasks.push(sending);
        tasks.push(listening);
        Ok(())
    }

    async fn listen_loop(self: Arc<Self>, mut listener: sqlx::postgres::PgListener) {
        while !self.slots.is_closed() {
            match listener.try_recv().await {
                Ok(Some(n)) => match serde_json::from_str::<Vec<Envelope>>(n.payload()) {
                    Ok(envelopes) => {
                        for e in envelopes {
                            self.take(e).await;
                        }
                    }
                    Err(e) => tracing::error!("a notification that does not read: {e}"),
                },
                // The connection was lost (and is made again): whatever was sent meanwhile is
                // gone, so every relay starts over (its sockets connect again and catch up).
                Ok(None) => {
                    tracing::warn!("the listening connection was lost: relays start over");
                    self.relays_moved(None);
                }
                Err(e) => {
                    tracing::warn!("listening for other servers: {e}");
                    tokio::time::sleep(Duration::from_secs(1)).await;
                }
            }
        }
    }

    /// One envelope from another server.
    async fn take(self: &Arc<Self>, envelope: Envelope) {
        let envelope = match envelope {
            Envelope::Stored { id } => match self.store.relay_body(id).await {
                Ok(Some(body)) => match serde_json::from_str(&body) {
                    Ok(e) => e,
                    Err(e) => return tracing::error!("kept message {id} does not read: {e}"),
                },
                Ok(None) => return tracing::error!("kept message {id} is gone"),
                Err(e) => return tracing::error!("reading kept message {id}: {e}"),
            },
            e => e,
        };
        match envelope {
            Envelope::Ask {
                session,
                from,
                req,
                ask,
            } => self.take_ask(session, from, req, ask),
            other => {
                let Some(session) = other.session().map(str::to_owned) else {
                    return;
                };
                // Only a cast's sender is kept aside (casts are most of the traffic: no copy).
                let cast_from = match &other {
                    Envelope::Cast { from, .. } => Some(from.clone()),
                    _ => None,
                };
                if !self.to_relay(&session, other)
                    && let Some(from) = cast_from
                {
                    // Casts for a relay that has gone: no more of them.
                    self.bus_send(&from, ask(&session, &self.server_id, 0, Ask::Leave));
                }
            }
        }
    }

    /// A command from another server for a session this one runs. The command reaches the
    /// owner before this returns, so commands from one server reach it in the order sent.
    fn take_ask(self: &Arc<Self>, session: String, from: String, req: u64, ask: Ask) {
        let Some(handle) = self.owned(&session).filter(|h| h.status().is_active()) else {
            if !matches!(ask, Ask::Leave) {
                self.bus_send(&from, reply(&session, req, Reply::NotHere));
            }
            return;
        };
        let bus = self.bus.get().cloned();
        let to = from.clone();
        let answer_to = move |r: Reply| {
            if let Some(bus) = bus {
                bus.send(&to, reply(&session, req, r));
            }
        };
        match ask {
            // The owner replies itself, so that its catch-up and its casts after it leave in
            // order.
            Ask::Join { who } => handle.remote_join(who, from, req),
            Ask::Leave => handle.leave(from),
            Ask::Answer { id, value, who } => {
                let reply = handle.send_answer(id, value, who);
                tokio::spawn(async move {
                    let r = reply
                        .await
                        .unwrap_or(AnswerReply::Refused(ProtocolError::session_ended()));
                    answer_to(Reply::Answer { reply: r });
                });
            }
            Ask::Undo { id, who } => {
                let reply = handle.send_undo(id, who);
                tokio::spawn(async move {
                    let result = reply
                        .await
                        .unwrap_or_else(|_| Err(ProtocolError::session_ended()));
                    answer_to(Reply::Undo { result });
                });
            }
            Ask::Stop => {
                let reply = handle.send_stop();
                tokio::spawn(async move {
                    answer_to(match reply.await {
                        Ok(()) => Reply::Stopped,
                        Err(_) => Reply::NotHere,
                    });
                });
            }
        }
    }

    /// Send through the bus, if this server has one (PostgreSQL).
    pub(super) fn bus_send(&self, to: &str, envelope: Envelope) {
        if let Some(bus) = self.bus.get() {
            bus.send(to, envelope);
        }
    }
}

pub(super) fn ask(session: &str, from: &str, req: u64, ask: Ask) -> Envelope {
    Envelope::Ask {
        session: session.to_owned(),
        from: from.to_owned(),
        req,
        ask,
    }
}

pub(super) fn reply(session: &str, req: u64, reply: Reply) -> Envelope {
    Envelope::Reply {
        session: session.to_owned(),
        req,
        reply,
    }
}

/// The sending task: takes what waits, packs each server's share into notifications in order,
/// and sends them on its own connection; reconnects when that connection fails (what it was
/// sending then is lost, see the module's note).
async fn send_loop(
    store: Store,
    notifier: Notifier,
    mut queue: UnboundedReceiver<(String, Envelope)>,
) {
    let mut notifier = Some(notifier);
    let mut forgot_at = tokio::time::Instant::now();
    let mut batch = Vec::with_capacity(BATCH);
    while queue.recv_many(&mut batch, BATCH).await > 0 {
        let n = match notifier.as_mut() {
            Some(n) => n,
            None => match store.notifier().await {
                Ok(Some(n)) => notifier.insert(n),
                Ok(None) => return,
                Err(e) => {
                    tracing::warn!("connecting to send to other servers: {e}");
                    batch.clear();
                    tokio::time::sleep(Duration::from_secs(1)).await;
                    continue;
                }
            },
        };
        if let Err(e) = send_batch(n, batch.drain(..)).await {
            tracing::warn!("sending to other servers: {e}");
            notifier = None;
            continue;
        }
        if forgot_at.elapsed() >= FORGET_BODIES_EVERY {
            forgot_at = tokio::time::Instant::now();
            if let Err(e) = n.forget_old_bodies().await {
                tracing::warn!("dropping old kept messages: {e}");
            }
        }
    }
}

/// Pack each server's envelopes, in order, into payloads under the limit, and send them.
async fn send_batch(
    notifier: &mut Notifier,
    batch: impl Iterator<Item = (String, Envelope)>,
) -> sqlx::Result<()> {
    let mut payloads: HashMap<String, Vec<String>> = HashMap::new();
    let mut order: Vec<String> = Vec::new();
    for (to, envelope) in batch {
        let mut text = serde_json::to_string(&envelope).expect("envelopes serialise");
        if text.len() + 2 > PAYLOAD_LIMIT {
            let id = notifier.keep_body(&text).await?;
            text = serde_json::to_string(&Envelope::Stored { id }).expect("envelopes serialise");
        }
        let list = payloads.entry(to.clone()).or_insert_with(|| {
            order.push(to);
            Vec::new()
        });
        match list.last_mut() {
            Some(last) if last.len() + text.len() + 2 <= PAYLOAD_LIMIT => {
                last.pop();
                last.push(',');
                last.push_str(&text);
                last.push(']');
            }
            _ => list.push(format!("[{text}]")),
        }
    }
    for to in order {
        let channel = channel(&to);
        for payload in &payloads[&to] {
            notifier.notify(&channel, payload).await?;
        }
    }
    Ok(())
}
