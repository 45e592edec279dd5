//! The bytes of the env protocol (`docs/env-protocol.md`): every message is a 4-byte big-endian
//! length and that many bytes of one JSON object; a frame's encoded image follows the message
//! that announces it as raw bytes (its length in the message), so images cross without base64.
//! Every read has a deadline.

use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::scene_graph::declared::DeclaredPredicate;

/// The protocol version this build speaks.
pub const PROTOCOL: u32 = 1;
/// Largest JSON message either side sends (a Box space of a few hundred thousand entries).
pub const MAX_MESSAGE: usize = 16 << 20;
/// Largest encoded frame.
pub const MAX_FRAME: usize = 16 << 20;

/// What dualrep asks; the env answers each with exactly one [`Reply`], in order.
#[derive(Debug, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Request<'a> {
    Hello { protocol: u32, client: &'a str },
    Reset { seed: u64, render: bool },
    Step { action: &'a [f64], render: bool },
    Close,
}

/// What the env answers.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Reply {
    Hello {
        protocol: u32,
        env: Box<Description>,
    },
    Reset(ResetReply),
    Step(StepReply),
    Close {},
    Error {
        message: String,
    },
}

/// A Box space: row-major `low` and `high` of `shape`'s size; `null` bounds are unbounded.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceMessage {
    pub shape: Vec<usize>,
    pub low: Vec<Option<f64>>,
    pub high: Vec<Option<f64>>,
}

/// The env's `hello`: everything that stays fixed while it runs.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Description {
    pub id: String,
    pub observation_space: SpaceMessage,
    pub action_space: SpaceMessage,
    /// Agent steps per second of the env's own clock (a robot's control rate).
    pub control_hz: f64,
    pub max_episode_steps: u32,
    #[serde(default)]
    pub predicates: Vec<DeclaredPredicate>,
    /// DRPL feature names, if the env computes features.
    #[serde(default)]
    pub features: Vec<String>,
    #[serde(default)]
    pub observation_names: Option<Vec<String>>,
    #[serde(default)]
    pub action_names: Option<Vec<String>>,
    /// Whether it can render frames for people.
    #[serde(default)]
    pub render: bool,
    /// Whether the same seed and actions give the same episode (a simulator; a robot: false).
    #[serde(default)]
    pub deterministic: bool,
}

/// A frame announced by a reply: `bytes` raw bytes follow the message.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameHeader {
    pub format: String,
    pub width: u32,
    pub height: u32,
    pub bytes: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResetReply {
    pub obs: Vec<f64>,
    #[serde(default)]
    pub holding: Vec<String>,
    #[serde(default)]
    pub frame: Option<FrameHeader>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepReply {
    pub obs: Vec<f64>,
    pub reward: f64,
    pub terminated: bool,
    pub truncated: bool,
    /// Names of the declared predicates that hold after the step.
    #[serde(default)]
    pub holding: Vec<String>,
    #[serde(default)]
    pub features: Option<Vec<f64>>,
    /// On an episode's last step: whether it achieved the task.
    #[serde(default)]
    pub success: Option<bool>,
    #[serde(default)]
    pub frame: Option<FrameHeader>,
}

/// Why a message could not cross.
#[derive(Debug, thiserror::Error)]
pub enum WireError {
    #[error("no answer within {0:?}")]
    Timeout(Duration),
    #[error("the connection closed")]
    Closed,
    #[error("{0}")]
    Io(#[from] io::Error),
    #[error("{0}")]
    Malformed(String),
}

/// Write one message.
pub fn send(stream: &mut TcpStream, request: &Request<'_>) -> Result<(), WireError> {
    let body = serde_json::to_vec(request).expect("requests serialise");
    let mut message = Vec::with_capacity(4 + body.len());
    message.extend_from_slice(&(body.len() as u32).to_be_bytes());
    message.extend_from_slice(&body);
    stream.write_all(&message)?;
    Ok(())
}

/// Read one message's JSON bytes, all of it before `deadline`.
pub fn receive(stream: &mut TcpStream, deadline: Instant) -> Result<Vec<u8>, WireError> {
    let mut len = [0u8; 4];
    read_exact_by(stream, &mut len, deadline)?;
    let len = u32::from_be_bytes(len) as usize;
    if len > MAX_MESSAGE {
        return Err(WireError::Malformed(format!(
            "a message of {len} bytes (at most {MAX_MESSAGE})"
        )));
    }
    let mut body = vec![0u8; len];
    read_exact_by(stream, &mut body, deadline)?;
    Ok(body)
}

/// Read the `len` raw bytes of an announced frame.
pub fn receive_frame(
    stream: &mut TcpStream,
    len: usize,
    deadline: Instant,
) -> Result<Vec<u8>, WireError> {
    if len > MAX_FRAME {
        return Err(WireError::Malformed(format!(
            "a frame of {len} bytes (at most {MAX_FRAME})"
        )));
    }
    let mut bytes = vec![0u8; len];
    read_exact_by(stream, &mut bytes, deadline)?;
    Ok(bytes)
}

/// `read_exact` that gives up at `deadline` however the bytes trickle in.
fn read_exact_by(
    stream: &mut TcpStream,
    mut buf: &mut [u8],
    deadline: Instant,
) -> Result<(), WireError> {
    while !buf.is_empty() {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(WireError::Timeout(Duration::ZERO));
        }
        stream.set_read_timeout(Some(left))?;
        match stream.read(buf) {
            Ok(0) => return Err(WireError::Closed),
            Ok(n) => buf = &mut buf[n..],
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                return Err(WireError::Timeout(Duration::ZERO));
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(WireError::Io(e)),
        }
    }
    Ok(())
}
