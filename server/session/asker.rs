//! Who answers a session's queries: stored answers first (after a resume), then people through
//! the control channel, or a synthetic trainer whose answers are reported to be stored; and the
//! session's observer (the recording) sees every query and answer. Evaluative queries are
//! judged here; preference pairs are compared in `preference_asker`.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::Arc;

use crate::guidance::evaluative_run::AskedStep;
use crate::guidance::evaluative_trainer::{
    Evaluation, EvaluativeQuery, EvaluativeTrainer, RestoreError,
};
use crate::rl::Sac;
use crate::scene_graph::SceneGraph;
use crate::sim::Task;

use super::catch_up::{CatchUp, GivenUp};
use super::error::{ExpertError, SessionError};
use super::events::{
    AnswerValue, Controls, Halt, Observer, QueryKind, Revision, SessionEvent, SessionSink,
    StoredRevision,
};
use super::query::{FrameHistory, QueryContent, QueryData, QueryRecord};
use super::remote::StoredMoment;
use super::runner::SessionContext;

/// Load an expert written by `dualrep expert` (the synthetic evaluative trainer consults it).
pub fn load_expert(path: &Path, task: &str) -> Result<Sac, ExpertError> {
    let bytes = std::fs::read(path).map_err(|error| ExpertError::Missing {
        path: path.to_path_buf(),
        task: task.to_string(),
        error,
    })?;
    Sac::from_safetensors(&bytes).map_err(|error| ExpertError::Unreadable {
        path: path.to_path_buf(),
        error,
    })
}

/// The expert of `task`: `<dir>/<task>.safetensors` when a folder is given, else the one the
/// binary ships.
pub fn load_task_expert(dir: Option<&Path>, task: Task) -> Result<Sac, ExpertError> {
    match dir {
        Some(dir) => load_expert(&dir.join(format!("{task}.safetensors")), task.id()),
        None => {
            let bytes = crate::shipped::expert(task).ok_or(ExpertError::NotShipped(task))?;
            Sac::from_safetensors(&bytes).map_err(ExpertError::ShippedUnreadable)
        }
    }
}

/// Asks the session's queries: replays stored answers first, then asks people through the
/// control channel (human sessions) or reports a synthetic trainer's answers (so they are stored).
pub(super) struct Asker {
    pub(super) sink: Arc<dyn SessionSink>,
    pub(super) controls: Controls,
    pub(super) replay: VecDeque<AnswerValue>,
    /// Stored revisions (undos and the answers after them), by the progress they apply at.
    replay_revisions: VecDeque<StoredRevision>,
    pub(super) seq: u64,
    /// A halt came while a query was open: the last answer was not given by anyone.
    pub(super) aborted: bool,
    /// The env failed while a query was being prepared (a remote env replaying a clip): the
    /// query was not asked, and the session ends with this reason.
    pub(super) fault: Option<SessionError>,
    /// A person answered since the last call of [`Asker::take_answered`].
    answered_live: bool,
    /// A remote session resumed from a checkpoint: the queries stored after it, from `seq` on,
    /// that the run may meet again (see `remote`).
    catch_up: CatchUp,
    /// A remote session: each evaluative query reports its step as the run stores it, so that
    /// a run resumed from an earlier checkpoint can take the answered ones back in.
    pub(super) keep_steps: bool,
    pub(super) observer: Option<Box<dyn Observer>>,
}

impl Asker {
    /// The session's asker, once its run is built: tells the server the session started (and
    /// which scene graph its queries are phrased in).
    pub(super) fn start(
        ctx: SessionContext,
        observer: Option<Box<dyn Observer>>,
        graph: SceneGraph,
    ) -> Self {
        ctx.sink.send(SessionEvent::Started {
            replayed: ctx.stored_answers.len() as u64,
            graph,
        });
        Self {
            sink: ctx.sink,
            controls: ctx.controls,
            replay: ctx.stored_answers.into(),
            replay_revisions: ctx.stored_revisions.into(),
            seq: 0,
            aborted: false,
            fault: None,
            answered_live: false,
            catch_up: CatchUp::default(),
            keep_steps: false,
            observer,
        }
    }

    /// Go on from session query number `next` (a remote session resumed from a checkpoint
    /// after `steps` steps, with `stored_end` query numbers stored): no replay from step 0, but
    /// a catch-up on the stored queries numbered `next` or later, whose moments the run may
    /// meet again; and apply the stored revisions the checkpoint does not hold (applied at
    /// `steps` or later, or never) once the catch-up is over.
    pub(super) fn continue_at(
        &mut self,
        next: u64,
        stored_end: u64,
        steps: u64,
        stored: Vec<StoredMoment>,
    ) {
        self.seq = next;
        self.catch_up = CatchUp::new(next, stored_end, stored);
        self.replay.clear();
        self.replay_revisions = std::mem::take(&mut self.replay_revisions)
            .into_iter()
            .filter(|r| r.applied_at.is_none_or(|at| at >= steps))
            .map(|r| StoredRevision {
                applied_at: None,
                ..r
            })
            .collect();
    }

