//! A session on an env that dies mid-run (a small env server on a thread, no Python): the
//! progress the failed session reports is the step its reason names, and a resume answers,
//! and keeps, the progress the session had made.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::{Duration, Instant};

use crate::support::server::{Api, serve};
use serde_json::{Value, json};

/// The env answers this many steps, then closes the connection on the next.
const DIES_AT_STEP: u64 = 157;

fn read(s: &mut TcpStream) -> Option<Value> {
    let mut len = [0u8; 4];
    s.read_exact(&mut len).ok()?;
    let mut body = vec![0u8; u32::from_be_bytes(len) as usize];
    s.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok()
}

fn write(s: &mut TcpStream, v: &Value) {
    let body = serde_json::to_vec(v).unwrap();
    s.write_all(&(body.len() as u32).to_be_bytes()).unwrap();
    s.write_all(&body).unwrap();
}

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
                "hello" => json!({"type": "hello", "protocol": 1, "env": {
                    "id": "dying-line",
                    "observation_space": {"shape": [2], "low": [-1, -1], "high": [1, 1]},
                    "action_space": {"shape": [1], "low": [-1], "high": [1]},
                    "control_hz": 10,
                    "max_episode_steps": 50,
                    "predicates": [{"name": "right", "label": "point right"}],
                    "deterministic": true
                }}),
                "reset" => json!({"type": "reset", "obs": [0.0, 0.0]}),
                "step" if steps == DIES_AT_STEP => return,
                "step" => {
                    steps += 1;
                    let a = request["action"][0].as_f64().unwrap();
                    json!({"type": "step", "obs": [a, 0.0], "reward": -a.abs(), "terminated": false,
                           "truncated": false, "holding": if a > 0.0 { json!(["right"]) } else { json!([]) }})
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
