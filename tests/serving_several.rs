//! Several `dualrep serve` processes on one PostgreSQL (docs/serving-several.md): sessions
//! launched on one server are claimed by whichever has free slots, and when a server is killed
//! with SIGKILL another takes its sessions over within the lease bound and finishes them,
//! without asking any query twice.

use std::time::{Duration, Instant};

use serde_json::{Value, json};
use sqlx::{Connection, Row};

use crate::support::line_env::launch_human_on_line;
use crate::support::postgres;
use crate::support::server::Api;
use crate::support::shared_db::{BOUND, asked_once, finishes, owners, start, wait_for};
use crate::support::trainer::Trainer;

/// Synthetic EF-50 sessions long enough to be mid-run when a server is killed.
const STEPS: u64 = 4000;

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
    a.kill();
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
    b.kill();
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
    server.kill();
}

/// A graceful shutdown (SIGTERM) on PostgreSQL hands the server's sessions over: it stops its
/// copies, releases their leases and exits, and another server claims them at its next look
/// (within a second, not the lease's 6 s) and finishes them, every query asked once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_shut_down_gracefully_hands_its_sessions_over_at_once() {
    let Some(pg) = postgres::database().await else {
        return;
    };
    let mut db = sqlx::PgConnection::connect(&pg.url).await.unwrap();
    let (dir_a, dir_b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (mut a, api_a) = start(dir_a.path(), &pg.url, "2");
    let ids = vec![launch(&api_a, 5).await, launch(&api_a, 6).await];
    let server_a = wait_for("A runs both", Duration::from_secs(30), async || {
        let o = owners(&mut db).await;
        let running: Vec<_> = o.values().filter(|(s, _)| s == "running").collect();
        (running.len() == 2).then(|| running[0].1.clone().unwrap())
    })
    .await;
    let (mut b, api_b) = start(dir_b.path(), &pg.url, "2");
    let asked = Instant::now();
    let status = a.terminate();
    let exited = asked.elapsed();
    assert!(status.success(), "A exits cleanly: {status:?}");
    wait_for("B claims both", Duration::from_secs(5), async || {
        let o = owners(&mut db).await;
        ids.iter()
            .all(|id| o[id].1.as_deref().is_some_and(|owner| owner != server_a))
            .then_some(())
    })
    .await;
    let handed = asked.elapsed();
    println!(
        "graceful handover: A exited {:.2} s after SIGTERM; B held both of its sessions {:.2} s \
         after it (a kill waits for the lease: up to {BOUND:?})",
        exited.as_secs_f64(),
        handed.as_secs_f64()
    );
    assert!(
        handed < BOUND,
        "handed over in {handed:?}, no faster than a kill"
    );
    for id in &ids {
        finishes(&api_b, id).await;
        asked_once(&api_b, &mut db, id).await;
    }
    b.kill();
}

/// A human session on a remote env whose server is killed resumes on another server from its
/// run's latest resume checkpoint, which the database keeps (the killed server's disk is not
/// needed), and asks nothing a person answered again, by id or by moment.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_servers_remote_session_resumes_on_another_from_its_checkpoint() {
    let Some(pg) = postgres::database().await else {
        return;
    };
    let mut db = sqlx::PgConnection::connect(&pg.url).await.unwrap();
    let (dir_a, dir_b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (mut a, api_a) = start(dir_a.path(), &pg.url, "1");
    let addr = |api: &Api| api.base.trim_start_matches("http://").parse().unwrap();
    let (id, token) = launch_human_on_line(&api_a, true).await;

    // Episodes are 20 steps: answer past the checkpoint at step 20 by three, leave one open.
    let wait = Duration::from_secs(60);
    let mut t = Trainer::connect(addr(&api_a), &id, &token).await;
    let mut answered: Vec<(i64, u64, Value)> = Vec::new();
    let open = loop {
        let q = t.next_of(&["query"], wait).await;
        let step = q["step"].as_u64().unwrap();
        if step >= 23 {
            break q;
        }
        let qid = q["id"].as_i64().unwrap();
        t.answer(qid, json!(if step % 2 == 0 { 1 } else { -1 }))
            .await;
        assert_eq!(t.next_of(&["ack"], wait).await["id"], qid);
        answered.push((qid, step, q["action"].clone()));
    };
    let kept: i64 = sqlx::query("SELECT COUNT(*) AS n FROM session_resumes WHERE session_id = $1")
        .bind(&id)
        .fetch_one(&mut db)
        .await
        .unwrap()
        .get("n");
    assert_eq!(kept, 1, "the resume checkpoint is in the database");

    // B starts; A dies with its data dir out of reach; B takes the session over.
    let (mut b, api_b) = start(dir_b.path(), &pg.url, "1");
    a.kill();
    drop(dir_a);
    let mut t = wait_for("B runs it and takes the socket", BOUND * 3, async || {
        Trainer::try_connect(addr(&api_b), &id, &token).await
    })
    .await;
    // The open query comes again (same moment: this env repeats its episodes); nothing
    // answered does, by id or by moment.
    let mut after = Vec::new();
    for _ in 0..3 {
        let q = t.next_of(&["query"], wait).await;
        let (qid, step) = (q["id"].as_i64().unwrap(), q["step"].as_u64().unwrap());
        for (done, done_step, done_action) in &answered {
            assert_ne!(qid, *done, "answered query {done} asked again: {q}");
            assert!(
                !(step == *done_step && q["action"] == *done_action),
                "query {qid} asks the moment of answered query {done} again: {q}"
            );
        }
        t.answer(qid, json!(1)).await;
        assert_eq!(t.next_of(&["ack"], wait).await["id"], qid);
        after.push(q);
    }
    assert_eq!(
        (&after[0]["step"], &after[0]["action"]),
        (&open["step"], &open["action"]),
        "the run resumed from its checkpoint at step 20 and met the open moment again"
    );
    t.close().await;
    let (status, _) = api_b
        .post(&format!("/api/sessions/{id}/stop"), json!({}))
        .await;
    assert_eq!(status, 200);
    b.kill();
}