    /// Whether the run is still catching up on queries stored after its checkpoint.
    pub(super) fn catching_up(&self) -> bool {
        self.catch_up.active(self.seq)
    }

    /// The stored answer to the moment `(step, action)` the run asks about, if it is the next
    /// stored query's: it is taken without asking (the caller reports it with
    /// [`Asker::replayed`]). A stored query that was left unanswered is asked again under its
    /// own number. Any other moment ends the catch-up.
    fn caught_up(&mut self, step: u64, action: &[f32]) -> Option<AnswerValue> {
        self.catch_up
            .meet(&mut self.seq, step, action)
            .and_then(|m| m.value)
    }

    /// End the catch-up once the run is past the next stored query's step (`steps` steps done)
    /// without having met it.
    pub(super) fn settle_catch_up(&mut self, steps: u64) {
        self.catch_up.settle(&mut self.seq, steps);
    }

    /// The stored queries the catch-up gave up on since the last call (the run did not meet
    /// their moments again).
    pub(super) fn take_given_up(&mut self) -> Vec<GivenUp> {
        self.catch_up.take_given_up()
    }

    /// A stored answer is the next query's (replayed or caught up on): nobody is asked.
    fn replayed(
        &mut self,
        step: u64,
        kind: QueryKind,
        describe: String,
        value: AnswerValue,
    ) -> AnswerValue {
        let seq = self.seq;
        self.seq += 1;
        self.observe(|o| o.query(step, seq, kind, describe));
        self.answered(step, seq, value)
    }

    /// Whether a person answered since the last call.
    pub(super) fn take_answered(&mut self) -> bool {
        std::mem::take(&mut self.answered_live)
    }

    fn observe(&mut self, f: impl FnOnce(&mut dyn Observer)) {
        if let Some(o) = self.observer.as_deref_mut() {
            f(o);
        }
    }

    /// The answer to query `seq` is known: record it.
    fn answered(&mut self, step: u64, seq: u64, value: AnswerValue) -> AnswerValue {
        self.observe(|o| o.answer(step, seq, value));
        value
    }

    /// How the session ends when its last query was aborted ([`Asker::aborted`]; a shutdown
    /// if no halt came): nobody gave that answer. `None` if it was not.
    pub(super) fn abort_halt(&self) -> Option<Halt> {
        self.aborted
            .then(|| self.controls.halted().unwrap_or(Halt::Shutdown))
    }

    pub(super) fn replaying(&self) -> bool {
        !self.replay.is_empty()
    }

    /// The revisions the learner takes in now, at `progress`, in order: stored ones where they
    /// were first applied (those never applied once the replay is over), then those trainers
    /// sent since the last call.
    pub(super) fn due_revisions(&mut self, progress: u64) -> Vec<Revision> {
        let mut due = Vec::new();
        while let Some(r) = self.replay_revisions.front() {
            let now = match r.applied_at {
                Some(at) => at <= progress,
                None => !self.replaying() && !self.catching_up(),
            };
            if !now {
                break;
            }
            due.push(r.revision);
            self.replay_revisions.pop_front();
        }
        due.extend(self.controls.take_revisions());
        for r in &due {
            let value = r.value;
            self.observe(|o| o.revision(progress, r.seq, value));
        }
        due
    }

    /// A person's answer to the next query (`None` if the session halted while waiting).
    pub(super) fn ask(
        &mut self,
        step: u64,
        abstract_state: u32,
        kind: QueryKind,
        describe: String,
        content: impl FnOnce() -> Result<(QueryContent, QueryRecord), SessionError>,
    ) -> Option<AnswerValue> {
        if let Some(v) = self.replay.pop_front() {
            return Some(self.replayed(step, kind, describe, v));
        }
        if self.controls.halted().is_some() {
            self.aborted = true;
            return None;
        }
        let (content, record) = match content() {
            Ok(c) => c,
            Err(reason) => {
                self.fault = Some(reason);
                self.aborted = true;
                return None;
            }
        };
        let seq = self.seq;
        self.seq += 1;
        self.observe(|o| o.query(step, seq, kind, describe));
        self.sink.send(SessionEvent::Query {
            seq,
            step,
            abstract_state,
            content: Box::new(content),
            record: Box::new(record),
        });
        match self.controls.wait_answer(seq) {
            Ok(v) => {
                self.answered_live = true;
                Some(self.answered(step, seq, v))
            }
            Err(_) => {
                self.aborted = true;
                None
            }
        }
    }

