//! The trainer's websocket: authorise with the session's trainer token (or the researcher's),
//! send `hello` and whatever the browser needs to catch up (the pending query), then relay the
//! session's broadcasts and take answers. Each message is parsed once (`protocol`); bad input
//! gets an `error` and the connection stays up.

use std::sync::Arc;
use std::time::Instant;

use axum::extract::State;
use axum::extract::ws::rejection::WebSocketUpgradeRejection;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade, close_code};
use axum::response::{IntoResponse, Response};
use tokio::sync::broadcast::error::RecvError;

use crate::api::AppState;
use crate::api::auth::SessionAccess;
use crate::api::error::{ApiError, ErrorBody};
use crate::hub::{AnswerReply, Identity, Joined, Reach, SessionHandle};
use crate::protocol::{
    ClientMessage, ErrorCode, ProtocolError, QueryId, ServerMessage, id_of, parse_client,
};
use crate::scene_graph::SceneGraph;
use crate::session::SessionPlan;
use crate::store::SessionRow;

use super::rate_limit::{MESSAGES_PER_SECOND, RateLimit, whole_ms};

/// Largest message a trainer may send: answers are a few dozen bytes.
pub const MAX_MESSAGE_BYTES: usize = 4 * 1024;

/// The trainer's websocket: JSON messages, one typed enum each way (`docs/protocol.md`).
#[utoipa::path(
    get,
    path = "/ws/sessions/{id}",
    tag = "trainers",
    security(()),
    params(
        ("id" = String, Path, description = "The session"),
        ("token" = String, Query, description = "The session's trainer token (from its trainer_url), or the researcher token")
    ),
    responses(
        (status = 101, description = "Switching to the websocket protocol"),
        (status = "default", description = "An error", body = ErrorBody)
    )
)]
pub async fn upgrade(
    State(state): State<AppState>,
    SessionAccess(row, who): SessionAccess,
    ws: Result<WebSocketUpgrade, WebSocketUpgradeRejection>,
) -> Response {
    let ws = match ws {
        Ok(ws) => ws,
        Err(e) => {
            return ApiError::BadRequest(format!("not a websocket request: {e}")).into_response();
        }
    };
    // The running session here, or on another server sharing the database (through a relay).
    let live = match state.hub.reach(&row).await {
        Reach::Live(h) => Some(h),
        Reach::NotRunning => None,
        // The browser's socket connects again after a short wait, as after any close.
        Reach::Between => {
            return ApiError::Moving(format!(
                "session {} is waiting for a server (queued for a free slot, or its server \
                 stopped and another is taking it over): connect again shortly",
                row.id
            ))
            .into_response();
        }
    };
    // The plan the running session was started with; an ended one's, read from its row (a
    // stored session that no longer reads gets no socket, rather than a made-up `hello`).
    let plan = match &live {
        Some(live) => live.plan.clone(),
        None => match row.spec().map(SessionPlan::new) {
            Ok(Ok(plan)) => Arc::new(plan),
            Ok(Err(e)) => return ApiError::Conflict(e.to_string()).into_response(),
            Err(e) => return ApiError::Conflict(e.to_string()).into_response(),
        },
    };
    ws.max_message_size(MAX_MESSAGE_BYTES)
        .max_frame_size(MAX_MESSAGE_BYTES)
        .on_upgrade(move |socket| serve(state, row, plan, live, who, socket))
}

fn text(s: &str) -> Message {
    Message::Text(s.to_owned().into())
}

fn hello(
    row: &SessionRow,
    plan: &SessionPlan,
    who: &Identity,
    geometry: Option<crate::sim::Geometry>,
    live_graph: Option<SceneGraph>,
    status: crate::store::Status,
) -> ServerMessage {
    // The running session's graph (a remote env's own task declares it), else the plan's.
    let graph = live_graph.unwrap_or(plan.graph);
    ServerMessage::Hello {
        session: row.id.clone(),
        task: plan.spec.task_name(),
        method: row.method.clone(),
        kind: plan.kind,
        status,
        predicates: graph.predicates().to_vec(),
        geometry,
        budget: row.budget as u64,
        pace_hz: plan.settings.pace_hz,
        trainer: who.trainer().cloned(),
        answers_per_query: plan.settings.answers_per_query,
        combine: plan.settings.combine,
    }
}

