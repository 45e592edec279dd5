//! `dualrep loadtest`: real websocket trainers against a server (one started in this process,
//! or a running one at `--addr`). M human EF-100 sessions ask a query every step at `--pace-hz`;
//! N trainers, spread over the sessions, answer every query at once (all with the same value,
//! so the first commits and the rest are idempotent repeats). Prints one JSON object: answers
//! per second, ack latency percentiles, errors, and `lost`: acknowledged answers that the API
//! does not return afterwards (must be 0).

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::Args;
use futures_util::{SinkExt, StreamExt};
use serde::Serialize;
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;

use super::serve::{ServeArgs, start};

#[derive(Debug, Args)]
pub struct LoadtestArgs {
    /// Trainer websockets in all.
    #[arg(long, default_value_t = 500)]
    pub trainers: usize,
    /// Sessions the trainers are spread over.
    #[arg(long, default_value_t = 50)]
    pub sessions: usize,
    /// How long trainers answer.
    #[arg(long, default_value_t = 20.0)]
    pub seconds: f64,
    /// A running server [default: start one in this process with a fresh data dir].
    #[arg(long)]
    pub addr: Option<SocketAddr>,
    /// The running server's researcher token [default: DUALREP_TOKEN].
    #[arg(long, env = "DUALREP_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Steps (and so queries) per second of each session.
    #[arg(long, default_value_t = 5.0)]
    pub pace_hz: f64,
    /// Task of the sessions.
    #[arg(long, default_value = "reaching")]
    pub task: String,
}

/// What one trainer saw.
#[derive(Default)]
struct TrainerLog {
    sent: u64,
    /// Milliseconds from sending an answer to its `ack`.
    latencies: Vec<f64>,
    /// `(session, query id, value)` of every acknowledged answer (a query id names a query
    /// within its session).
    acked: Vec<(Arc<str>, i64, i64)>,
    errors: HashMap<String, u64>,
    /// Trainers that never connected.
    connect_failures: u64,
    /// Connection attempts refused and tried again.
    connect_retries: u64,
}

/// How long a trainer waits before it tries a refused connection again.
const CONNECT_RETRY: Duration = Duration::from_millis(200);

#[derive(Serialize)]
struct Report {
    trainers: usize,
    sessions: usize,
    seconds: f64,
    pace_hz: f64,
    answers_sent: u64,
    acks: u64,
    answers_per_second: f64,
    /// Distinct queries answered (each by the first of its session's trainers).
    queries_answered: usize,
    ack_latency_ms: Value,
    errors: u64,
    errors_by_code: HashMap<String, u64>,
    connect_failures: u64,
    connect_retries: u64,
    lost: u64,
    server: &'static str,
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((p / 100.0) * (sorted.len() - 1) as f64).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

/// The value every trainer gives a query: the same for all of them, varied across queries.
fn value_for(query_id: i64) -> i64 {
    [1, 0, -1][query_id.rem_euclid(3) as usize]
}

async fn trainer(session: Arc<str>, url: String, until: Instant, log: Arc<Mutex<TrainerLog>>) {
    // Nagle off, as a browser's small websocket messages go out at once. A refusal (503: on
    // PostgreSQL a session no server has claimed yet) is tried again, as the page does.
    let mut retries = 0;
    let socket = loop {
        match tokio_tungstenite::connect_async_with_config(&url, None, true).await {
            Ok((s, _)) => break s,
            Err(_) if Instant::now() + CONNECT_RETRY < until => {
                retries += 1;
                tokio::time::sleep(CONNECT_RETRY).await;
            }
            Err(_) => {
                let mut log = log.lock().unwrap();
                log.connect_failures += 1;
                log.connect_retries += retries;
                return;
            }
        }
    };
    let (mut tx, mut rx) = socket.split();
    let mut sent_at: HashMap<i64, Instant> = HashMap::new();
    let mut local = TrainerLog::default();
    loop {
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break;
        }
        let msg = match tokio::time::timeout(left, rx.next()).await {
            Ok(Some(Ok(Message::Text(t)))) => t,
            Ok(Some(Ok(_))) => continue,
            Ok(Some(Err(_)) | None) | Err(_) => break,
        };
        let Ok(v) = serde_json::from_str::<Value>(&msg) else {
            continue;
        };
        let id = v["id"].as_i64().unwrap_or(-1);
        match v["type"].as_str() {
            Some("query") if !sent_at.contains_key(&id) => {
                let answer =
                    json!({"type": "answer", "id": id, "value": value_for(id)}).to_string();
                sent_at.insert(id, Instant::now());
                local.sent += 1;
                if tx.send(Message::Text(answer.into())).await.is_err() {
                    break;
                }
            }
            Some("ack") => {
                if let Some(t) = sent_at.get(&id) {
                    local.latencies.push(t.elapsed().as_secs_f64() * 1e3);
                    local
                        .acked
                        .push((session.clone(), id, v["value"].as_i64().unwrap_or(99)));
                }
            }
            Some("error") => {
                let code = v["code"].as_str().unwrap_or("?").to_string();
                *local.errors.entry(code).or_default() += 1;
            }
            Some("ended") => break,
            _ => {}
        }
    }
    let _ = tx.close().await;
    let mut log = log.lock().unwrap();
    log.connect_retries += retries;
    log.sent += local.sent;
    log.latencies.extend(local.latencies);
    log.acked.extend(local.acked);
    for (k, n) in local.errors {
        *log.errors.entry(k).or_default() += n;
    }
}

