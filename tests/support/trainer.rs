//! A websocket trainer for tests: connect with a token, read typed-ish JSON, answer.

use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream, connect_async};

pub struct Trainer {
    ws: WebSocketStream<MaybeTlsStream<TcpStream>>,
}

/// The token inside a `trainer_url`.
pub fn token_of(trainer_url: &str) -> String {
    trainer_url.split("token=").nth(1).unwrap().to_string()
}

impl Trainer {
    pub async fn connect(addr: std::net::SocketAddr, session: &str, token: &str) -> Self {
        let (ws, _) = connect_async(format!("ws://{addr}/ws/sessions/{session}?token={token}"))
            .await
            .expect("websocket connects");
        Self { ws }
    }

    /// `None` when the server refuses the upgrade (e.g. 503 while no server runs the session).
    pub async fn try_connect(
        addr: std::net::SocketAddr,
        session: &str,
        token: &str,
    ) -> Option<Self> {
        let url = format!("ws://{addr}/ws/sessions/{session}?token={token}");
        connect_async(url).await.ok().map(|(ws, _)| Self { ws })
    }

    pub async fn send_text(&mut self, text: &str) {
        self.ws
            .send(Message::Text(text.to_string().into()))
            .await
            .unwrap();
    }

    pub async fn answer(&mut self, id: i64, value: Value) {
        self.send_text(&json!({"type": "answer", "id": id, "value": value}).to_string())
            .await;
    }

    /// The next JSON message (frames included), or `None` when the socket closed.
    pub async fn next(&mut self, timeout: Duration) -> Option<Value> {
        loop {
            match tokio::time::timeout(timeout, self.ws.next())
                .await
                .expect("a message in time")
            {
                Some(Ok(Message::Text(t))) => return Some(serde_json::from_str(&t).unwrap()),
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => return None,
                Some(Ok(_)) => continue,
            }
        }
    }

    /// The next message whose type is one of `types`, skipping others.
    pub async fn next_of(&mut self, types: &[&str], timeout: Duration) -> Value {
        loop {
            let m = self.next(timeout).await.expect("the socket stays open");
            if types.contains(&m["type"].as_str().unwrap_or("")) {
                return m;
            }
        }
    }

    pub async fn close(mut self) {
        let _ = self.ws.close(None).await;
    }
}