async fn serve(
    state: AppState,
    row: SessionRow,
    plan: Arc<SessionPlan>,
    session: Option<SessionHandle>,
    who: Identity,
    mut socket: WebSocket,
) {
    let snapshot = session.as_ref().map(SessionHandle::snapshot);
    let status = snapshot.as_ref().map_or(row.status, |s| s.status);
    let live_graph = snapshot.as_ref().and_then(|s| s.graph);
    let geometry = snapshot.and_then(|s| s.geometry);
    if socket
        .send(text(
            &hello(&row, &plan, &who, geometry, live_graph, status).to_text(),
        ))
        .await
        .is_err()
    {
        return;
    }
    // Joined atomically: the catch-up, then every broadcast after it, nothing between.
    let joined = match &session {
        Some(s) if status.is_active() => s.join(&who).await.map(|j| (s, j)),
        _ => None,
    };
    let Some((
        session,
        Joined {
            catch_up,
            broadcast: mut rx,
        },
    )) = joined
    else {
        // It runs on, elsewhere (its server lost it while this socket joined).
        if session.as_ref().is_some_and(|s| s.status().is_active()) {
            return moved(socket).await;
        }
        // Nothing runs: say so, and refuse answers until the browser goes.
        let ended = ServerMessage::Ended {
            status: state.hub.status_of(&row),
            reason: row.reason.clone(),
        };
        if socket.send(text(&ended.to_text())).await.is_err() {
            return;
        }
        return refuse_until_closed(socket).await;
    };
    for m in catch_up {
        if socket.send(text(&m)).await.is_err() {
            return;
        }
    }
    let mut limit = RateLimit::new(Instant::now());
    loop {
        tokio::select! {
            broadcast = rx.recv() => match broadcast {
                Ok(m) => {
                    if socket.send(text(&m)).await.is_err() {
                        return;
                    }
                }
                // Too slow for the frame rate: join again, which re-sends what must not be
                // missed.
                Err(RecvError::Lagged(_)) => {
                    let Some(again) = session.join(&who).await else { return };
                    rx = again.broadcast;
                    for m in again.catch_up {
                        if socket.send(text(&m)).await.is_err() {
                            return;
                        }
                    }
                }
                // The session runs on, on another server (this one lost it, or the relay to
                // the server that ran it ended): close, and the browser connects again.
                Err(RecvError::Closed) if session.status().is_active() => return moved(socket).await,
                // The session ended (its `ended` came last): answers are closed from here.
                Err(RecvError::Closed) => return refuse_until_closed(socket).await,
            },
            incoming = socket.recv() => {
                let reply = match incoming {
                    Some(Ok(Message::Text(t))) => handle(session, &who, &mut limit, t.as_str()).await,
                    Some(Ok(Message::Binary(_))) => Some(ProtocolError::new(ErrorCode::BadMessage, "binary messages are not part of the protocol; send JSON text").to_message(None)),
                    Some(Ok(_)) => None, // ping / pong (answered by axum)
                    // Closed, or a protocol violation such as an oversized message.
                    Some(Err(_)) | None => return,
                };
                if let Some(reply) = reply
                    && socket.send(text(&reply.to_text())).await.is_err()
                {
                    return;
                }
            }
        }
    }
}

/// The session goes on elsewhere: close with 1012 ("service restart"), without `ended`, so
/// that the browser connects again (through the proxy) and reaches it where it runs now.
async fn moved(mut socket: WebSocket) {
    let frame = CloseFrame {
        code: close_code::RESTART,
        reason: "the session moved to another server: connect again".into(),
    };
    let _ = socket.send(Message::Close(Some(frame))).await;
}

/// Nothing runs: refuse answers until the browser goes.
async fn refuse_until_closed(mut socket: WebSocket) {
    while let Some(Ok(m)) = socket.recv().await {
        let reply = match m {
            Message::Text(t) => match parse_client(t.as_str()) {
                Ok(_) => session_ended(id_of(t.as_str())),
                Err(e) => e.to_message(id_of(t.as_str())),
            },
            Message::Close(_) => return,
            _ => continue,
        };
        if socket.send(text(&reply.to_text())).await.is_err() {
            return;
        }
    }
}

fn session_ended(id: Option<QueryId>) -> ServerMessage {
    ProtocolError::session_ended().to_message(id)
}

async fn handle(
    session: &SessionHandle,
    who: &Identity,
    limit: &mut RateLimit,
    t: &str,
) -> Option<ServerMessage> {
    let message = match parse_client(t) {
        Ok(m) => m,
        Err(e) => return Some(e.to_message(id_of(t))),
    };
    if let Err(wait) = limit.take(Instant::now()) {
        let id = match &message {
            ClientMessage::Answer { id, .. } | ClientMessage::Undo { id } => *id,
        };
        // Nothing of the message was kept: the client sends it again after the wait.
        let retry_after_ms = whole_ms(wait);
        return Some(
            ProtocolError::rate_limited(
                format!(
                    "more than {MESSAGES_PER_SECOND} messages a second; this one was not taken: send it again in {retry_after_ms} ms"
                ),
                retry_after_ms,
            )
            .to_message(Some(id)),
        );
    }
    match message {
        ClientMessage::Answer { id, value } => Some(match session.answer(id, value, who).await {
            AnswerReply::Ack(value) => ServerMessage::Ack { id, value },
            AnswerReply::Refused(e) => e.to_message(Some(id)),
        }),
        // On success every page gets `undone` and the query again, by broadcast.
        ClientMessage::Undo { id } => match session.undo(id, who).await {
            Ok(()) => None,
            Err(e) => Some(e.to_message(Some(id))),
        },
    }
}
