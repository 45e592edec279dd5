//! A session's owner on a paused clock: the test plays the session thread (its event channel
//! and its controls), so answer deadlines and the undo window are checked to the millisecond
//! without waiting for them. The clock moves only by `tokio::time::advance`: a blocking task
//! held for the whole test keeps tokio from jumping ahead while the runtime waits on SQLite's
//! own thread.

use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Duration;

use tokio::sync::mpsc::{UnboundedSender, unbounded_channel};

use super::handle::{AnswerReply, SessionHandle};
use super::owner::Owner;
use super::{Hub, HubConfig, UNDO_WINDOW};
use crate::protocol::ErrorCode;
use crate::session::{AnswerValue, Control, QueryContent, SessionEvent, SessionSpec};
use crate::store::{NewSession, Status, Store};

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
    let (mut owner, handle, commands) = Owner::new(hub, "s1".into(), spec, TIMEOUT);
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
    /// Ask query `seq` and return its id on the wire once the owner has stored and opened it
    /// (the session's query number: `seq` itself).
    async fn ask(&self, seq: u64) -> u64 {
        self.events
            .send(SessionEvent::Query {
                seq,
                step: seq * 10,
                abstract_state: 1,
                content: Box::new(content()),
            })
            .unwrap();
        self.wait_for(|s| s == Status::Waiting).await;
        let joined = self.handle.join().await.unwrap();
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
        self.handle.join().await.unwrap();
    }
}

#[tokio::test(start_paused = true)]
async fn a_query_counts_as_no_feedback_exactly_at_its_timeout() {
    let h = harness().await;
    h.events
        .send(SessionEvent::Started {
            replayed: 0,
            graph: crate::scene_graph::SceneGraph::Reaching,
        })
        .unwrap();
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
    assert_eq!(answers[0].who, crate::session::Answerer::Timeout);
    // Late: the timeout's answer stands.
    assert!(matches!(
        h.handle.answer(id, AnswerValue::Evaluation(1)).await,
        AnswerReply::Refused(e) if e.code == ErrorCode::AlreadyAnswered
    ));
}

#[tokio::test(start_paused = true)]
async fn an_answer_before_the_timeout_wins_and_no_timeout_follows() {
    let h = harness().await;
    h.events
        .send(SessionEvent::Started {
            replayed: 0,
            graph: crate::scene_graph::SceneGraph::Reaching,
        })
        .unwrap();
    let id = h.ask(0).await;
    tokio::time::advance(TIMEOUT / 2).await;
    assert_eq!(
        h.handle.answer(id, AnswerValue::Evaluation(-1)).await,
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
    assert_eq!(answers[0].who, crate::session::Answerer::Trainer);
}

#[tokio::test(start_paused = true)]
async fn an_answer_can_be_undone_within_the_window_and_not_after() {
    let h = harness().await;
    h.events
        .send(SessionEvent::Started {
            replayed: 0,
            graph: crate::scene_graph::SceneGraph::Reaching,
        })
        .unwrap();
    // Within the window: undone, the session told, and the query open again with a new
    // deadline.
    let first = h.ask(0).await;
    h.handle.answer(first, AnswerValue::Evaluation(1)).await;
    h.control().await;
    tokio::time::advance(UNDO_WINDOW - Duration::from_millis(1)).await;
    h.handle.undo(first).await.unwrap();
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
    h.handle.answer(second, AnswerValue::Evaluation(-1)).await;
    h.control().await;
    tokio::time::advance(UNDO_WINDOW + Duration::from_millis(1)).await;
    let refused = h.handle.undo(second).await.unwrap_err();
    assert_eq!(refused.code, ErrorCode::UndoUnavailable);
    assert!(refused.message.contains("30 s"), "{}", refused.message);
    let answers = h.store.answers("s1").await.unwrap();
    assert_eq!(answers[1].value, AnswerValue::Evaluation(-1));
}

#[tokio::test(start_paused = true)]
async fn the_end_is_stored_and_published_and_open_queries_close() {
    let h = harness().await;
    h.events
        .send(SessionEvent::Started {
            replayed: 0,
            graph: crate::scene_graph::SceneGraph::Reaching,
        })
        .unwrap();
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
    let reply = handle.answer(id, AnswerValue::Evaluation(1)).await;
    assert!(matches!(reply, AnswerReply::Refused(e) if e.code == ErrorCode::SessionEnded));
}
