//! The websocket protocol (`docs/protocol.md`), below both the hub and the socket: one
//! serde-tagged enum each way, and the closed sets of values on the wire (query kinds, who
//! answered, why a query was withdrawn, error codes) as enums. Client text is parsed once,
//! here, into `ClientMessage`; anything else becomes a `ProtocolError` with a code the browser
//! can act on. No IO.

use serde::{Deserialize, Serialize};

use crate::json_input;
use crate::scene_graph::Predicate;
pub use crate::session::{AnswerValue, Answerer, QueryKind};
use crate::session::{Frame, QueryContent};
pub use crate::settings::Combine;
use crate::sim::Geometry;
use crate::store::{Status, TrainerRef};

/// A query's id on the wire: the session's own query number (0 for its first query), the
/// order in which the session asked it. Answers, acks, withdrawals and errors name queries by
/// it; it is also `query_id` in the REST answers and the exports.
pub type QueryId = u64;

/// Server to trainer.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    /// First message on every connection.
    Hello {
        session: String,
        /// `reaching`, `placing`, `lunar-lander`, or `remote` (a remote env's own task).
        task: &'static str,
        method: String,
        /// Which answers this session takes.
        kind: QueryKind,
        status: Status,
        predicates: Vec<Predicate>,
        /// The current episode's static scene (absent until the session has started).
        #[serde(skip_serializing_if = "Option::is_none")]
        geometry: Option<Geometry>,
        /// Steps (evaluative) or queries (preference) the session will take.
        budget: u64,
        /// Steps per second the session runs at while people watch (the page paces its
        /// drawing by it).
        pace_hz: f64,
        /// The named trainer this connection answers as (absent: anonymous, or a researcher).
        #[serde(skip_serializing_if = "Option::is_none")]
        trainer: Option<TrainerRef>,
        /// Answers each query takes from different named trainers (1: the first one wins).
        answers_per_query: usize,
        /// How they combine: `first`, `majority`, `mean` or `each`.
        combine: Combine,
    },
    Frame(Frame),
    /// Boxed: a query (with its clips) is far larger than the other messages.
    Query(Box<QueryMessage>),
    /// The answer to `id` is stored.
    Ack {
        id: QueryId,
        value: AnswerValue,
    },
    /// The answer to `id` was taken back (a trainer's undo); the query follows again, open for
    /// a new answer.
    Undone {
        id: QueryId,
    },
    /// `id` needs no answer any more.
    Withdrawn {
        id: QueryId,
        reason: WithdrawReason,
    },
    Progress(ProgressMessage),
    Error {
        code: ErrorCode,
        message: String,
        #[serde(skip_serializing_if = "Option::is_none")]
        id: Option<QueryId>,
        /// `rate_limited`: send the refused message again after this many milliseconds.
        #[serde(skip_serializing_if = "Option::is_none")]
        retry_after_ms: Option<u64>,
    },
    /// The session is over (or the server is shutting down); no more messages follow.
    Ended {
        status: Status,
        #[serde(skip_serializing_if = "Option::is_none")]
        reason: Option<String>,
    },
}

/// A query for the trainers.
#[derive(Clone, Debug, Serialize)]
pub struct QueryMessage {
    pub id: QueryId,
    /// The environment step (evaluative) or query number (preference) it was asked at.
    pub step: u64,
    pub abstract_state: u32,
    /// Milliseconds left before it counts as "no feedback" (or a skipped pair).
    pub expires_in_ms: u64,
    #[serde(flatten)]
    pub content: QueryContent,
}

/// Where the session stands.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ProgressMessage {
    /// Queries answered so far (by anyone, timeouts included).
    pub answered: u64,
    /// Steps or queries done, of `budget`.
    pub progress: u64,
    pub budget: u64,
    /// `steps` or `queries`.
    pub unit: std::borrow::Cow<'static, str>,
    /// Share of steps with feedback (evaluative sessions).
    pub feedback_fraction: f64,
    /// Returns of the latest finished episodes, oldest first (evaluative sessions).
    pub recent_returns: Vec<f64>,
    /// Posterior alignment with the synthetic trainer's reward (synthetic preference sessions).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alignment: Option<f64>,
    /// How the query rule paces itself (evaluative sessions, from their first finished episode).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pacing: Option<RulePacing>,
}

