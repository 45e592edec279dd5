//! A session's owner on a paused clock: the test plays the session thread (its event channel
//! and its controls), so answer deadlines and the undo window are checked to the millisecond
//! without waiting for them. The clock moves only by `tokio::time::advance`: a blocking task
//! held for the whole test keeps tokio from jumping ahead while the runtime waits on SQLite's
//! own thread.

use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Duration;

use tokio::sync::mpsc::{UnboundedSender, unbounded_channel};

use super::handle::{AnswerReply, Identity, SessionHandle};
use super::owner::Owner;
use super::{Hub, HubConfig, UNDO_WINDOW};
use crate::protocol::ErrorCode;
use crate::session::{
    AnswerValue, Answerer, Control, QueryContent, QueryData, QueryRecord, SessionEvent,
    SessionPlan, SessionSpec,
};
use crate::store::{AddTrainer, NewSession, Status, Store, TrainerOrigin};

/// The anonymous trainer on the session's shared link.
const ANON: Identity = Identity::Anonymous;

const TIMEOUT: Duration = Duration::from_secs(20);

/// A human DREF session on Reaching, served by its owner; the test is its session thread.
struct Harness {
    handle: SessionHandle,
    events: UnboundedSender<SessionEvent>,
    controls: Receiver<Control>,
    store: Store,
    _dir: tempfile::TempDir,
    /// Dropped with the harness: ends the blocking task that holds the clock.
    _clock: std::sync::mpsc::Sender<()>,
}

async fn harness() -> Harness {
    harness_with(serde_json::json!({})).await
}

/// A named trainer of session s1.
async fn trainer(store: &Store, name: &str) -> Identity {
    match store
        .add_trainer("s1", name, &format!("token-{name}"), TrainerOrigin::Invited)
        .await
        .unwrap()
    {
        AddTrainer::Added(t) => Identity::Trainer(t.as_ref()),
        AddTrainer::NameTaken => panic!("{name} is taken"),
    }
}

async fn harness_with(params: serde_json::Value) -> Harness {
    let (clock, held) = std::sync::mpsc::channel::<()>();
    tokio::task::spawn_blocking(move || {
        let _ = held.recv();
    });
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(dir.path()).await.unwrap();
    let hub = Hub::new(
        store.clone(),
        HubConfig {
            data_dir: dir.path().to_path_buf(),
            models_dir: None,
            max_running: 1,
            rerun_connect: None,
            session_stack_size: None,
        },
    );
    let spec: SessionSpec = serde_json::from_value(serde_json::json!({
        "task": "reaching", "method": "dref", "trainer": "human", "seed": 0, "budget": 1000,
        "params": params,
    }))
    .unwrap();
    let config = serde_json::to_value(&spec).unwrap();
    store
        .insert_session(NewSession {
            id: "s1",
            task: "reaching",
            method: "dref",
            trainer: "human",
            seed: 0,
            budget: 1000,
            config: &config,
            trainer_token: "t",
        })
        .await
        .unwrap();
    let (mut owner, handle, commands) = Owner::new(
        hub,
        "s1".into(),
        SessionPlan::new(spec).unwrap(),
        TIMEOUT,
        0,
    );
    let (control_tx, controls) = std::sync::mpsc::channel();
    owner.control = Some(control_tx);
    let (events, events_rx) = unbounded_channel();
    tokio::spawn(owner.serve(events_rx, commands));
    Harness {
        handle,
        events,
        controls,
        store,
        _dir: dir,
        _clock: clock,
    }
}

/// A one-frame evaluative query.
fn content() -> QueryContent {
    let mut env = crate::sim::Task::Reaching.make_env();
    env.reset(0);
    QueryContent::Evaluative {
        clip: crate::session::Clip {
            geometry: env.geometry(),
            frames: vec![env.render()],
        },
        action: vec![0.0; env.spec().action_space.dim()],
        holding: Vec::new(),
        predicted: 0.0,
    }
}

impl Harness {
    /// The session thread says it has started, with nothing replayed.
    fn start(&self) {
        self.events
            .send(SessionEvent::Started {
                replayed: 0,
                graph: crate::scene_graph::SceneGraph::Reaching,
            })
            .unwrap();
    }

    /// Ask query `seq` and return its id on the wire once the owner has stored and opened it
    /// (the session's query number: `seq` itself).
    async fn ask(&self, seq: u64) -> u64 {
        self.events
            .send(SessionEvent::Query {
                seq,
                step: seq * 10,
                abstract_state: 1,
                content: Box::new(content()),
                record: Box::new(QueryRecord {
                    data: QueryData::Evaluative {
                        observation: vec![0.0; 3],
                        action: vec![0.5; 3],
                        reward: 0.0,
                        next_observation: vec![0.1; 3],
                    },
                    asked: None,
                }),
            })
            .unwrap();
        self.wait_for(|s| s == Status::Waiting).await;
        let joined = self.handle.join(&ANON).await.unwrap();
        let query: serde_json::Value =
            serde_json::from_str(joined.catch_up.last().unwrap()).unwrap();
        assert_eq!(query["type"], "query");
        assert_eq!(query["id"], seq);
        seq
    }

