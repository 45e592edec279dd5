//! Several `dualrep serve` processes on one PostgreSQL (docs/serving-several.md): sessions
//! launched on one server are claimed by whichever has free slots, and when a server is killed
//! with SIGKILL another takes its sessions over within the lease bound and finishes them,
//! without asking any query twice.

use std::collections::{HashMap, HashSet};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use sqlx::{Connection, Row};

use crate::support::binary::start_serve;
use crate::support::postgres;
use crate::support::server::{Api, TOKEN};

/// The lease (6 s) plus the claim period (1 s): `server/hub/leases.rs`.
const BOUND: Duration = Duration::from_secs(7);
/// Synthetic EF-50 sessions long enough to be mid-run when a server is killed.
const STEPS: u64 = 4000;

fn start(data: &std::path::Path, url: &str, max: &str) -> (Child, Api) {
    let (child, base) = start_serve(
        data,
        TOKEN,
        &["--database", url, "--max-sessions", max],
        Stdio::null(),
    );
    (
        child,
        Api::new(base.trim_start_matches("http://").parse().unwrap()),
    )
}

/// `(id -> (status, owner))` of every session, from the database.
async fn owners(db: &mut sqlx::PgConnection) -> HashMap<String, (String, Option<String>)> {
    sqlx::query("SELECT id, status, owner FROM sessions")
        .fetch_all(db)
        .await
        .unwrap()
        .iter()
        .map(|r| (r.get("id"), (r.get("status"), r.get("owner"))))
        .collect()
}

/// Launch a synthetic session on `api`'s server; its id.
async fn launch(api: &Api, seed: u64) -> String {
    let (status, r) = api
        .post(
            "/api/sessions",
            json!({"task": "reaching", "method": "ef-50", "trainer": "synthetic", "seed": seed,
                   "steps": STEPS,
                   "params": {"hidden": [32, 32], "batch_size": 32, "record": false,
                              "checkpoint_every": 500}}),
        )
        .await;
    assert_eq!(status, 201, "{r}");
    r["id"].as_str().unwrap().to_string()
}

/// Every answer of session `id` (read through `api`) is to a different query, and every query
/// stored for it has its one answer.
async fn asked_once(api: &Api, db: &mut sqlx::PgConnection, id: &str) {
    let answers: Value = api.get(&format!("/api/sessions/{id}/answers")).await;
    let answers = answers.as_array().unwrap();
    let seqs: HashSet<i64> = answers
        .iter()
        .map(|a| a["query_id"].as_i64().unwrap())
        .collect();
    assert_eq!(seqs.len(), answers.len(), "a query asked twice in {id}");
    assert!(!answers.is_empty(), "{id} asked nothing");
    let queries: i64 = sqlx::query("SELECT COUNT(*) AS n FROM queries WHERE session_id = $1")
        .bind(id)
        .fetch_one(db)
        .await
        .unwrap()
        .get("n");
    assert_eq!(
        queries as usize,
        answers.len(),
        "{id}: every query answered once"
    );
}

/// Wait until session `id` has finished (read through `api`), failing on any other end.
async fn finishes(api: &Api, id: &str) {
    wait_for(
        &format!("{id} finishes"),
        Duration::from_secs(300),
        async || {
            let v = api.get(&format!("/api/sessions/{id}")).await;
            assert!(
                !["failed", "stopped", "interrupted"].contains(&v["status"].as_str().unwrap()),
                "{v}"
            );
            (v["status"] == "finished").then_some(())
        },
    )
    .await;
}

