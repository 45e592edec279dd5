//! A one-dimensional env of its own task, served over the env protocol (`docs/env-protocol.md`)
//! from a thread of the test: the action becomes the observation, and acting right (a > 0)
//! holds the one predicate "right". No Python.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};

use serde_json::{Value, json};

/// The hello of a one-dimensional env of its own task: act right (a > 0) to hold "right".
pub fn line_hello(id: &str, max_episode_steps: u32) -> Value {
    json!({"type": "hello", "protocol": 1, "env": {
        "id": id,
        "observation_space": {"shape": [2], "low": [-1, -1], "high": [1, 1]},
        "action_space": {"shape": [1], "low": [-1], "high": [1]},
        "control_hz": 10,
        "max_episode_steps": max_episode_steps,
        "predicates": [{"name": "right", "label": "point right"}],
        "deterministic": true
    }})
}

/// That env's answer to a step: the action becomes the observation.
pub fn line_step(request: &Value) -> Value {
    let a = request["action"][0].as_f64().unwrap();
    json!({"type": "step", "obs": [a, 0.0], "reward": -a.abs(), "terminated": false,
           "truncated": false, "holding": if a > 0.0 { json!(["right"]) } else { json!([]) }})
}

pub fn read(s: &mut TcpStream) -> Option<Value> {
    let mut len = [0u8; 4];
    s.read_exact(&mut len).ok()?;
    let mut body = vec![0u8; u32::from_be_bytes(len) as usize];
    s.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok()
}

pub fn write(s: &mut TcpStream, v: &Value) {
    let body = serde_json::to_vec(v).unwrap();
    s.write_all(&(body.len() as u32).to_be_bytes()).unwrap();
    s.write_all(&body).unwrap();
}

/// An env of its own task on a free port, serving every connection (a resumed session connects
/// again). `repeats`: each reset starts the same episode, as an env server written from
/// `docs/env-protocol.md` for a simulator may; else each connection starts from elsewhere, as
/// a robot would.
pub fn line_env(repeats: bool) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("tcp://{}", listener.local_addr().unwrap());
    std::thread::spawn(move || {
        for (connection, stream) in listener.incoming().enumerate() {
            let Ok(mut s) = stream else { return };
            let start = if repeats {
                0.0
            } else {
                0.3 * connection as f64
            };
            std::thread::spawn(move || {
                while let Some(request) = read(&mut s) {
                    let reply = match request["type"].as_str().unwrap() {
                        "hello" => line_hello("line", 20),
                        "reset" => json!({"type": "reset", "obs": [start, 0.0]}),
                        "step" => line_step(&request),
                        "close" => {
                            write(&mut s, &json!({"type": "close"}));
                            return;
                        }
                        _ => return,
                    };
                    write(&mut s, &reply);
                }
            });
        }
    });
    url
}

/// A human EF-100 session of 200 steps on a new [`line_env`] (episodes of 20 steps, a
/// checkpoint after each), launched through `api`; its id and trainer token.
pub async fn launch_human_on_line(api: &super::server::Api, repeats: bool) -> (String, String) {
    let (status, launched) = api
        .post(
            "/api/sessions",
            json!({"env": {"url": line_env(repeats)}, "method": "ef-100", "trainer": "human",
                   "seed": 3, "steps": 200,
                   "params": {"hidden": [8, 8], "batch_size": 16, "record": false,
                              "pace_hz": 200, "answer_timeout_s": 60}}),
        )
        .await;
    assert_eq!(status, 201, "{launched}");
    let id = launched["id"].as_str().unwrap().to_string();
    (
        id,
        super::trainer::token_of(launched["trainer_url"].as_str().unwrap()),
    )
}