    /// Wait (on the owner, not the clock) until the published status satisfies `ok`.
    async fn wait_for(&self, ok: impl Fn(Status) -> bool) {
        let mut snapshot = self.handle.snapshot.clone();
        snapshot.wait_for(|s| ok(s.status)).await.unwrap();
    }

    /// The next control the session thread would get, waiting for the owner to send it.
    async fn control(&self) -> Control {
        loop {
            match self.controls.try_recv() {
                Ok(c) => return c,
                Err(TryRecvError::Empty) => tokio::task::yield_now().await,
                Err(TryRecvError::Disconnected) => panic!("the owner went"),
            }
        }
    }

    /// Let the owner run whatever is due, without moving the clock.
    async fn settle(&self) {
        // A join is answered only after every command and event before it.
        self.handle.join(&ANON).await.unwrap();
    }
}

#[tokio::test(start_paused = true)]
async fn a_query_counts_as_no_feedback_exactly_at_its_timeout() {
    let h = harness().await;
    h.start();
    let id = h.ask(0).await;
    tokio::time::advance(TIMEOUT - Duration::from_millis(1)).await;
    h.settle().await;
    assert_eq!(h.controls.try_recv(), Err(TryRecvError::Empty));
    assert_eq!(h.handle.status(), Status::Waiting);
    // `waiting` is live state only: the database keeps `running` (no write per query).
    let stored = h.store.session("s1").await.unwrap().unwrap().status;
    assert_eq!(stored, Status::Running);
    tokio::time::advance(Duration::from_millis(1)).await;
    assert_eq!(
        h.control().await,
        Control::Answer {
            seq: 0,
            value: AnswerValue::Evaluation(0)
        }
    );
    h.wait_for(|s| s == Status::Running).await;
    let answers = h.store.answers("s1").await.unwrap();
    assert_eq!(answers.len(), 1);
    assert_eq!(answers[0].query_id, id as i64);
    assert_eq!(answers[0].who, Answerer::Timeout);
    // Late: the timeout's answer stands.
    assert!(matches!(
        h.handle.answer(id, AnswerValue::Evaluation(1), &ANON).await,
        AnswerReply::Refused(e) if e.code == ErrorCode::AlreadyAnswered
    ));
}

#[tokio::test(start_paused = true)]
async fn an_answer_before_the_timeout_wins_and_no_timeout_follows() {
    let h = harness().await;
    h.start();
    let id = h.ask(0).await;
    tokio::time::advance(TIMEOUT / 2).await;
    assert_eq!(
        h.handle
            .answer(id, AnswerValue::Evaluation(-1), &ANON)
            .await,
        AnswerReply::Ack(AnswerValue::Evaluation(-1))
    );
    assert_eq!(
        h.control().await,
        Control::Answer {
            seq: 0,
            value: AnswerValue::Evaluation(-1)
        }
    );
    tokio::time::advance(TIMEOUT).await;
    h.settle().await;
    assert_eq!(h.controls.try_recv(), Err(TryRecvError::Empty));
    let answers = h.store.answers("s1").await.unwrap();
    assert_eq!(answers[0].value, AnswerValue::Evaluation(-1));
    assert_eq!(answers[0].who, Answerer::Trainer);
}

#[tokio::test(start_paused = true)]
async fn an_answer_can_be_undone_within_the_window_and_not_after() {
    let h = harness().await;
    h.start();
    // Within the window: undone, the session told, and the query open again with a new
    // deadline.
    let first = h.ask(0).await;
    h.handle
        .answer(first, AnswerValue::Evaluation(1), &ANON)
        .await;
    h.control().await;
    tokio::time::advance(UNDO_WINDOW - Duration::from_millis(1)).await;
    h.handle.undo(first, &ANON).await.unwrap();
    match h.control().await {
        Control::Revise(r) => assert_eq!((r.seq, r.revision, r.value), (0, 1, None)),
        other => panic!("expected a revision, got {other:?}"),
    }
    // The reopened query expires like any query, as the answer's next revision.
    tokio::time::advance(TIMEOUT).await;
    match h.control().await {
        Control::Revise(r) => assert_eq!(
            (r.seq, r.revision, r.value),
            (0, 2, Some(AnswerValue::Evaluation(0)))
        ),
        other => panic!("expected a revision, got {other:?}"),
    }
    // Past the window: the answer stands.
    let second = h.ask(1).await;
    h.handle
        .answer(second, AnswerValue::Evaluation(-1), &ANON)
        .await;
    h.control().await;
    tokio::time::advance(UNDO_WINDOW + Duration::from_millis(1)).await;
    let refused = h.handle.undo(second, &ANON).await.unwrap_err();
    assert_eq!(refused.code, ErrorCode::UndoUnavailable);
    assert!(refused.message.contains("30 s"), "{}", refused.message);
    let answers = h.store.answers("s1").await.unwrap();
    assert_eq!(answers[1].value, AnswerValue::Evaluation(-1));
}