    /// A synthetic trainer answered the next query.
    pub(super) fn report(
        &mut self,
        step: u64,
        abstract_state: u32,
        kind: QueryKind,
        describe: String,
        value: AnswerValue,
        record: QueryRecord,
    ) {
        self.replay.pop_front();
        let seq = self.seq;
        self.observe(|o| o.query(step, seq, kind, describe));
        self.answered(step, seq, value);
        self.sink.send(SessionEvent::Answered {
            seq: self.seq,
            step,
            abstract_state,
            kind,
            value,
            record: Box::new(record),
        });
        self.seq += 1;
    }
}

/// Who judges an evaluative session's steps.
pub(super) enum Judge {
    /// People: the clip of the episode so far goes with each query.
    Human {
        history: FrameHistory,
        graph: SceneGraph,
    },
    /// The expert oracle (EF, DREF) or nobody (SAC).
    Synthetic {
        oracle: Box<dyn EvaluativeTrainer>,
        graph: SceneGraph,
    },
}

pub(super) struct EvaluativeAsker {
    pub(super) asker: Asker,
    pub(super) judge: Judge,
}

impl EvaluativeTrainer for EvaluativeAsker {
    /// The synthetic oracle's state (its random stream), for a remote session's run checkpoint.
    fn checkpoint_state(&self) -> serde_json::Value {
        match &self.judge {
            Judge::Synthetic { oracle, .. } => oracle.checkpoint_state(),
            Judge::Human { .. } => serde_json::Value::Null,
        }
    }

    fn restore_state(&mut self, state: &serde_json::Value) -> Result<(), RestoreError> {
        match &mut self.judge {
            Judge::Synthetic { oracle, .. } => oracle.restore_state(state),
            Judge::Human { .. } => Ok(()),
        }
    }

    fn evaluate(&mut self, q: &EvaluativeQuery<'_>) -> Evaluation {
        // A resumed remote run meeting a moment answered after its checkpoint: the stored
        // answer, asked of nobody (the oracle is still consulted, so that its random stream
        // goes on as it did the first time).
        if let Some(stored) = self.asker.caught_up(q.step, q.action) {
            let describe = match &mut self.judge {
                Judge::Human { graph, .. } => describe_evaluative(graph, q),
                Judge::Synthetic { oracle, graph } => {
                    oracle.evaluate(q);
                    if self.asker.observer.is_some() {
                        describe_evaluative(graph, q)
                    } else {
                        String::new()
                    }
                }
            };
            return self
                .asker
                .replayed(q.step, QueryKind::Evaluative, describe, stored)
                .as_evaluation()
                .unwrap_or(Evaluation::NoFeedback);
        }
        let keep_steps = self.asker.keep_steps;
        let record = || QueryRecord {
            data: transition(q),
            asked: keep_steps.then(|| AskedStep::of(q)),
        };
        match &mut self.judge {
            Judge::Human { history, graph } => self
                .asker
                .ask(
                    q.step,
                    q.abstract_state.0,
                    QueryKind::Evaluative,
                    describe_evaluative(graph, q),
                    || {
                        let content = QueryContent::Evaluative {
                            clip: history.clip().expect("the history starts with the episode"),
                            action: q.action.to_vec(),
                            holding: graph.holding(q.abstract_state),
                            predicted: q.predicted,
                        };
                        Ok((content, record()))
                    },
                )
                .and_then(AnswerValue::as_evaluation)
                .unwrap_or(Evaluation::NoFeedback),
            Judge::Synthetic { oracle, graph } => {
                let e = oracle.evaluate(q);
                // Described only for the recording: a long synthetic run asks thousands.
                let describe = if self.asker.observer.is_some() {
                    describe_evaluative(graph, q)
                } else {
                    String::new()
                };
                self.asker.report(
                    q.step,
                    q.abstract_state.0,
                    QueryKind::Evaluative,
                    describe,
                    AnswerValue::evaluation(e),
                    record(),
                );
                e
            }
        }
    }
}

/// An evaluative query's transition, for datasets.
fn transition(q: &EvaluativeQuery<'_>) -> QueryData {
    QueryData::Evaluative {
        observation: q.obs.to_vec(),
        action: q.action.to_vec(),
        reward: q.reward,
        next_observation: q.next_obs.to_vec(),
    }
}

/// A query in words, for the recording.
fn describe_evaluative(graph: &SceneGraph, q: &EvaluativeQuery<'_>) -> String {
    let action: Vec<String> = q.action.iter().map(|a| format!("{a:+.2}")).collect();
    format!(
        "step {}: was action [{}] good? holding: {}",
        q.step,
        action.join(", "),
        graph.holding(q.abstract_state).join(", ")
    )
}
