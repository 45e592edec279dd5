//! Several servers behind a plain round-robin proxy (docs/serving-several.md): Debian's nginx
//! in front of two `dualrep serve` processes on one PostgreSQL. Trainers reach their sessions
//! through the proxy whichever server runs them (a socket that lands on the other server is
//! relayed through the database). One server is killed with SIGKILL after 40 acknowledged
//! answers; the other takes its sessions over; no acknowledged answer is lost, no query is
//! asked again once answered, and every session finishes.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use sqlx::Connection;
use tokio_tungstenite::connect_async;
use tokio_tungstenite::tungstenite::Message;

use crate::support::nginx::Proxy;
use crate::support::postgres;
use crate::support::server::Api;
use crate::support::shared_db::{BOUND, asked_once, owners, start, wait_for};
use crate::support::trainer::token_of;

/// Human EF-100 sessions: every step asks, so answers flow as fast as trainers give them
/// (at 15 steps a second, under a socket's limit of 20 messages a second).
const SESSIONS: u64 = 4;
const STEPS: u64 = 200;
/// Acknowledged answers (over all sessions) before one server is killed.
const KILL_AFTER: usize = 40;

/// What the trainers saw, over all sessions.
#[derive(Default)]
struct Tally {
    /// (session, query) -> the value acknowledged.
    acked: Mutex<HashMap<(String, i64), Value>>,
    acks: AtomicUsize,
    /// Queries shown again after their answer was acknowledged.
    asked_again: Mutex<Vec<(String, i64)>>,
    /// Sockets opened, and those the proxy gave to the server not running the session.
    sockets: AtomicUsize,
    relayed: AtomicUsize,
    /// Sockets that closed before the session ended (the killed server's, relays that ended).
    reconnects: AtomicUsize,
}