pub fn run(args: LoadtestArgs) -> anyhow::Result<()> {
    if args.trainers == 0 || args.sessions == 0 || args.trainers < args.sessions {
        bail!("--trainers must be at least --sessions (and both at least 1)");
    }
    tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?
        .block_on(loadtest(args))
}

async fn loadtest(args: LoadtestArgs) -> anyhow::Result<()> {
    let data_dir = tempfile::tempdir().context("a temporary data dir")?;
    let (addr, token, running) = match args.addr {
        Some(addr) => {
            let token = args
                .token
                .clone()
                .context("--addr needs --token (or DUALREP_TOKEN)")?;
            (addr, token, None)
        }
        None => {
            let running = start(ServeArgs {
                addr: "127.0.0.1:0".parse()?,
                data_dir: data_dir.path().to_path_buf(),
                database: None,
                token: Some(crate::hub::random_hex(16)),
                max_sessions: Some(args.sessions),
                web_dir: None,
                models_dir: None,
                cors_origins: vec![],
                shutdown_grace_s: 30.0,
                rerun_connect: None,
            })
            .await?;
            (running.addr, running.token.clone(), Some(running))
        }
    };
    let http = reqwest::Client::new();
    let base = format!("http://{addr}");
    // Sessions long enough to outlast the test; no learning (the answer path is under test).
    let steps = ((args.seconds + 30.0) * args.pace_hz * 2.0).ceil() as u64;
    let mut sessions = Vec::new();
    for seed in 0..args.sessions {
        let r: Value = http
            .post(format!("{base}/api/sessions"))
            .bearer_auth(&token)
            .json(&json!({
                "task": args.task, "method": "ef-100", "trainer": "human", "seed": seed, "steps": steps,
                "params": {"pace_hz": args.pace_hz, "answer_timeout_s": 30, "hidden": [32, 32],
                           "batch_size": 32, "learning_starts": steps + 1, "checkpoint_every": steps + 1,
                           "record": false}
            }))
            .send()
            .await?
            .error_for_status()?
            .json()
            .await?;
        let id = r["id"].as_str().context("no id")?.to_string();
        let url = r["trainer_url"].as_str().context("no trainer_url")?;
        let token = url
            .split("token=")
            .nth(1)
            .context("no token in trainer_url")?
            .to_string();
        sessions.push((id, token));
    }
    let log = Arc::new(Mutex::new(TrainerLog::default()));
    let start_at = Instant::now();
    let until = start_at + Duration::from_secs_f64(args.seconds);
    let tasks: Vec<_> = (0..args.trainers)
        .map(|i| {
            let (id, t) = &sessions[i % sessions.len()];
            let url = format!("ws://{addr}/ws/sessions/{id}?token={t}");
            tokio::spawn(trainer(id.as_str().into(), url, until, log.clone()))
        })
        .collect();
    for t in tasks {
        let _ = t.await;
    }
    let elapsed = start_at.elapsed().as_secs_f64();
    for (id, _) in &sessions {
        let _ = http
            .post(format!("{base}/api/sessions/{id}/stop"))
            .bearer_auth(&token)
            .send()
            .await;
    }

    // Every acknowledged answer must be in the database, with its value.
    let mut stored: HashMap<(&str, i64), i64> = HashMap::new();
    for (id, _) in &sessions {
        let answers: Vec<Value> = http
            .get(format!("{base}/api/sessions/{id}/answers"))
            .bearer_auth(&token)
            .send()
            .await?
            .error_for_status()?
            .json()
            .await?;
        for a in answers {
            if let (Some(q), Some(v)) = (a["query_id"].as_i64(), a["value"].as_i64()) {
                stored.insert((id.as_str(), q), v);
            }
        }
    }
    let log = std::mem::take(&mut *log.lock().unwrap());
    let lost = log
        .acked
        .iter()
        .filter(|(s, q, v)| stored.get(&(&**s, *q)) != Some(v))
        .count() as u64;
    let queries_answered = log
        .acked
        .iter()
        .map(|(s, q, _)| (s.clone(), *q))
        .collect::<std::collections::HashSet<_>>()
        .len();
    let mut lat = log.latencies.clone();
    lat.sort_by(f64::total_cmp);
    let report = Report {
        trainers: args.trainers,
        sessions: args.sessions,
        seconds: elapsed,
        pace_hz: args.pace_hz,
        answers_sent: log.sent,
        acks: lat.len() as u64,
        answers_per_second: lat.len() as f64 / elapsed,
        queries_answered,
        ack_latency_ms: json!({
            "p50": percentile(&lat, 50.0), "p90": percentile(&lat, 90.0),
            "p99": percentile(&lat, 99.0), "max": lat.last().copied().unwrap_or(f64::NAN),
        }),
        errors: log.errors.values().sum(),
        errors_by_code: log.errors,
        connect_failures: log.connect_failures,
        connect_retries: log.connect_retries,
        lost,
        server: if running.is_some() {
            "in-process"
        } else {
            "external"
        },
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    if let Some(r) = running {
        r.shutdown().await?;
    }
    Ok(())
}