#[tokio::test(start_paused = true)]
async fn the_end_is_stored_and_published_and_open_queries_close() {
    let h = harness().await;
    h.start();
    let id = h.ask(0).await;
    h.events
        .send(SessionEvent::Ended(crate::session::Ending::Stopped))
        .unwrap();
    let Harness {
        handle,
        events,
        store,
        ..
    } = h;
    drop(events); // the session thread is done
    let mut snapshot = handle.snapshot.clone();
    snapshot
        .wait_for(|s| s.status == Status::Stopped)
        .await
        .unwrap();
    assert_eq!(
        store.session("s1").await.unwrap().unwrap().status,
        Status::Stopped
    );
    // The owner has gone: answers are refused as ended, not lost in a queue.
    let reply = handle.answer(id, AnswerValue::Evaluation(1), &ANON).await;
    assert!(matches!(reply, AnswerReply::Refused(e) if e.code == ErrorCode::SessionEnded));
}

#[tokio::test(start_paused = true)]
async fn a_named_answer_stores_who_and_only_its_trainer_may_undo_it() {
    let h = harness().await;
    let (ada, bo) = (
        trainer(&h.store, "ada").await,
        trainer(&h.store, "bo").await,
    );
    h.start();
    let id = h.ask(0).await;
    h.handle.answer(id, AnswerValue::Evaluation(1), &ada).await;
    h.control().await;
    let refused = h.handle.undo(id, &bo).await.unwrap_err();
    assert_eq!(refused.code, ErrorCode::UndoUnavailable);
    assert!(
        refused.message.contains("another trainer"),
        "{}",
        refused.message
    );
    // The shared link cannot undo a named trainer's answer either; the trainer can.
    assert!(h.handle.undo(id, &ANON).await.is_err());
    h.handle.undo(id, &ada).await.unwrap();
    let answers = h.store.answers("s1").await.unwrap();
    assert_eq!(answers[0].trainer.as_deref(), Some("ada"));
}

#[tokio::test(start_paused = true)]
async fn k_named_trainers_answer_each_query_and_their_answers_combine() {
    let h = harness_with(serde_json::json!({"answers_per_query": 2, "combine": "mean"})).await;
    let (ada, bo) = (
        trainer(&h.store, "ada").await,
        trainer(&h.store, "bo").await,
    );
    h.start();
    let id = h.ask(0).await;
    // Without a name there is no answer to count.
    assert!(matches!(
        h.handle.answer(id, AnswerValue::Evaluation(1), &ANON).await,
        AnswerReply::Refused(e) if e.code == ErrorCode::IdentityRequired
    ));
    assert_eq!(
        h.handle.answer(id, AnswerValue::Evaluation(1), &ada).await,
        AnswerReply::Ack(AnswerValue::Evaluation(1))
    );
    h.settle().await;
    assert_eq!(
        h.controls.try_recv(),
        Err(TryRecvError::Empty),
        "one of two"
    );
    // A repeat is idempotent, a change of mind is refused; a page of ada's no longer gets it.
    assert_eq!(
        h.handle.answer(id, AnswerValue::Evaluation(1), &ada).await,
        AnswerReply::Ack(AnswerValue::Evaluation(1))
    );
    assert!(matches!(
        h.handle.answer(id, AnswerValue::Evaluation(-1), &ada).await,
        AnswerReply::Refused(e) if e.code == ErrorCode::AlreadyAnswered
    ));
    let joined = h.handle.join(&ada).await.unwrap();
    assert!(
        joined
            .catch_up
            .iter()
            .all(|m| !m.contains("\"type\":\"query\""))
    );
    h.handle.answer(id, AnswerValue::Evaluation(0), &bo).await;
    let Control::Answer { seq: 0, value } = h.control().await else {
        panic!("the combined answer goes to the session")
    };
    assert_eq!(value.as_evaluation().unwrap().value(), 0.5);
    let answers = h.store.answers("s1").await.unwrap();
    assert_eq!(
        (answers[0].who, answers[0].trainer.clone()),
        (Answerer::Trainers, None)
    );
    let people = h.store.person_answers("s1").await.unwrap();
    assert_eq!(people.len(), 2);
    assert_eq!(people[0].value, AnswerValue::Evaluation(1));
    assert!(
        h.handle.undo(id, &ada).await.is_err(),
        "combined answers stand"
    );

    // With one answer when the time runs out, that one is the answer.
    let second = h.ask(1).await;
    h.handle
        .answer(second, AnswerValue::Evaluation(-1), &bo)
        .await;
    tokio::time::advance(TIMEOUT).await;
    assert_eq!(
        h.control().await,
        Control::Answer {
            seq: 1,
            value: AnswerValue::Evaluation(-1)
        }
    );
    // Late: the query has its answer.
    assert!(matches!(
        h.handle.answer(second, AnswerValue::Evaluation(1), &ada).await,
        AnswerReply::Refused(e) if e.code == ErrorCode::AlreadyAnswered
    ));
}