/// A trainer that answers +1 to every query of session `id` through the proxy, connecting
/// again whenever its socket closes, until the session ends; the status it ended with.
/// `owner_addr`: the address of the server running the session, as the database says. Until
/// it has had a relayed socket, a trainer whose socket reached the session's own server closes
/// it and connects again (round robin gives it the other server next), so that every session
/// is trained through a relay for a while.
async fn train(
    proxy: SocketAddr,
    id: String,
    token: String,
    tally: Arc<Tally>,
    owner_addr: impl Fn() -> futures_util::future::BoxFuture<'static, Option<String>>,
) -> String {
    let mut relayed_once = false;
    // Round robin gives the other server within a few tries; past ten, keep what came.
    let mut tries = 0;
    loop {
        let url = format!("ws://{proxy}/ws/sessions/{id}?token={token}");
        // Refused (503: between servers) or cut: try again shortly, as the page does.
        let Ok((mut ws, response)) = connect_async(url).await else {
            tokio::time::sleep(Duration::from_millis(200)).await;
            continue;
        };
        tally.sockets.fetch_add(1, Ordering::Relaxed);
        let upstream = response
            .headers()
            .get("x-dualrep-upstream")
            .and_then(|v| v.to_str().ok())
            .map(str::to_owned);
        // nginx names the servers it tried: the last one took the socket.
        let upstream = upstream.and_then(|u| u.rsplit(", ").next().map(str::to_owned));
        match (upstream, owner_addr().await) {
            (Some(up), Some(owner)) if up != owner => {
                tally.relayed.fetch_add(1, Ordering::Relaxed);
                relayed_once = true;
            }
            (Some(_), Some(_)) if !relayed_once && tries < 10 => {
                tries += 1;
                let _ = ws.close(None).await;
                continue;
            }
            _ => {}
        }
        loop {
            let m = match tokio::time::timeout(Duration::from_secs(60), ws.next()).await {
                Ok(Some(Ok(Message::Text(t)))) => serde_json::from_str::<Value>(&t).unwrap(),
                Ok(Some(Ok(Message::Close(_)) | Err(_)) | None) => break,
                Ok(Some(Ok(_))) => continue,
                Err(_) => panic!("session {id}: nothing for 60 s"),
            };
            match m["type"].as_str().unwrap() {
                "query" => {
                    let q = m["id"].as_i64().unwrap();
                    if tally.acked.lock().unwrap().contains_key(&(id.clone(), q)) {
                        tally.asked_again.lock().unwrap().push((id.clone(), q));
                        continue;
                    }
                    let answer = json!({"type": "answer", "id": q, "value": 1}).to_string();
                    if ws.send(Message::Text(answer.into())).await.is_err() {
                        break;
                    }
                }
                "ack" => {
                    let q = m["id"].as_i64().unwrap();
                    tally
                        .acked
                        .lock()
                        .unwrap()
                        .insert((id.clone(), q), m["value"].clone());
                    tally.acks.fetch_add(1, Ordering::Relaxed);
                }
                "ended" => return m["status"].as_str().unwrap().to_owned(),
                // Faster than the socket's rate limit: send it again after the wait.
                "error" if m["code"] == "rate_limited" => {
                    let wait = m["retry_after_ms"].as_u64().unwrap();
                    tokio::time::sleep(Duration::from_millis(wait)).await;
                    let q = m["id"].as_i64().unwrap();
                    let answer = json!({"type": "answer", "id": q, "value": 1}).to_string();
                    if ws.send(Message::Text(answer.into())).await.is_err() {
                        break;
                    }
                }
                // An answer not taken (its server went): the query comes again after the
                // socket reconnects, and is answered then.
                _ => {}
            }
        }
        tally.reconnects.fetch_add(1, Ordering::Relaxed);
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn trainers_through_a_round_robin_proxy_lose_nothing_when_a_server_is_killed() {
    let Some(pg) = postgres::database().await else {
        return;
    };
    let mut db = sqlx::PgConnection::connect(&pg.url).await.unwrap();
    let (dir_a, dir_b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    // Server A alone, two slots: every session is launched on it, it claims two and two wait
    // queued. Server B, four slots, claims those two as it starts and has room for A's after
    // the kill. (With both up before the launches, a launch's own claim races the other
    // server's claim tick, and one server could end up with every session.)
    let (mut a, api_a) = start(dir_a.path(), &pg.url, "2");
    let mut sessions = Vec::new();
    for seed in 0..SESSIONS {
        let (status, r) = api_a
            .post(
                "/api/sessions",
                json!({"task": "reaching", "method": "ef-100", "trainer": "human", "seed": seed,
                       "steps": STEPS,
                       "params": {"pace_hz": 15, "hidden": [32, 32], "batch_size": 32,
                                  "answer_timeout_s": 60, "record": false}}),
            )
            .await;
        assert_eq!(status, 201, "{r}");
        sessions.push((
            r["id"].as_str().unwrap().to_owned(),
            token_of(r["trainer_url"].as_str().unwrap()),
        ));
    }
    let id_a = api_a.get("/healthz").await["server"]
        .as_str()
        .unwrap()
        .to_owned();
    wait_for("A runs two sessions", Duration::from_secs(30), async || {
        let o = owners(&mut db).await;
        let on_a = o
            .values()
            .filter(|(s, owner)| s == "running" && owner.as_deref() == Some(id_a.as_str()))
            .count();
        let queued = o.values().filter(|(s, _)| s == "queued").count();
        (on_a == 2 && queued == 2).then_some(())
    })
    .await;
    let (mut b, api_b) = start(dir_b.path(), &pg.url, "4");
    let addr = |api: &Api| api.base.trim_start_matches("http://").to_owned();
    let (addr_a, addr_b) = (addr(&api_a), addr(&api_b));
    let proxy = Proxy::start(&[addr_a.parse().unwrap(), addr_b.parse().unwrap()]);
    let id_b = api_b.get("/healthz").await["server"]
        .as_str()
        .unwrap()
        .to_owned();
    let servers = (id_a, id_b);
    wait_for(
        "B runs the other two",
        Duration::from_secs(30),
        async || {
            let o = owners(&mut db).await;
            let on_b = o
                .values()
                .filter(|(s, owner)| s == "running" && owner.as_deref() == Some(servers.1.as_str()))
                .count();
            (on_b == 2).then_some(())
        },
    )
    .await;
    let address_of: Arc<HashMap<String, String>> = Arc::new(HashMap::from([
        (servers.0.clone(), addr_a.clone()),
        (servers.1.clone(), addr_b.clone()),
    ]));

    let tally = Arc::new(Tally::default());
    let trainers: Vec<_> = sessions
        .iter()
        .map(|(id, token)| {
            let (url, id2, address_of) = (pg.url.clone(), id.clone(), address_of.clone());
            let owner_addr = move || -> futures_util::future::BoxFuture<'static, Option<String>> {
                let (url, id, address_of) = (url.clone(), id2.clone(), address_of.clone());
                Box::pin(async move {
                    let mut db = sqlx::PgConnection::connect(&url).await.ok()?;
                    let owner = owners(&mut db).await.get(&id)?.1.clone()?;
                    address_of.get(&owner).cloned()
                })
            };
            tokio::spawn(train(
                proxy.addr,
                id.clone(),
                token.clone(),
                tally.clone(),
                owner_addr,
            ))
        })
        .collect();

    // Kill A after 40 acknowledged answers.
    wait_for(
        "40 acknowledged answers",
        Duration::from_secs(60),
        async || (tally.acks.load(Ordering::Relaxed) >= KILL_AFTER).then_some(()),
    )
    .await;
    a.kill();
    let killed = Instant::now();
    let acked_at_kill = tally.acks.load(Ordering::Relaxed);
    let on_a: Vec<String> = {
        let o = owners(&mut db).await;
        sessions
            .iter()
            .map(|(id, _)| id.clone())
            .filter(|id| o[id].1.as_deref() == Some(servers.0.as_str()))
            .collect()
    };
    assert!(
        !on_a.is_empty(),
        "A ran sessions when it was killed (raise STEPS)"
    );
    wait_for("B takes A's sessions over", BOUND * 3, async || {
        let o = owners(&mut db).await;
        on_a.iter()
            .all(|id| o[id].1.as_deref() == Some(servers.1.as_str()))
            .then_some(())
    })
    .await;
    let takeover = killed.elapsed();

    // Every session finishes; every acknowledged answer is stored as acknowledged.
    for t in trainers {
        let status = tokio::time::timeout(Duration::from_secs(300), t)
            .await
            .expect("the sessions finish within 300 s")
            .unwrap();
        assert_eq!(status, "finished");
    }
    let finished = killed.elapsed();
    let acked = tally.acked.lock().unwrap().clone();
    let mut lost = Vec::new();
    for (id, _) in &sessions {
        let answers: Value = api_b.get(&format!("/api/sessions/{id}/answers")).await;
        let stored: HashMap<i64, Value> = answers
            .as_array()
            .unwrap()
            .iter()
            .map(|a| (a["query_id"].as_i64().unwrap(), a["value"].clone()))
            .collect();
        assert_eq!(
            stored.len() as u64,
            STEPS,
            "{id}: every step asked and answered"
        );
        for ((s, q), v) in &acked {
            if s == id && stored.get(q) != Some(v) {
                lost.push((s.clone(), *q));
            }
        }
        asked_once(&api_b, &mut db, id).await;
    }
    let asked_again = tally.asked_again.lock().unwrap().clone();
    println!(
        "proxy: {} sessions of {STEPS} steps, {} sockets ({} to the server not running the \
         session, relayed), {} closed and reconnected; A killed after {acked_at_kill} acks, ran \
         {} sessions; B owned them all {:.2} s after the kill; all finished {:.2} s after it; \
         {} answers acknowledged, {} lost, {} queries asked again",
        SESSIONS,
        tally.sockets.load(Ordering::Relaxed),
        tally.relayed.load(Ordering::Relaxed),
        tally.reconnects.load(Ordering::Relaxed),
        on_a.len(),
        takeover.as_secs_f64(),
        finished.as_secs_f64(),
        acked.len(),
        lost.len(),
        asked_again.len(),
    );
    assert!(lost.is_empty(), "acknowledged answers lost: {lost:?}");
    assert!(asked_again.is_empty(), "asked again: {asked_again:?}");
    assert!(
        tally.relayed.load(Ordering::Relaxed) > 0,
        "no socket went through a relay:\n{}",
        proxy.log()
    );
    b.kill();
}
