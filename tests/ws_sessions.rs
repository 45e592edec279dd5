//! Real websocket trainers against the server on port 0: a human DREF session and a human DRPL
//! session driven to their end; several trainers on one query; reconnecting; bad input. Undoing
//! an answer is in `ws_undo`.

use std::collections::HashMap;
use std::time::Duration;

use crate::support::postgres;
use crate::support::server::{Api, serve, serve_on};
use crate::support::trainer::{Trainer, token_of};
use serde_json::{Value, json};

pub(crate) const WAIT: Duration = Duration::from_secs(60);

pub(crate) async fn launch(api: &Api, body: Value) -> (String, String) {
    let (status, r) = api.post("/api/sessions", body).await;
    assert_eq!(status, 201, "{r}");
    (
        r["id"].as_str().unwrap().to_string(),
        token_of(r["trainer_url"].as_str().unwrap()),
    )
}

/// Answer every query until `ended`; returns the acknowledged `(query id -> value)`.
pub(crate) async fn answer_all(
    t: &mut Trainer,
    pick: impl Fn(&Value) -> Value,
) -> (HashMap<i64, Value>, Value) {
    let mut acked = HashMap::new();
    let mut frames = 0;
    loop {
        let m = t
            .next(WAIT)
            .await
            .expect("the socket stays open until ended");
        match m["type"].as_str().unwrap() {
            "query" => {
                let v = pick(&m);
                t.answer(m["id"].as_i64().unwrap(), v).await;
            }
            "ack" => {
                acked.insert(m["id"].as_i64().unwrap(), m["value"].clone());
            }
            "frame" => frames += 1,
            "error" => panic!("unexpected error {m}"),
            "ended" => {
                assert_eq!(m["status"], "finished", "{m}");
                return (acked, json!({"frames": frames}));
            }
            _ => {}
        }
    }
}

/// Read messages until `want` is satisfied and return that one; queries met on the way are
/// parked in `parked` (by id) to be answered later.
pub(crate) async fn until(
    t: &mut Trainer,
    want: impl Fn(&Value) -> bool,
    parked: &mut Vec<i64>,
) -> Value {
    loop {
        let m = t.next(WAIT).await.expect("the socket stays open");
        if want(&m) {
            return m;
        }
        if m["type"] == "query" {
            parked.push(m["id"].as_i64().unwrap());
        }
        assert_ne!(m["type"], "ended", "ended before {m}");
    }
}

async fn stored_answers(api: &Api, id: &str) -> HashMap<i64, Value> {
    api.get(&format!("/api/sessions/{id}/answers"))
        .await
        .as_array()
        .unwrap()
        .iter()
        .map(|a| (a["query_id"].as_i64().unwrap(), a["value"].clone()))
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_human_dref_session_runs_to_its_end_with_every_answer_stored() {
    human_dref_session_to_its_end(None).await;
}

/// The same on PostgreSQL (`--database postgres://...`): the whole server on it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_human_dref_session_runs_to_its_end_on_postgresql() {
    if let Some(db) = postgres::database().await {
        human_dref_session_to_its_end(Some(&db.url)).await;
    }
}

