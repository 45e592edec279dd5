//! What a session thread tells the async side, and what it is told: plain values over channels,
//! so the session loop needs no runtime. The server implements [`SessionSink`] with a tokio
//! channel; tests implement it with a `Vec`.

use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::guidance::drpl::trainer::Preference;
use crate::guidance::evaluative_run::EpisodeRecord;
use crate::guidance::evaluative_trainer::{Evaluation, MeanLabel};
use crate::scene_graph::{AbstractState, SceneGraph};
use crate::sim::{Geometry, RenderState};

use super::query::{QueryContent, QueryRecord};

/// Which answers a query takes: a +1 / 0 / -1 judgement (DREF, EF) or a preference between two
/// segments (DRPL and the other preference methods).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum QueryKind {
    Evaluative,
    Preference,
}

impl QueryKind {
    pub fn as_str(self) -> &'static str {
        match self {
            QueryKind::Evaluative => "evaluative",
            QueryKind::Preference => "preference",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        [QueryKind::Evaluative, QueryKind::Preference]
            .into_iter()
            .find(|k| k.as_str() == s)
    }
}

/// Who gave an answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Answerer {
    /// A person, through the websocket.
    Trainer,
    /// Several named trainers: their answers combined (`combine` = majority, mean or each).
    Trainers,
    /// The session's synthetic trainer (an expert oracle or a reward).
    Synthetic,
    /// Nobody: the answer timeout gave "no feedback" (or skipped the pair).
    Timeout,
}

impl Answerer {
    pub fn as_str(self) -> &'static str {
        match self {
            Answerer::Trainer => "trainer",
            Answerer::Trainers => "trainers",
            Answerer::Synthetic => "synthetic",
            Answerer::Timeout => "timeout",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        [
            Answerer::Trainer,
            Answerer::Trainers,
            Answerer::Synthetic,
            Answerer::Timeout,
        ]
        .into_iter()
        .find(|k| k.as_str() == s)
    }
}

/// A trainer's answer as the websocket carries it: `1 | 0 | -1` or `"left" | "right" | "equal" |
/// "skip"`; and what several trainers' answers combine into (`session::combine`): a mean such
/// as `0.5`, or a tally `{"tally": {"left": 2, ...}}`, which no trainer sends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(untagged)]
pub enum AnswerValue {
    Evaluation(i8),
    Preference(Preference),
    Mean(MeanLabel),
}

impl AnswerValue {
    pub fn evaluation(e: Evaluation) -> Self {
        match e {
            Evaluation::Mean(m) => AnswerValue::Mean(m),
            e => AnswerValue::Evaluation(e.value() as i8),
        }
    }

    /// The evaluative answer, if this is one with a valid value.
    pub fn as_evaluation(self) -> Option<Evaluation> {
        match self {
            AnswerValue::Evaluation(v) => Evaluation::from_value(i64::from(v)),
            AnswerValue::Mean(m) => Some(Evaluation::Mean(m)),
            AnswerValue::Preference(_) => None,
        }
    }

    pub fn as_preference(self) -> Option<Preference> {
        match self {
            AnswerValue::Preference(p) => Some(p),
            AnswerValue::Evaluation(_) | AnswerValue::Mean(_) => None,
        }
    }

    /// Whether one trainer can give this answer (combined values cannot be sent).
    pub fn is_single(self) -> bool {
        !matches!(
            self,
            AnswerValue::Mean(_) | AnswerValue::Preference(Preference::Tally(_))
        )
    }

    /// "No feedback" or a skip: what the paper counts in NFC.
    pub fn is_no_feedback(self) -> bool {
        matches!(
            self,
            AnswerValue::Evaluation(0) | AnswerValue::Preference(Preference::Skip)
        )
    }

    /// Whether this value answers a query of `kind`.
    pub fn fits(self, kind: QueryKind) -> bool {
        match kind {
            QueryKind::Evaluative => self.as_evaluation().is_some(),
            QueryKind::Preference => self.as_preference().is_some(),
        }
    }

    /// What a trainer who never answered gave: "no feedback" (as the paper allows) or a skip.
    pub fn timeout(kind: QueryKind) -> Self {
        match kind {
            QueryKind::Preference => AnswerValue::Preference(Preference::Skip),
            QueryKind::Evaluative => AnswerValue::Evaluation(0),
        }
    }

    /// The value as a number for scalars and plots (preferences: left 1, right -1, else 0).
    pub fn as_number(self) -> f64 {
        match self {
            AnswerValue::Evaluation(v) => f64::from(v),
            AnswerValue::Mean(m) => f64::from(m.value()),
            AnswerValue::Preference(Preference::Tally(t)) => {
                (f64::from(t.left) - f64::from(t.right)) / f64::from(t.total().max(1))
            }
            AnswerValue::Preference(Preference::Left) => 1.0,
            AnswerValue::Preference(Preference::Right) => -1.0,
            AnswerValue::Preference(_) => 0.0,
        }
    }
}

