//! A session on an env that dies mid-run (a small env server on a thread, no Python): the
//! progress the failed session reports is the step its reason names, and a resume answers,
//! and keeps, the progress the session had made. A human session stopped after answering past
//! its checkpoint resumes without asking an answered moment again, and on a robot its learner
//! takes in the answers given after the checkpoint.

use std::collections::BTreeMap;
use std::net::TcpListener;
use std::time::{Duration, Instant};

use crate::support::line_env::{launch_human_on_line, line_hello, line_step, read, write};
use crate::support::server::{Api, serve};
use crate::support::trainer::Trainer;
use dualrep::guidance::evaluative_run::EvaluativeRun;
use serde_json::{Value, json};

/// The env answers this many steps, then closes the connection on the next.
const DIES_AT_STEP: u64 = 157;

/// An env of its own task on a free port that serves one connection and dies at
/// [`DIES_AT_STEP`]; nothing listens there afterwards.
fn dying_env() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("tcp://{}", listener.local_addr().unwrap());
    std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        drop(listener);
        let mut steps = 0u64;
        while let Some(request) = read(&mut s) {
            let reply = match request["type"].as_str().unwrap() {
                "hello" => line_hello("dying-line", 50),
                "reset" => json!({"type": "reset", "obs": [0.0, 0.0]}),
                "step" if steps == DIES_AT_STEP => return,
                "step" => {
                    steps += 1;
                    line_step(&request)
                }
                _ => return,
            };
            write(&mut s, &reply);
        }
    });
    url
}

async fn settled(api: &Api, id: &str) -> Value {
    let start = Instant::now();
    loop {
        let s = api.get(&format!("/api/sessions/{id}")).await;
        if !["queued", "running", "waiting"].contains(&s["status"].as_str().unwrap()) {
            return s;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "{s}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_failed_session_reports_the_step_it_failed_at_and_a_resume_keeps_it() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (status, launched) = api
        .post(
            "/api/sessions",
            json!({"env": {"url": dying_env()}, "method": "sac", "trainer": "synthetic",
                   "steps": 1000, "params": {"hidden": [8, 8], "batch_size": 16, "record": false}}),
        )
        .await;
    assert_eq!(status, 201, "{launched}");
    let id = launched["id"].as_str().unwrap().to_string();
    let failed = settled(&api, &id).await;
    assert_eq!(failed["status"], "failed", "{failed}");
    let reason = failed["reason"].as_str().unwrap();
    assert!(
        reason.starts_with(&format!("at step {DIES_AT_STEP}: ")),
        "{reason}"
    );
    assert_eq!(
        failed["progress"], DIES_AT_STEP,
        "the progress is the step the reason names: {failed}"
    );

    // The env is gone: the resume is accepted with the progress the session had made, then
    // fails to reach the env, and the progress stays.
    let (status, resumed) = api
        .post(&format!("/api/sessions/{id}/resume"), json!({}))
        .await;
    assert_eq!(status, 200, "{resumed}");
    assert_eq!(resumed["progress"], DIES_AT_STEP, "{resumed}");
    let again = settled(&api, &id).await;
    assert_eq!(again["status"], "failed", "{again}");
    assert!(
        again["reason"].as_str().unwrap().contains("unreachable"),
        "{again}"
    );
    assert_eq!(again["progress"], DIES_AT_STEP, "{again}");
    server.shutdown().await.unwrap();
}

/// Issue 35: a human session on a remote env, stopped after answering queries past its latest
/// checkpoint, resumes at that checkpoint and replays the same moments on a deterministic env:
/// the answered ones take their stored answers, and no query after the resume repeats an
/// answered moment (same step and action) or an answered query's id; the query left open is
/// asked again under its id.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_resumed_remote_session_never_asks_an_answered_moment_again() {
    let (open, after) = answer_past_checkpoint_stop_and_resume(true).await;
    assert_eq!(
        (&after[0]["id"], &after[0]["step"], &after[0]["action"]),
        (&open["id"], &open["step"], &open["action"]),
        "{}",
        after[0]
    );
}

/// On an env that does not repeat its episodes (a robot) the resumed run meets other moments:
/// the queries after the checkpoint stay stored, and new ones are numbered after all of them.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_resumed_remote_session_on_a_robot_numbers_new_queries_after_the_stored_ones() {
    let (open, after) = answer_past_checkpoint_stop_and_resume(false).await;
    let first_new = open["id"].as_i64().unwrap() + 1;
    let ids: Vec<i64> = after.iter().map(|q| q["id"].as_i64().unwrap()).collect();
    assert_eq!(ids, (first_new..first_new + 3).collect::<Vec<_>>());
    assert_eq!(after[0]["step"], 20, "the run resumed at its checkpoint");
}

/// A human EF-100 session on [`line_env`], answered on every query up to three past its
/// checkpoint at step 20, stopped with the next query open, and resumed.
struct Resumed {
    dir: tempfile::TempDir,
    server: dualrep::cli::serve::Running,
    api: Api,
    id: String,
    token: String,
    /// The answered queries before the stop: id -> (step, action, answer).
    answered: BTreeMap<i64, (u64, Value, i64)>,
    /// The query left open at the stop.
    open: Value,
}

const WAIT: Duration = Duration::from_secs(60);

/// Episodes are 20 steps: the checkpoint after the first answered episode is at step 20.
const ANSWERED_PAST_CHECKPOINT: u64 = 3;