/// A query rule's pacing as a person feels it (docs/dref.md): floods of consecutive queries,
/// and silences while the robot keeps failing ("frozen").
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RulePacing {
    /// Finished episodes.
    pub episodes: u64,
    /// Episodes after which the rule had not asked for 10k steps while the last 10 episodes
    /// failed.
    pub frozen_episodes: u64,
    /// The longest stretch of consecutive asked steps.
    pub longest_flood: u64,
    /// Steps since the rule last asked, at the latest episode's end.
    pub steps_since_query: u64,
    /// Whether each of the latest episodes (at most 10) succeeded, oldest first.
    #[serde(skip)]
    recent_successes: std::collections::VecDeque<bool>,
}

impl RulePacing {
    /// Count a finished episode.
    pub fn episode(&mut self, e: &crate::guidance::evaluative_run::EpisodeRecord) {
        use crate::guidance::ask_pacing::{FROZEN_FAILED_EPISODES, is_frozen};
        self.episodes += 1;
        self.longest_flood = e.longest_flood;
        self.steps_since_query = e.steps_since_query;
        let recent = &mut self.recent_successes;
        recent.push_back(e.outcome == crate::sim::Outcome::Success);
        if recent.len() > FROZEN_FAILED_EPISODES {
            recent.pop_front();
        }
        if is_frozen(e.steps_since_query, recent.iter().copied()) {
            self.frozen_episodes += 1;
        }
    }
}

/// Trainer to server.
#[derive(Clone, Debug, PartialEq)]
pub enum ClientMessage {
    Answer { id: QueryId, value: AnswerValue },
    Undo { id: QueryId },
}

/// The fields of an `answer` ([`ClientMessage::Answer`]) as JSON: ids are read as any integer,
/// so that a negative one is refused as an unknown query (no session has one) rather than as a
/// malformed message.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnswerFields {
    id: i64,
    value: AnswerValue,
}

/// The fields of an `undo`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct UndoFields {
    id: i64,
}

/// Why a query needs no answer any more.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WithdrawReason {
    /// Answered (by this trainer or another).
    Answered,
    /// Its answer timeout passed: it counts as "no feedback" (a skipped pair).
    Expired,
    /// The session ended while it was open.
    Ended,
}

impl WithdrawReason {
    /// Why a query closes when `who` answers it.
    pub fn answered_by(who: Answerer) -> Self {
        match who {
            Answerer::Timeout => WithdrawReason::Expired,
            Answerer::Trainer | Answerer::Trainers | Answerer::Synthetic => {
                WithdrawReason::Answered
            }
        }
    }
}

/// What went wrong with a client's message, for the browser to act on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// Not JSON.
    MalformedJson,
    /// JSON, but not a message of the protocol.
    BadMessage,
    /// A value of the wrong kind for the query (a preference for an evaluative query, say).
    BadValue,
    /// Answered before with another value; the first answer stands.
    AlreadyAnswered,
    /// Asked, but no longer open (its session ended while it waited).
    Expired,
    /// Not a query of this session.
    UnknownQuery,
    /// The database failed; nothing was stored, try again.
    StoreFailed,
    /// Not the latest answer a trainer gave, too old, or the session is not running.
    UndoUnavailable,
    /// Too many messages a second.
    RateLimited,
    /// The session is not running; answers are closed.
    SessionEnded,
    /// The session takes several answers per query from named trainers: this connection has
    /// no name (open your own link, or join with a name).
    IdentityRequired,
}

/// Why a client message was refused.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ProtocolError {
    pub code: ErrorCode,
    pub message: String,
    /// When the client may send the refused message again (`rate_limited` only).
    pub retry_after_ms: Option<u64>,
}