/// One rendered step for watching browsers.
#[derive(Clone, Debug, Serialize)]
pub struct Frame {
    pub step: u64,
    pub episode: u64,
    pub state: RenderState,
    /// Sent with the first frame of every episode (Lunar Lander's terrain changes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub geometry: Option<Geometry>,
    pub reward: f32,
    pub episode_return: f64,
}

/// How a session thread ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Ending {
    Finished,
    /// A researcher stopped it.
    Stopped,
    /// The server shut down; it can be resumed.
    Interrupted,
    Failed(String),
}

/// A checkpoint: where the session was, and a digest of the learner that a resumed session's
/// replay must reproduce.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// Steps (evaluative) or queries (preference) done.
    pub progress: u64,
    /// Queries answered so far (all of them replayable from the store).
    pub answers: u64,
    pub digest: String,
    /// The learner's safetensors bytes (evaluative sessions) or the posterior's (preference
    /// sessions), written to `<data dir>/checkpoints/<id>.safetensors`.
    pub weights: Option<Vec<u8>>,
    /// What a session on a remote env resumes from (which cannot replay from step 0): its
    /// whole run (evaluative) or the trajectories it recorded (preference). Kept, latest only,
    /// beside the session's other checkpoints.
    pub resume: Option<Vec<u8>>,
}

/// Everything a session reports, in order.
#[derive(Clone, Debug)]
pub enum SessionEvent {
    /// The session built its run and is about to take its first step (after `replayed` stored
    /// answers it will not ask again).
    Started {
        replayed: u64,
        /// The scene graph its queries are phrased in (a remote env's own task: the one it
        /// declared).
        graph: SceneGraph,
    },
    Frame(Box<Frame>),
    /// A query for people: the session now waits for `Control::Answer` with this `seq`.
    Query {
        seq: u64,
        step: u64,
        abstract_state: u32,
        content: Box<QueryContent>,
        /// What the learner saw (stored for datasets), and a remote session's step as the run
        /// stored it (stored with the query, before anyone can answer it).
        record: Box<QueryRecord>,
    },
    /// A synthetic trainer's query and answer together (nobody waits).
    Answered {
        seq: u64,
        step: u64,
        abstract_state: u32,
        kind: QueryKind,
        value: AnswerValue,
        record: Box<QueryRecord>,
    },
    Episode(EpisodeRecord),
    /// A preference session's posterior after an answer.
    Alignment {
        queries: u64,
        alignment: f64,
        alignment_of_mean: f64,
    },
    /// Steps or queries done (sent at most a few times a second).
    Progress {
        progress: u64,
    },
    Checkpoint(Checkpoint),
    /// The learner took in revision `revision` of query `seq`'s answer (an undo, or the answer
    /// given after it) when `progress` steps or queries were done: a resume replays it there.
    Revised {
        seq: u64,
        revision: u32,
        progress: u64,
    },
    Ended(Ending),
}

/// Where a session thread sends its events. `send` never blocks for long.
pub trait SessionSink: Send + Sync {
    fn send(&self, event: SessionEvent);
}

/// Watches a session step by step on its own thread (the server's Rerun recorder implements
/// it). Calls must be cheap: an implementation hands the data to its own thread, and flushes
/// when dropped (the session drops it before reporting its end).
pub trait Observer: Send {
    /// An episode starts at `step` with this static scene.
    fn episode_start(&mut self, episode: u64, step: u64, geometry: &Geometry);
    /// Transition `step` (0-based) ended in `state`.
    fn step(
        &mut self,
        step: u64,
        episode: u64,
        state: &RenderState,
        reward: f32,
        cumulative_return: f64,
        abstract_state: AbstractState,
    );
    /// Query `seq` was asked at `step` (a replayed one too: a resumed session's recording is
    /// whole).
    fn query(&mut self, step: u64, seq: u64, kind: QueryKind, text: String);
    fn answer(&mut self, step: u64, seq: u64, value: AnswerValue);
    /// The answer to query `seq` was undone (`None`) or given again after an undo, taking
    /// effect at `progress` (steps or queries done).
    fn revision(&mut self, progress: u64, seq: u64, value: Option<AnswerValue>);
}

/// What the async side tells a session thread.
#[derive(Clone, Debug, PartialEq)]
pub enum Control {
    /// The committed answer to query `seq`.
    Answer { seq: u64, value: AnswerValue },
    /// A trainer undid the answer to query `seq` (`value: None`) or answered it again after an
    /// undo; committed already. The session applies it at its next step (or query).
    Revise(Revision),
    /// Stop for good (a researcher's request).
    Stop,
    /// Checkpoint and end as interrupted (graceful shutdown); resumable.
    Shutdown,
}

/// A change to an answer the learner already used: the undo, then the new answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Revision {
    pub seq: u64,
    /// 1 for the first undo, 2 for the answer after it, and so on.
    pub revision: u32,
    /// `None`: undone (the learner uses "no feedback" / no answer until a new one comes).
    pub value: Option<AnswerValue>,
}

