//! The trainer's websocket: authorise with the session's trainer token (or the researcher's),
//! send `hello` and whatever the browser needs to catch up (the pending query), then relay the
//! session's broadcasts and take answers. Each message is parsed once (`protocol`); bad input
//! gets an `error` and the connection stays up.

use std::sync::Arc;
use std::time::Instant;

use axum::extract::ws::rejection::WebSocketUpgradeRejection;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use tokio::sync::broadcast::error::RecvError;

use super::protocol::{ClientMessage, ProtocolError, ServerMessage, id_of, parse_client};
use crate::http::AppState;
use crate::http::auth::same_token;
use crate::http::error::ApiError;
use crate::hub::{AnswerReply, Live};
use crate::scene_graph::SceneGraph;
use crate::store::SessionRow;

/// Largest message a trainer may send: answers are a few dozen bytes.
pub const MAX_MESSAGE_BYTES: usize = 4 * 1024;
/// Answers per second a socket may send on average, and the burst it may save up.
const ANSWER_RATE: f64 = 20.0;
const ANSWER_BURST: f64 = 40.0;

#[derive(Debug, Deserialize)]
pub struct WsQuery {
    token: Option<String>,
}

pub async fn upgrade(
    State(state): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<WsQuery>,
    ws: Result<WebSocketUpgrade, WebSocketUpgradeRejection>,
) -> Response {
    let row = match state.store.session(&id).await {
        Ok(Some(row)) => row,
        Ok(None) => return ApiError::not_found(format!("no session {id}")).into_response(),
        Err(e) => return ApiError::from(e).into_response(),
    };
    let Some(token) = q.token else {
        return ApiError::unauthorized("the websocket needs ?token=<the session's trainer token>")
            .into_response();
    };
    if !same_token(&token, &row.trainer_token) && !same_token(&token, &state.token) {
        return ApiError::new(
            StatusCode::FORBIDDEN,
            "forbidden",
            format!("this token is not valid for session {id}"),
        )
        .into_response();
    }
    let ws = match ws {
        Ok(ws) => ws,
        Err(e) => {
            return ApiError::bad_request(format!("not a websocket request: {e}")).into_response();
        }
    };
    ws.max_message_size(MAX_MESSAGE_BYTES)
        .max_frame_size(MAX_MESSAGE_BYTES)
        .on_upgrade(move |socket| serve(state, row, socket))
}

fn text(s: &str) -> Message {
    Message::Text(s.to_owned().into())
}

fn hello(row: &SessionRow, live: Option<&Live>, status: crate::store::Status) -> ServerMessage {
    let spec = row.spec().ok();
    let task = spec.as_ref().map_or(crate::sim::Task::Reaching, |s| s.task);
    let graph = spec
        .as_ref()
        .and_then(|s| s.scene_graph().ok())
        .unwrap_or_else(|| SceneGraph::for_task(task));
    let pace_hz = spec
        .as_ref()
        .and_then(|s| s.settings().ok())
        .map_or(crate::session::spec::DEFAULT_PACE_HZ, |s| s.pace_hz);
    let kind = spec.map_or("evaluative", |s| s.method.query_kind());
    ServerMessage::Hello {
        session: row.id.clone(),
        task,
        method: row.method.clone(),
        kind,
        status,
        predicates: graph.predicates().to_vec(),
        geometry: live.and_then(|l| l.lock().geometry.clone()),
        budget: row.budget as u64,
        pace_hz,
    }
}

/// A token bucket: `ANSWER_RATE` per second, bursts of `ANSWER_BURST`.
struct RateLimit {
    tokens: f64,
    at: Instant,
}

impl RateLimit {
    fn new() -> Self {
        Self {
            tokens: ANSWER_BURST,
            at: Instant::now(),
        }
    }

    fn allow(&mut self) -> bool {
        let now = Instant::now();
        self.tokens = (self.tokens + now.duration_since(self.at).as_secs_f64() * ANSWER_RATE)
            .min(ANSWER_BURST);
        self.at = now;
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

async fn serve(state: AppState, row: SessionRow, mut socket: WebSocket) {
    let live = state.hub.live(&row.id);
    let status = state.hub.status_of(&row);
    if socket
        .send(text(&hello(&row, live.as_deref(), status).to_text()))
        .await
        .is_err()
    {
        return;
    }
    let Some(live) = live.filter(|_| status.is_active()) else {
        // Nothing runs: say so, and refuse answers until the browser goes.
        let ended = ServerMessage::Ended {
            status,
            reason: row.reason.clone(),
        };
        if socket.send(text(&ended.to_text())).await.is_err() {
            return;
        }
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
        return;
    };
    // Subscribe before catching up, so nothing falls between; the browser drops duplicates by id.
    let mut rx = live.subscribe();
    for m in live.catch_up() {
        if socket.send(text(&m)).await.is_err() {
            return;
        }
    }
    let mut limit = RateLimit::new();
    loop {
        tokio::select! {
            broadcast = rx.recv() => match broadcast {
                Ok(m) => {
                    if socket.send(text(&m)).await.is_err() {
                        return;
                    }
                }
                // Too slow for the frame rate: skip ahead, and re-send what must not be missed.
                Err(RecvError::Lagged(_)) => {
                    for m in live.catch_up() {
                        if socket.send(text(&m)).await.is_err() {
                            return;
                        }
                    }
                }
                Err(RecvError::Closed) => return,
            },
            incoming = socket.recv() => {
                let reply = match incoming {
                    Some(Ok(Message::Text(t))) => handle(&state, &live, &mut limit, t.as_str()).await,
                    Some(Ok(Message::Binary(_))) => Some(ProtocolError::new("bad_message", "binary messages are not part of the protocol; send JSON text").to_message(None)),
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

fn session_ended(id: Option<i64>) -> ServerMessage {
    ProtocolError::new(
        "session_ended",
        "the session is not running; answers are closed",
    )
    .to_message(id)
}

async fn handle(
    state: &AppState,
    live: &Arc<Live>,
    limit: &mut RateLimit,
    t: &str,
) -> Option<ServerMessage> {
    let message = match parse_client(t) {
        Ok(m) => m,
        Err(e) => return Some(e.to_message(id_of(t))),
    };
    if !limit.allow() {
        let id = match &message {
            ClientMessage::Answer { id, .. } | ClientMessage::Undo { id } => *id,
        };
        return Some(
            ProtocolError::new(
                "rate_limited",
                format!("more than {ANSWER_RATE} messages a second; slow down"),
            )
            .to_message(Some(id)),
        );
    }
    match message {
        ClientMessage::Answer { id, value } => {
            if !live.lock().status.is_active() {
                return Some(session_ended(Some(id)));
            }
            Some(
                match live.answer(&state.store, id, value, "trainer").await {
                    AnswerReply::Ack(value) => ServerMessage::Ack { id, value },
                    AnswerReply::Refused(e) => e.to_message(Some(id)),
                },
            )
        }
        // On success every page gets `undone` and the query again, by broadcast.
        ClientMessage::Undo { id } => match live.undo(&state.store, id).await {
            Ok(()) => None,
            Err(e) => Some(e.to_message(Some(id))),
        },
    }
}