async fn wait_for<T>(what: &str, within: Duration, mut check: impl AsyncFnMut() -> Option<T>) -> T {
    let start = Instant::now();
    loop {
        if let Some(t) = check().await {
            return t;
        }
        assert!(start.elapsed() < within, "{what} within {within:?}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_servers_session_is_taken_over_and_finishes_on_another() {
    let Some(pg) = postgres::database().await else {
        return;
    };
    let mut db = sqlx::PgConnection::connect(&pg.url).await.unwrap();
    let (dir_a, dir_b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());

    // Server A alone, two slots: it claims two of the three sessions launched on it.
    let (mut a, api_a) = start(dir_a.path(), &pg.url, "2");
    let mut ids = Vec::new();
    for seed in 1..=3 {
        ids.push(launch(&api_a, seed).await);
    }
    let server_a = wait_for("A runs two sessions", Duration::from_secs(30), async || {
        let o = owners(&mut db).await;
        let running: Vec<_> = o.values().filter(|(s, _)| s == "running").collect();
        let queued = o.values().filter(|(s, _)| s == "queued").count();
        (running.len() == 2 && queued == 1).then(|| running[0].1.clone().unwrap())
    })
    .await;

    // Server B, two slots: it claims the third, and has one slot left for a takeover.
    let (mut b, api_b) = start(dir_b.path(), &pg.url, "2");
    let server_b = wait_for("B runs the third", Duration::from_secs(30), async || {
        let o = owners(&mut db).await;
        o.values()
            .find(|(s, owner)| s == "running" && owner.as_deref() != Some(&server_a))
            .and_then(|(_, owner)| owner.clone())
    })
    .await;
    let o = owners(&mut db).await;
    let on_a: Vec<String> = ids
        .iter()
        .filter(|id| o[*id].1.as_deref() == Some(&server_a))
        .cloned()
        .collect();
    assert_eq!(on_a.len(), 2, "{o:?}");
    assert!(
        o.values().all(|(s, _)| s == "running"),
        "all three still running when A is killed: {o:?} (raise STEPS)"
    );

    // SIGKILL A: B takes over one of its sessions within the bound (the other when a slot of
    // B's frees up).
    a.kill().unwrap();
    a.wait().unwrap();
    let killed = Instant::now();
    let taken = wait_for("B takes a session of A's over", BOUND * 2, async || {
        let o = owners(&mut db).await;
        on_a.iter()
            .find(|id| o[*id].1.as_deref() == Some(&server_b))
            .cloned()
    })
    .await;
    let takeover = killed.elapsed();
    println!(
        "takeover: session {taken} of the killed server {server_a} claimed by {server_b} \
         {:.2} s after the kill (bound {:?})",
        takeover.as_secs_f64(),
        BOUND
    );
    assert!(takeover <= BOUND, "takeover took {takeover:?}");

    // Every session finishes on B; no query was asked twice.
    for id in &ids {
        finishes(&api_b, id).await;
        asked_once(&api_b, &mut db, id).await;
    }
    let o = owners(&mut db).await;
    assert_eq!(o[&taken].1.as_deref(), Some(server_b.as_str()));
    b.kill().unwrap();
    b.wait().unwrap();
}

/// A server that finds its lease taken (the `owner` column changed under it) ends its copy
/// without writing more; when the other lease runs out it claims the session again, which
/// resumes from what was stored and finishes, every query asked once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_whose_lease_is_taken_stops_its_copy_and_the_session_resumes() {
    let Some(pg) = postgres::database().await else {
        return;
    };
    let mut db = sqlx::PgConnection::connect(&pg.url).await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (mut server, api) = start(dir.path(), &pg.url, "1");
    let id = launch(&api, 4).await;
    let me = wait_for("the session runs", Duration::from_secs(30), async || {
        let o = owners(&mut db).await;
        let (status, owner) = &o[&id];
        (status == "running").then(|| owner.clone().unwrap())
    })
    .await;
    // Another (pretend) server holds it for 5 s.
    sqlx::query(
        "UPDATE sessions SET owner = 'intruder', lease_until = now() + interval '5 seconds'
         WHERE id = $1",
    )
    .bind(&id)
    .execute(&mut db)
    .await
    .unwrap();
    let taken = Instant::now();
    // The server renews within 2 s, finds the session gone and drops its copy: from then on
    // its copy stores nothing (a running synthetic session stores answers many times a second).
    let stored = async |db: &mut sqlx::PgConnection| -> i64 {
        sqlx::query("SELECT COUNT(*) AS n FROM answers WHERE session_id = $1")
            .bind(&id)
            .fetch_one(db)
            .await
            .unwrap()
            .get("n")
    };
    tokio::time::sleep_until((taken + Duration::from_secs(3)).into()).await;
    let before = stored(&mut db).await;
    tokio::time::sleep_until((taken + Duration::from_millis(4700)).into()).await;
    assert_eq!(
        stored(&mut db).await,
        before,
        "the dropped copy wrote answers"
    );
    // After the pretend lease it claims the session again.
    wait_for(
        "the server claims it again",
        Duration::from_secs(10),
        async || {
            let o = owners(&mut db).await;
            (o[&id].1.as_deref() == Some(me.as_str())).then_some(())
        },
    )
    .await;
    assert!(
        taken.elapsed() >= Duration::from_secs(3),
        "not before the other lease ran out"
    );
    finishes(&api, &id).await;
    asked_once(&api, &mut db, &id).await;
    server.kill().unwrap();
    server.wait().unwrap();
}