async fn human_dref_session_to_its_end(database: Option<&str>) {
    let dir = tempfile::tempdir().unwrap();
    let server = serve_on(dir.path(), database).await;
    let api = Api::new(server.addr);
    let (id, token) = launch(
        &api,
        json!({"task": "reaching", "method": "dref", "trainer": "human", "seed": 1, "steps": 100,
               "params": {"pace_hz": 15, "hidden": [32, 32], "batch_size": 32, "answer_timeout_s": 30}}),
    )
    .await;
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    let hello = t.next(WAIT).await.unwrap();
    assert_eq!(
        (hello["type"].as_str(), hello["kind"].as_str()),
        (Some("hello"), Some("evaluative"))
    );
    assert!(!hello["predicates"].as_array().unwrap().is_empty());
    assert_eq!(hello["pace_hz"], 15.0, "the page paces its drawing by it");
    let (acked, seen) = answer_all(&mut t, |q| {
        assert_eq!(q["kind"], "evaluative");
        assert!(!q["clip"]["frames"].as_array().unwrap().is_empty());
        assert_eq!(q["action"].as_array().unwrap().len(), 2);
        json!(if q["step"].as_u64().unwrap() % 2 == 0 {
            1
        } else {
            -1
        })
    })
    .await;
    assert!(!acked.is_empty(), "DREF asks at its first step");
    assert!(
        seen["frames"].as_u64().unwrap() > 0,
        "a human session streams frames"
    );
    let stored = stored_answers(&api, &id).await;
    assert_eq!(
        stored, acked,
        "every acknowledged answer is stored, and nothing else"
    );
    let s = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(
        (s["status"].as_str(), s["progress"].as_u64()),
        (Some("finished"), Some(100))
    );
    assert_eq!(
        s["answers"]["by_trainer"].as_u64(),
        Some(acked.len() as u64)
    );
    // The share of steps asked, kept up between episode ends (100 steps may end none).
    let fraction = s["latest"]["feedback_fraction"].as_f64().unwrap();
    assert!(
        (fraction - acked.len() as f64 / 100.0).abs() < 0.02,
        "feedback {fraction} after {} answers in 100 steps",
        acked.len()
    );
    // Episodes end by success, failure or time limit; 100 steps may hold none of them.
    assert!(
        api.get(&format!("/api/sessions/{id}/episodes"))
            .await
            .is_array()
    );
    // After the end, answers get a clear error and the socket stays usable.
    let any = *acked.keys().next().unwrap();
    t.answer(any, json!(1)).await;
    let e = t.next_of(&["error"], WAIT).await;
    assert_eq!(
        (e["code"].as_str(), e["id"].as_i64()),
        (Some("session_ended"), Some(any))
    );
    t.close().await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_human_drpl_session_runs_to_its_end() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (id, token) = launch(
        &api,
        json!({"task": "placing", "method": "drpl", "trainer": "human", "seed": 4, "queries": 4,
               "params": {"trajectories": 10}}),
    )
    .await;
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    let values = ["left", "right", "equal", "skip"];
    let (acked, _) = answer_all(&mut t, |q| {
        assert_eq!(q["kind"], "preference");
        assert!(!q["left"]["frames"].as_array().unwrap().is_empty());
        assert!(!q["right"]["frames"].as_array().unwrap().is_empty());
        assert!(
            q["predicate"]["label"].is_string(),
            "DRPL names the predicate: {}",
            q["predicate"]
        );
        json!(values[q["id"].as_u64().unwrap() as usize % 4])
    })
    .await;
    assert_eq!(acked.len(), 4);
    assert_eq!(stored_answers(&api, &id).await, acked);
    let s = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(
        (s["status"].as_str(), s["answers"]["no_feedback"].as_u64()),
        (Some("finished"), Some(1))
    );
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_first_answer_wins_a_reconnect_gets_the_query_again_and_bad_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (id, token) = launch(
        &api,
        json!({"task": "reaching", "method": "ef-100", "trainer": "human", "seed": 0, "steps": 50,
               "params": {"pace_hz": 100, "hidden": [32, 32], "batch_size": 32}}),
    )
    .await;
    let (other_id, other_token) = launch(
        &api,
        json!({"task": "reaching", "method": "ef-100", "trainer": "human", "seed": 1, "steps": 50,
               "params": {"pace_hz": 100, "hidden": [32, 32], "batch_size": 32}}),
    )
    .await;
    // Tokens are per session; the researcher token may watch.
    let refused = reqwest::get(format!(
        "http://{}/ws/sessions/{id}?token={other_token}",
        server.addr
    ))
    .await
    .unwrap();
    assert_eq!(refused.status(), 403);
    let refused = reqwest::get(format!("http://{}/ws/sessions/{id}", server.addr))
        .await
        .unwrap();
    assert_eq!(refused.status(), 401);

    let mut a = Trainer::connect(server.addr, &id, &token).await;
    let mut b = Trainer::connect(server.addr, &id, &token).await;
    let q = a.next_of(&["query"], WAIT).await;
    let qid = q["id"].as_i64().unwrap();
    let qb = b.next_of(&["query"], WAIT).await;
    assert_eq!(qb["id"].as_i64(), Some(qid), "every trainer sees the query");

    // A reconnecting browser gets the pending query again.
    b.close().await;
    let mut b = Trainer::connect(server.addr, &id, &token).await;
    let again = b.next_of(&["query"], WAIT).await;
    assert_eq!(again["id"].as_i64(), Some(qid));

    // Bad input: each gets an error with a code, and the socket keeps working.
    for (text, code) in [
        ("{oops", "malformed_json"),
        (r#"{"type":"answer","id":"x","value":1}"#, "bad_message"),
        (
            r#"{"type":"answer","id":999999,"value":1}"#,
            "unknown_query",
        ),
        (r#"{"type":"shout"}"#, "bad_message"),
    ] {
        a.send_text(text).await;
        let e = a.next_of(&["error"], WAIT).await;
        assert_eq!(e["code"].as_str(), Some(code), "{text} -> {e}");
    }
    a.answer(qid, json!("left")).await;
    assert_eq!(a.next_of(&["error"], WAIT).await["code"], "bad_value");
    a.answer(-5, json!(1)).await;
    assert_eq!(a.next_of(&["error"], WAIT).await["code"], "unknown_query");

    // The first committed answer wins; the other trainer sees it withdrawn, a repeat is idempotent.
    a.answer(qid, json!(1)).await;
    let ack = a.next_of(&["ack"], WAIT).await;
    assert_eq!(
        (ack["id"].as_i64(), ack["value"].as_i64()),
        (Some(qid), Some(1))
    );
    // The session asks its next query as soon as the answer reaches it, so b may see that
    // query before the replies below: it is parked, not skipped.
    let mut parked = Vec::new();
    let w = until(&mut b, |m| m["type"] == "withdrawn", &mut parked).await;
    assert_eq!(
        (w["id"].as_i64(), w["reason"].as_str()),
        (Some(qid), Some("answered"))
    );
    b.answer(qid, json!(1)).await;
    let reply = |m: &Value| m["type"] == "ack" || m["type"] == "error";
    assert_eq!(until(&mut b, reply, &mut parked).await["type"], "ack");
    b.answer(qid, json!(-1)).await;
    assert_eq!(
        until(&mut b, |m| m["type"] == "error", &mut parked).await["code"],
        "already_answered"
    );

    // Query ids are each session's own numbers: the other session's first query is 0 as well,
    // and on this session's socket 0 names this session's first query (answered above), so
    // another session's answer can never land here.
    let mut o = Trainer::connect(server.addr, &other_id, &other_token).await;
    let other_first = o.next_of(&["query"], WAIT).await["id"].as_i64().unwrap();
    assert_eq!((other_first, qid), (0, 0));
    a.answer(other_first, json!(-1)).await;
    assert_eq!(
        a.next_of(&["error"], WAIT).await["code"],
        "already_answered"
    );

    // An oversized message closes that socket only; the server keeps serving.
    a.send_text(&format!(
        r#"{{"type":"answer","id":1,"value":"{}"}}"#,
        "x".repeat(10_000)
    ))
    .await;
    let closed = loop {
        match a.next(WAIT).await {
            None => break true,
            Some(m)
                if m["type"] == "frame"
                    || m["type"] == "progress"
                    || m["type"] == "query"
                    || m["type"] == "withdrawn" =>
            {
                continue;
            }
            Some(m) => panic!("unexpected {m}"),
        }
    };
    assert!(closed);
    let health = reqwest::get(format!("http://{}/healthz", server.addr))
        .await
        .unwrap();
    assert_eq!(health.status(), 200);
    let q2 = match parked.first() {
        Some(&id) => id,
        None => b.next_of(&["query"], WAIT).await["id"].as_i64().unwrap(),
    };
    b.answer(q2, json!(0)).await;
    assert_eq!(b.next_of(&["ack"], WAIT).await["id"].as_i64(), Some(q2));
    o.close().await;
    b.close().await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_rate_limited_message_says_when_to_send_it_again_and_is_taken_then() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (id, token) = launch(
        &api,
        json!({"task": "reaching", "method": "ef-100", "trainer": "human", "seed": 0, "steps": 50,
               "params": {"pace_hz": 100, "hidden": [32, 32], "batch_size": 32}}),
    )
    .await;
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    // More than the burst at once (answers to no query: each is refused, one way or the other).
    let unknown = r#"{"type":"answer","id":999999,"value":1}"#;
    for _ in 0..60 {
        t.send_text(unknown).await;
    }
    let mut replies = 0;
    let limited = loop {
        let e = t.next_of(&["error"], WAIT).await;
        replies += 1;
        if e["code"] == "rate_limited" {
            break e;
        }
        assert_eq!(e["code"], "unknown_query", "{e}");
    };
    let retry_after_ms = limited["retry_after_ms"]
        .as_u64()
        .unwrap_or_else(|| panic!("a rate_limited error says when to retry: {limited}"));
    assert!((1..=1000).contains(&retry_after_ms), "{limited}");
    assert_eq!(limited["id"], 999999, "{limited}");
    assert!(
        limited["message"]
            .as_str()
            .unwrap()
            .contains(&format!("send it again in {retry_after_ms} ms")),
        "the text says it too: {limited}"
    );
    // Drain the rest of the burst's replies (in the order the socket handled the messages). A
    // refusal's wait holds while nothing else is taken, and the bucket refills as the socket
    // works: under load it may take a message after its last refusal. So burst again until the
    // burst's last message is refused; then, after waiting what that refusal said, the same
    // message is taken (it reaches the session, which does not know the query).
    let mut last = limited.clone();
    let mut left = 60 - replies;
    for burst in 0.. {
        for _ in 0..left {
            last = t.next_of(&["error"], WAIT).await;
        }
        if last["code"] == "rate_limited" {
            break;
        }
        assert!(burst < 5, "no burst ended refused: {last}");
        for _ in 0..60 {
            t.send_text(unknown).await;
        }
        left = 60;
    }
    let wait_ms = last["retry_after_ms"].as_u64().unwrap();
    tokio::time::sleep(Duration::from_millis(wait_ms)).await;
    t.send_text(unknown).await;
    let e = t.next_of(&["error"], WAIT).await;
    assert_eq!(e["code"], "unknown_query", "taken after the wait: {e}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_malformed_value_is_refused_naming_its_field() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (id, token) = launch(
        &api,
        json!({"task": "reaching", "method": "ef-100", "trainer": "human", "seed": 0, "steps": 50,
               "params": {"pace_hz": 100, "hidden": [32, 32], "batch_size": 32}}),
    )
    .await;
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    for (text, code, names) in [
        (
            r#"{"type":"answer","id":0,"value":NaN}"#,
            "malformed_json",
            "\"value\"",
        ),
        (
            r#"{"type":"answer","id":0,"value":1e999}"#,
            "malformed_json",
            "\"value\"",
        ),
        (
            r#"{"type":"answer","id":0.5,"value":1}"#,
            "bad_message",
            "\"id\"",
        ),
        (r#"{"type":"undo","id":[1]}"#, "bad_message", "\"id\""),
    ] {
        t.send_text(text).await;
        let e = t.next_of(&["error"], WAIT).await;
        assert_eq!(e["code"], code, "{text} -> {e}");
        let message = e["message"].as_str().unwrap();
        assert!(
            message.contains(names),
            "{text}: the error names the field: {message}"
        );
    }
}
