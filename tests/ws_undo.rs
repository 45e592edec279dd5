//! Undoing an answer over the websocket: the undone query is asked again and its new answer
//! replaces the old one, also across a restart; an undone preference comes back before the pair
//! that waited behind it.

use std::collections::HashSet;

use crate::support::server::{Api, serve};
use crate::support::trainer::Trainer;
use crate::ws_sessions::{WAIT, answer_all, launch, until};
use serde_json::{Value, json};

fn is(kind: &'static str, id: i64) -> impl Fn(&Value) -> bool {
    move |m: &Value| m["type"] == kind && m["id"].as_i64() == Some(id)
}

fn answer_row(answers: &Value, id: i64) -> Value {
    answers
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["query_id"].as_i64() == Some(id))
        .cloned()
        .unwrap_or_else(|| panic!("query {id} has no stored answer: {answers}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_undone_answer_is_asked_again_replaced_and_replayed_after_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (id, token) = launch(
        &api,
        json!({"task": "reaching", "method": "ef-100", "trainer": "human", "seed": 2, "steps": 60,
               "params": {"pace_hz": 50, "hidden": [32, 32], "batch_size": 32,
                          "checkpoint_every": 10, "answer_timeout_s": 30}}),
    )
    .await;
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    let mut parked = Vec::new();
    let first = t.next_of(&["query"], WAIT).await["id"].as_i64().unwrap();
    t.answer(first, json!(1)).await;
    until(&mut t, is("ack", first), &mut parked).await;

    // The session has moved on and waits on the next step's query; the undo reopens the first.
    t.send_text(&json!({"type": "undo", "id": first}).to_string())
        .await;
    let undone = until(
        &mut t,
        |m| m["type"] == "undone" || m["type"] == "error",
        &mut parked,
    )
    .await;
    assert_eq!(undone, json!({"type": "undone", "id": first}));
    let again = until(
        &mut t,
        |m| m["type"] == "query" && m["id"].as_i64() == Some(first),
        &mut parked,
    )
    .await;
    assert_eq!(again["id"], 0, "the session's first query");
    // While it is open nobody can undo it again; an older answer cannot be undone at all.
    t.send_text(&json!({"type": "undo", "id": first}).to_string())
        .await;
    let e = until(&mut t, |m| m["type"] == "error", &mut parked).await;
    assert_eq!(e["code"], "undo_unavailable", "{e}");
    let s = api.get(&format!("/api/sessions/{id}/answers")).await;
    assert_eq!(
        answer_row(&s, first)["value"],
        0,
        "undone: no feedback meanwhile"
    );

    t.answer(first, json!(-1)).await;
    let ack = until(&mut t, is("ack", first), &mut parked).await;
    assert_eq!(ack["value"], -1);
    // Answer 25 more, then restart the server in the middle of the session.
    if parked.is_empty() {
        parked.push(t.next_of(&["query"], WAIT).await["id"].as_i64().unwrap());
    }
    let second = parked[0];
    let (mut answered, mut acked) = (HashSet::from([first]), HashSet::from([first]));
    for q in parked.drain(..) {
        if answered.insert(q) {
            t.answer(q, json!(1)).await;
        }
    }
    while acked.len() < 26 {
        let m = t.next(WAIT).await.unwrap();
        let q = m["id"].as_i64().unwrap_or(-1);
        match m["type"].as_str().unwrap() {
            "query" if answered.insert(q) => t.answer(q, json!(1)).await,
            "ack" => {
                acked.insert(q);
            }
            "error" => panic!("{m}"),
            _ => {}
        }
    }
    // The second query's answer is not the latest any more: it stands.
    t.send_text(&json!({"type": "undo", "id": second}).to_string())
        .await;
    let e = until(&mut t, |m| m["type"] == "error", &mut parked).await;
    assert_eq!(
        (e["code"].as_str(), e["id"].as_i64()),
        (Some("undo_unavailable"), Some(second))
    );
    t.close().await;
    server.shutdown().await.unwrap();

    // After the restart the session replays its answers, the undo and the new answer where
    // they happened; the replay must reproduce the checkpoint taken after them, or the
    // session fails with "diverged".
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let s = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(s["status"], "interrupted", "{s}");
    let (status, r) = api
        .post(&format!("/api/sessions/{id}/resume"), json!({}))
        .await;
    assert_eq!(status, 200, "{r}");
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    let (_, _) = answer_all(&mut t, |_| json!(1)).await;
    let s = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(
        (s["status"].as_str(), s["progress"].as_u64()),
        (Some("finished"), Some(60)),
        "{s}"
    );
    let answers = api.get(&format!("/api/sessions/{id}/answers")).await;
    assert_eq!(answers.as_array().unwrap().len(), 60, "one answer per step");
    let row = answer_row(&answers, first);
    assert_eq!(
        (row["value"].as_i64(), row["revision"].as_i64()),
        (Some(-1), Some(2)),
        "{row}"
    );
    t.close().await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_undone_preference_leaves_the_next_pair_waiting_and_is_answered_again() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let (id, token) = launch(
        &api,
        json!({"task": "placing", "method": "drpl", "trainer": "human", "seed": 4, "queries": 3,
               "params": {"trajectories": 10}}),
    )
    .await;
    let mut t = Trainer::connect(server.addr, &id, &token).await;
    let mut parked = Vec::new();
    let q0 = t.next_of(&["query"], WAIT).await["id"].as_i64().unwrap();
    t.answer(q0, json!("left")).await;
    until(&mut t, is("ack", q0), &mut parked).await;
    let q1 = t.next_of(&["query"], WAIT).await["id"].as_i64().unwrap();
    assert_ne!(q0, q1);
    t.send_text(&json!({"type": "undo", "id": q0}).to_string())
        .await;
    until(&mut t, is("undone", q0), &mut parked).await;
    until(&mut t, is("query", q0), &mut parked).await;
    // A page that joins now gets both open queries, the reopened one last.
    let mut late = Trainer::connect(server.addr, &id, &token).await;
    let a = late.next_of(&["query"], WAIT).await;
    let b = late.next_of(&["query"], WAIT).await;
    assert_eq!((a["id"].as_i64(), b["id"].as_i64()), (Some(q1), Some(q0)));
    late.close().await;
    t.answer(q0, json!("right")).await;
    assert_eq!(
        until(&mut t, is("ack", q0), &mut parked).await["value"],
        "right"
    );
    // The waiting pair comes back for pages that showed the reopened one.
    until(&mut t, is("query", q1), &mut parked).await;
    t.answer(q1, json!("equal")).await;
    let (acked, _) = answer_all(&mut t, |_| json!("equal")).await;
    assert!(acked.contains_key(&q1));
    let answers = api.get(&format!("/api/sessions/{id}/answers")).await;
    assert_eq!(answers.as_array().unwrap().len(), 3);
    let row = answer_row(&answers, q0);
    assert_eq!(
        (row["value"].as_str(), row["revision"].as_i64()),
        (Some("right"), Some(2))
    );
    t.close().await;
    server.shutdown().await.unwrap();
}