async fn answered_past_checkpoint_stopped_and_resumed(repeats: bool) -> Resumed {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (id, token) = launch_human_on_line(&api, repeats).await;

    // Answer every query up to three steps past the checkpoint at step 20; leave the next open.
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    let mut answered = BTreeMap::new();
    let open = loop {
        let q = t.next_of(&["query"], WAIT).await;
        let step = q["step"].as_u64().unwrap();
        if step >= 20 + ANSWERED_PAST_CHECKPOINT {
            break q;
        }
        let qid = q["id"].as_i64().unwrap();
        let value = if step % 2 == 0 { 1 } else { -1 };
        t.answer(qid, json!(value)).await;
        let ack = t.next_of(&["ack"], WAIT).await;
        assert_eq!(ack["id"], qid, "{ack}");
        answered.insert(qid, (step, q["action"].clone(), value));
    };
    assert_eq!(answered.len() as u64, 20 + ANSWERED_PAST_CHECKPOINT);
    let (status, _) = api
        .post(&format!("/api/sessions/{id}/stop"), json!({}))
        .await;
    assert_eq!(status, 200);
    assert_eq!(settled(&api, &id).await["status"], "stopped");
    t.close().await;

    let (status, resumed) = api
        .post(&format!("/api/sessions/{id}/resume"), json!({}))
        .await;
    assert_eq!(status, 200, "{resumed}");
    Resumed {
        dir,
        server,
        api,
        id,
        token,
        answered,
        open,
    }
}

impl Resumed {
    /// The next query, checked to be no answered one by id or by moment, answered "good".
    async fn answer_next(&self, t: &mut Trainer) -> Value {
        let q = t.next_of(&["query"], WAIT).await;
        let (qid, step) = (q["id"].as_i64().unwrap(), q["step"].as_u64().unwrap());
        assert!(
            !self.answered.contains_key(&qid),
            "query {qid} was answered: {q}"
        );
        for (done, (done_step, done_action, _)) in &self.answered {
            assert!(
                !(step == *done_step && q["action"] == *done_action),
                "query {qid} asks again the moment of answered query {done} (step {step}, action {}): {q}",
                q["action"]
            );
        }
        t.answer(qid, json!(1)).await;
        assert_eq!(t.next_of(&["ack"], WAIT).await["id"], qid);
        q
    }

    async fn stop(self) {
        self.api
            .post(&format!("/api/sessions/{}/stop", self.id), json!({}))
            .await;
        settled(&self.api, &self.id).await;
        self.server.shutdown().await.unwrap();
    }
}

/// The query left open at the stop and the first three queries after the resume (none of
/// them an answered one, by id or by moment).
async fn answer_past_checkpoint_stop_and_resume(repeats: bool) -> (Value, Vec<Value>) {
    let r = answered_past_checkpoint_stopped_and_resumed(repeats).await;
    let mut t = Trainer::connect(r.server.addr, &r.id, &r.token).await;
    let mut after = Vec::new();
    for _ in 0..3 {
        after.push(r.answer_next(&mut t).await);
    }
    t.close().await;
    let open = r.open.clone();
    r.stop().await;
    (open, after)
}

/// The issue after issue 35: on a robot the resumed run does not meet the moments answered
/// after its checkpoint again, and it used to restart from the checkpoint without them: the
/// learner never learnt from those answers. Now it takes them in from the steps stored with
/// their queries: at the next checkpoint (step 40) its replay buffer holds them with their
/// answers as H beside the 40 steps it took, and the run counts them as asked.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_resumed_remote_session_on_a_robot_learns_from_the_answers_given_after_its_checkpoint() {
    let r = answered_past_checkpoint_stopped_and_resumed(false).await;
    let mut t = Trainer::connect(r.server.addr, &r.id, &r.token).await;
    // Answer the resumed run's episode, steps 20 to 39; the checkpoint at step 40 is stored
    // before its first query is asked.
    loop {
        let q = t.next_of(&["query"], WAIT).await;
        if q["step"] == 40 {
            break;
        }
        let qid = q["id"].as_i64().unwrap();
        assert!(!r.answered.contains_key(&qid), "{q}");
        t.answer(qid, json!(1)).await;
        assert_eq!(t.next_of(&["ack"], WAIT).await["id"], qid);
    }
    let taken_in = ANSWERED_PAST_CHECKPOINT as usize;

    // The run counts every answer given: 23 before the stop, 20 after.
    let episodes = r.api.get(&format!("/api/sessions/{}/episodes", r.id)).await;
    let at_40 = episodes
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["step"] == 40)
        .unwrap_or_else(|| panic!("an episode ended at step 40: {episodes}"));
    assert_eq!(at_40["feedback_count"], 20 + taken_in + 20, "{at_40}");

    // The learner's data: 40 steps and the three answered steps taken in, each with its answer.
    let path = r.dir.path().join(format!("checkpoints/{}.resume", r.id));
    let bytes = std::fs::read(&path).unwrap();
    let replay = EvaluativeRun::checkpoint_replay(&bytes).unwrap();
    assert_eq!(replay.len(), 40 + taken_in);
    let labels: Vec<f32> = (0..replay.len()).map(|slot| replay.human(slot)).collect();
    let count = |h: f32| labels.iter().filter(|&&l| l == h).count();
    // Before the stop: +1 on even steps, -1 on odd ones (steps 0-22); after: +1 (steps 20-39).
    assert_eq!((count(1.0), count(-1.0)), (12 + 20, 11), "{labels:?}");
    for (qid, (step, action, value)) in r.answered.range(20..) {
        let action: Vec<f32> = action
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_f64().unwrap() as f32)
            .collect();
        let rows: Vec<usize> = (0..replay.len())
            .filter(|&slot| replay.action(slot) == action.as_slice())
            .collect();
        assert!(
            rows.iter().any(|&slot| replay.human(slot) == *value as f32),
            "query {qid} (step {step}, answered {value}) is not in the replay: rows {rows:?}"
        );
    }
    t.close().await;
    r.stop().await;
}