impl ProtocolError {
    pub fn new(code: ErrorCode, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
            retry_after_ms: None,
        }
    }

    /// Too many messages: this one was not taken; send it again in `retry_after_ms`.
    pub fn rate_limited(message: impl Into<String>, retry_after_ms: u64) -> Self {
        Self {
            retry_after_ms: Some(retry_after_ms),
            ..Self::new(ErrorCode::RateLimited, message)
        }
    }

    /// The refusal of any answer once the session is not running.
    pub fn session_ended() -> Self {
        Self::new(
            ErrorCode::SessionEnded,
            "the session is not running; answers are closed",
        )
    }

    pub fn to_message(&self, id: Option<QueryId>) -> ServerMessage {
        ServerMessage::Error {
            code: self.code,
            message: self.message.clone(),
            id,
            retry_after_ms: self.retry_after_ms,
        }
    }
}

/// Parse one text message from a trainer. Errors name the message type and the field that
/// was wrong.
pub fn parse_client(text: &str) -> Result<ClientMessage, ProtocolError> {
    const EXPECTED: &str = "expected {\"type\": \"answer\", \"id\": <query id>, \"value\": 1 | 0 | -1 | \"left\" | \"right\" | \"equal\" | \"skip\"} or {\"type\": \"undo\", \"id\": <query id>}";
    let value: serde_json::Value = json_input::from_str(text)
        .map_err(|e| ProtocolError::new(ErrorCode::MalformedJson, e.to_string()))?;
    let serde_json::Value::Object(mut fields) = value else {
        return Err(ProtocolError::new(
            ErrorCode::BadMessage,
            format!("a message is a JSON object with a \"type\"; {EXPECTED}"),
        ));
    };
    let kind = fields.remove("type");
    let bad =
        |what: String| ProtocolError::new(ErrorCode::BadMessage, format!("{what}; {EXPECTED}"));
    let fields = serde_json::Value::Object(fields);
    let wire = match kind.as_ref().and_then(serde_json::Value::as_str) {
        Some("answer") => {
            let a: AnswerFields = json_input::from_value(fields)
                .map_err(|e| bad(format!("an answer message: {e}")))?;
            (a.id, Some(a.value))
        }
        Some("undo") => {
            let u: UndoFields =
                json_input::from_value(fields).map_err(|e| bad(format!("an undo message: {e}")))?;
            (u.id, None)
        }
        Some(other) => return Err(bad(format!("unknown message type {other:?}"))),
        None => {
            return Err(bad(match kind {
                None => "a message without a \"type\"".to_string(),
                Some(k) => format!("field \"type\": {k} is not a message type"),
            }));
        }
    };
    let query = |id: i64| {
        QueryId::try_from(id).map_err(|_| {
            ProtocolError::new(
                ErrorCode::UnknownQuery,
                format!("query {id} does not belong to this session"),
            )
        })
    };
    Ok(match wire {
        (_, Some(value)) if !value.is_single() => {
            return Err(ProtocolError::new(
                ErrorCode::BadMessage,
                "an answer message: field \"value\": a trainer answers 1, 0, -1, \"left\", \"right\", \"equal\" or \"skip\"; means and tallies are what the server combines",
            ));
        }
        (id, Some(value)) => ClientMessage::Answer {
            id: query(id)?,
            value,
        },
        (id, None) => ClientMessage::Undo { id: query(id)? },
    })
}

/// The id a (possibly malformed) message names, to attach to its error.
pub fn id_of(text: &str) -> Option<QueryId> {
    serde_json::from_str::<serde_json::Value>(text)
        .ok()?
        .get("id")?
        .as_u64()
}

impl ServerMessage {
    pub fn to_text(&self) -> String {
        serde_json::to_string(self).expect("server messages serialise")
    }
}

#[cfg(test)]
#[path = "protocol_tests.rs"]
mod tests;
