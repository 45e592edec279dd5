//! Nothing acknowledged is lost: the real binary is killed with SIGKILL while a trainer streams
//! answers; after a restart every acknowledged answer is in the database file and in the API,
//! the session is `interrupted`, and once resumed it never re-asks an answered query and finishes.

use std::collections::HashMap;
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::Duration;

use crate::support::binary::start_serve;
use crate::support::server::{Api, TOKEN};
use crate::support::trainer::{Trainer, token_of};
use serde_json::{Value, json};
use sqlx::Row;

const WAIT: Duration = Duration::from_secs(60);

/// Start `dualrep serve` on a free port; returns the child and its address.
fn start_server(data: &Path) -> (Child, std::net::SocketAddr) {
    let (child, url) = start_serve(data, TOKEN, &["--max-sessions", "2"], Stdio::null());
    (child, url.trim_start_matches("http://").parse().unwrap())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn acknowledged_answers_survive_sigkill_and_the_session_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let (mut child, addr) = start_server(dir.path());
    let api = Api::new(addr);
    let (status, r) = api
        .post(
            "/api/sessions",
            json!({"task": "reaching", "method": "ef-50", "trainer": "human", "seed": 7, "steps": 300,
                   "params": {"pace_hz": 30, "hidden": [32, 32], "batch_size": 32, "checkpoint_every": 40}}),
        )
        .await;
    assert_eq!(status, 201, "{r}");
    let id = r["id"].as_str().unwrap().to_string();
    let token = token_of(r["trainer_url"].as_str().unwrap());

    // Stream answers, logging every ack, and kill the server mid-stream.
    // Queries are named by the session's query number, on the wire and in the API.
    let mut acked: HashMap<u64, Value> = HashMap::new();
    let mut t = Trainer::connect(addr, &id, &token).await;
    while acked.len() < 25 {
        let m = t.next(WAIT).await.expect("open");
        match m["type"].as_str().unwrap() {
            "query" => {
                let qid = m["id"].as_u64().unwrap();
                t.answer(qid as i64, json!([1, 0, -1][(qid % 3) as usize]))
                    .await;
            }
            "ack" => {
                let qid = m["id"].as_u64().unwrap();
                acked.insert(qid, m["value"].clone());
            }
            "error" | "ended" => panic!("unexpected {m}"),
            _ => {}
        }
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    drop(t);

    // Every acknowledged answer is in the database file...
    let pool = sqlx::SqlitePool::connect(&format!(
        "sqlite://{}",
        dir.path().join("dualrep.db").display()
    ))
    .await
    .unwrap();
    let rows = sqlx::query(
        "SELECT q.seq, a.value FROM answers a JOIN queries q ON q.id = a.query_id
         WHERE a.session_id = ?",
    )
    .bind(&id)
    .fetch_all(&pool)
    .await
    .unwrap();
    let in_db: HashMap<u64, Value> = rows
        .iter()
        .map(|r| {
            (
                r.get::<i64, _>("seq") as u64,
                serde_json::from_str(r.get::<&str, _>("value")).unwrap(),
            )
        })
        .collect();
    for (q, v) in &acked {
        assert_eq!(
            in_db.get(q),
            Some(v),
            "acknowledged answer to query {q} is in the database"
        );
    }
    pool.close().await;

    // ... and in the API after a restart, where the session is interrupted.
    let (mut child, addr) = start_server(dir.path());
    let api = Api::new(addr);
    let s = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(s["status"], "interrupted", "{s}");
    let answers = api.get(&format!("/api/sessions/{id}/answers")).await;
    let via_api: HashMap<u64, Value> = answers
        .as_array()
        .unwrap()
        .iter()
        .map(|a| (a["query_id"].as_u64().unwrap(), a["value"].clone()))
        .collect();
    for (q, v) in &acked {
        assert_eq!(via_api.get(q), Some(v));
    }
    let answered_before = via_api.len() as u64;

    // Resume: stored answers are replayed, never asked again; the session finishes.
    let (status, r) = api
        .post(&format!("/api/sessions/{id}/resume"), json!({}))
        .await;
    assert_eq!(status, 200, "{r}");
    let mut t = Trainer::connect(addr, &id, &token).await;
    let mut asked_after = 0;
    loop {
        let m = t.next(WAIT).await.expect("open");
        match m["type"].as_str().unwrap() {
            "query" => {
                let qid = m["id"].as_u64().unwrap();
                assert!(
                    qid >= answered_before,
                    "query {qid} was answered before the crash"
                );
                assert!(!acked.contains_key(&qid));
                asked_after += 1;
                t.answer(qid as i64, json!(1)).await;
            }
            "error" => panic!("unexpected {m}"),
            "ended" => {
                assert_eq!(m["status"], "finished", "{m}");
                break;
            }
            _ => {}
        }
    }
    assert!(asked_after > 0);
    let s = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(
        (s["status"].as_str(), s["progress"].as_u64()),
        (Some("finished"), Some(300))
    );
    let answers = api.get(&format!("/api/sessions/{id}/answers")).await;
    let seqs: Vec<u64> = answers
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["query_id"].as_u64().unwrap())
        .collect();
    assert_eq!(
        seqs,
        (0..seqs.len() as u64).collect::<Vec<_>>(),
        "one answer per query, none twice"
    );
    child.kill().unwrap();
    child.wait().unwrap();
}