/// A revision as stored, replayed by a resumed session at the progress it was first applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StoredRevision {
    pub revision: Revision,
    /// `None`: committed but never applied (the server stopped first): applied once the replay
    /// is over.
    pub applied_at: Option<u64>,
}

/// Why a session must leave its loop early.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Halt {
    Stop,
    Shutdown,
}

/// The session thread's end of the control channel.
pub struct Controls {
    rx: Receiver<Control>,
    halt: Option<Halt>,
    /// Revisions received and not yet applied, in the order they were committed.
    revisions: std::collections::VecDeque<Revision>,
}

impl Controls {
    pub fn new(rx: Receiver<Control>) -> Self {
        Self {
            rx,
            halt: None,
            revisions: Default::default(),
        }
    }

    /// The revisions received so far (during waits and sleeps too), oldest first.
    pub fn take_revisions(&mut self) -> impl Iterator<Item = Revision> + '_ {
        self.poll();
        self.revisions.drain(..)
    }

    /// A stop or shutdown received so far, without waiting. Answers arriving outside a wait are
    /// stale (the query was answered by a timeout or replay) and dropped.
    pub fn poll(&mut self) -> Option<Halt> {
        while self.halt.is_none() {
            match self.rx.try_recv() {
                Ok(c) => self.note(c),
                Err(std::sync::mpsc::TryRecvError::Empty) => break,
                // The server dropped the session: treat as a shutdown.
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    self.halt = Some(Halt::Shutdown)
                }
            }
        }
        self.halt
    }

    fn note(&mut self, control: Control) {
        match control {
            Control::Stop => self.halt = Some(Halt::Stop),
            Control::Shutdown => self.halt = Some(Halt::Shutdown),
            Control::Answer { .. } => {}
            Control::Revise(r) => self.revisions.push_back(r),
        }
    }

    /// Block until the answer to `seq` or a halt. The async side owns timeouts (it commits a
    /// timeout answer and sends it here), so that exactly one answer per query is ever stored.
    pub fn wait_answer(&mut self, seq: u64) -> Result<AnswerValue, Halt> {
        loop {
            if let Some(h) = self.halt {
                return Err(h);
            }
            match self.rx.recv_timeout(Duration::from_secs(3600)) {
                Ok(Control::Answer { seq: s, value }) if s == seq => return Ok(value),
                Ok(other) => self.note(other),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => self.halt = Some(Halt::Shutdown),
            }
        }
    }

    /// Sleep up to `d`, waking early for a halt.
    pub fn sleep(&mut self, d: Duration) -> Option<Halt> {
        if self.halt.is_some() {
            return self.halt;
        }
        match self.rx.recv_timeout(d) {
            Ok(c) => {
                self.note(c);
                self.poll()
            }
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => {
                self.halt = Some(Halt::Shutdown);
                self.halt
            }
        }
    }

    pub fn halted(&self) -> Option<Halt> {
        self.halt
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answer_values_parse_from_the_wire_forms() {
        let v: AnswerValue = serde_json::from_str("-1").unwrap();
        assert_eq!(v.as_evaluation(), Some(Evaluation::Bad));
        let v: AnswerValue = serde_json::from_str("\"equal\"").unwrap();
        assert_eq!(v.as_preference(), Some(Preference::Equal));
        assert!(serde_json::from_str::<AnswerValue>("\"maybe\"").is_err());
        assert!(!AnswerValue::Evaluation(2).fits(QueryKind::Evaluative));
        assert!(!AnswerValue::Evaluation(1).fits(QueryKind::Preference));
        assert_eq!(
            serde_json::to_string(&AnswerValue::timeout(QueryKind::Preference)).unwrap(),
            "\"skip\""
        );
    }

    #[test]
    fn a_wait_returns_the_matching_answer_and_drops_stale_ones() {
        let (tx, rx) = std::sync::mpsc::channel();
        let mut c = Controls::new(rx);
        tx.send(Control::Answer {
            seq: 3,
            value: AnswerValue::Evaluation(1),
        })
        .unwrap();
        tx.send(Control::Answer {
            seq: 4,
            value: AnswerValue::Evaluation(-1),
        })
        .unwrap();
        assert_eq!(c.wait_answer(4), Ok(AnswerValue::Evaluation(-1)));
        // A revision that arrives while the session waits is kept for its next step.
        let undo = Revision {
            seq: 2,
            revision: 1,
            value: None,
        };
        tx.send(Control::Revise(undo)).unwrap();
        tx.send(Control::Answer {
            seq: 5,
            value: AnswerValue::Evaluation(0),
        })
        .unwrap();
        assert_eq!(c.wait_answer(5), Ok(AnswerValue::Evaluation(0)));
        assert_eq!(c.take_revisions().collect::<Vec<_>>(), vec![undo]);
        assert_eq!(c.take_revisions().count(), 0);
        tx.send(Control::Stop).unwrap();
        assert_eq!(c.wait_answer(6), Err(Halt::Stop));
        drop(tx);
        assert_eq!(c.poll(), Some(Halt::Stop));
    }
}
