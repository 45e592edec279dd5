//! The client against envs that misbehave on purpose: each test runs a small env server on a
//! thread that answers `hello` properly and then does one wrong thing, and checks the reason the
//! client gives.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use super::*;
use crate::sim::Env;

fn hello() -> Value {
    json!({"type": "hello", "protocol": 1, "env": {
        "id": "line",
        "observation_space": {"shape": [2], "low": [-1, -1], "high": [1, 1]},
        "action_space": {"shape": [1], "low": [-2], "high": [2]},
        "control_hz": 10,
        "max_episode_steps": 3,
        "predicates": [{"name": "right", "label": "point right"}],
        "render": true,
        "deterministic": true
    }})
}

fn read(s: &mut TcpStream) -> Option<Value> {
    let mut len = [0u8; 4];
    s.read_exact(&mut len).ok()?;
    let mut body = vec![0u8; u32::from_be_bytes(len) as usize];
    s.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok()
}

fn write_raw(s: &mut TcpStream, body: &[u8]) {
    let _ = s.write_all(&(body.len() as u32).to_be_bytes());
    let _ = s.write_all(body);
}

fn write(s: &mut TcpStream, v: &Value) {
    write_raw(s, &serde_json::to_vec(v).unwrap());
}

/// An env on a free port: it answers `hello`, then hands each later request to `answer`
/// (which writes whatever it likes; returning false closes the connection).
fn env(answer: impl FnMut(&mut TcpStream, Value) -> bool + Send + 'static) -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("tcp://{}", listener.local_addr().unwrap());
    std::thread::spawn(move || {
        let mut answer = answer;
        let (mut s, _) = listener.accept().unwrap();
        let Some(first) = read(&mut s) else { return };
        assert_eq!(first["type"], "hello");
        write(&mut s, &hello());
        while let Some(request) = read(&mut s) {
            if !answer(&mut s, request) {
                return;
            }
        }
    });
    url
}

fn fast() -> Timeouts {
    Timeouts {
        connect: Duration::from_secs(5),
        request: Duration::from_millis(500),
    }
}

fn reset_ok(s: &mut TcpStream) {
    write(
        s,
        &json!({"type": "reset", "obs": [0.0, 0.5], "holding": []}),
    );
}

#[test]
fn a_well_behaved_env_steps_with_scaled_actions_and_reported_predicates() {
    let url = env(|s, r| {
        match r["type"].as_str().unwrap() {
            "reset" => reset_ok(s),
            "step" => {
                // The learner's -1..1 arrives in the env's -2..2.
                let a = r["action"][0].as_f64().unwrap();
                write(
                    s,
                    &json!({"type": "step", "obs": [a, 0.0], "reward": 1.5, "terminated": false,
                            "truncated": false, "holding": if a > 0.0 { json!(["right"]) } else { json!([]) }}),
                );
            }
            _ => return false,
        }
        true
    });
    let mut e = RemoteEnv::connect(&url, fast()).unwrap();
    assert_eq!(e.spec().action_space.dim(), 1);
    assert_eq!(e.try_reset(7).unwrap(), vec![0.0, 0.5]);
    let s = e.try_step(&[0.5]).unwrap();
    assert_eq!((s.obs[0], s.reward, s.outcome), (1.0, 1.5, None));
    assert_eq!(e.reported_predicates(), Some(1));
    let s = e.try_step(&[-1.0]).unwrap();
    assert_eq!(s.obs[0], -2.0);
    assert_eq!(e.reported_predicates(), Some(0));
    // The declared limit of 3 steps truncates, as Gymnasium's TimeLimit would.
    let s = e.try_step(&[3.0]).unwrap();
    assert_eq!(s.obs[0], 2.0, "actions are clipped to [-1, 1] first");
    assert!(s.truncated && !s.terminated);
    assert_eq!(s.outcome, Some(crate::sim::Outcome::TimeLimit));
    assert!(e.try_step(&[0.0]).unwrap_err().0.contains("reset first"));
}

/// Connect, reset, step once, and return the fault the step gave.
fn step_fault(answer: impl FnMut(&mut TcpStream, Value) -> bool + Send + 'static) -> String {
    let url = env(answer);
    let mut e = RemoteEnv::connect(&url, fast()).unwrap();
    e.try_reset(1).unwrap();
    let fault = e.try_step(&[0.0]).unwrap_err().0;
    // Broken for good: the same reason again, at once.
    let start = Instant::now();
    assert_eq!(e.try_reset(1).unwrap_err().0, fault);
    assert!(start.elapsed() < Duration::from_millis(100));
    assert!(fault.contains(&url), "{fault}");
    fault
}

fn after_reset(
    mut on_step: impl FnMut(&mut TcpStream) -> bool + Send + 'static,
) -> impl FnMut(&mut TcpStream, Value) -> bool + Send + 'static {
    move |s, r| {
        if r["type"] == "reset" {
            reset_ok(s);
            true
        } else {
            on_step(s)
        }
    }
}

#[test]
fn a_slow_env_times_out() {
    let fault = step_fault(after_reset(|_| {
        std::thread::sleep(Duration::from_secs(2));
        false
    }));
    assert!(fault.contains("no answer within 0.5 s"), "{fault}");
}

#[test]
fn an_env_that_dies_mid_episode_is_said_to_have_closed() {
    let fault = step_fault(after_reset(|_| false));
    assert!(fault.contains("closed the connection"), "{fault}");
}

#[test]
fn malformed_and_inconsistent_replies_are_named() {
    let cases: Vec<(Value, &str)> = vec![
        (
            json!({"type": "step", "obs": [0.0], "reward": 0, "terminated": false, "truncated": false}),
            "an observation of 1 entries",
        ),
        (
            json!({"type": "step", "obs": [0.0, 1.0], "reward": 0, "terminated": false, "truncated": false,
                "holding": ["left"]}),
            "\"left\" holds, but it was not declared",
        ),
        (
            json!({"type": "step", "obs": [0.0, 1.0], "reward": 0, "terminated": false, "truncated": false,
                "features": [1.0]}),
            "features",
        ),
        (
            json!({"type": "step", "obs": [0.0, 1.0], "reward": 0, "terminated": false, "truncated": false,
                "colour": "red"}),
            "malformed message",
        ),
        (
            json!({"type": "reset", "obs": [0.0, 1.0]}),
            "answered a step with a reset",
        ),
        (
            json!({"type": "error", "message": "the gripper jammed"}),
            "it reported an error: the gripper jammed",
        ),
    ];
    for (reply, expected) in cases {
        let fault = step_fault(after_reset(move |s| {
            write(s, &reply);
            true
        }));
        assert!(fault.contains(expected), "{fault} (expected {expected})");
    }
    let fault = step_fault(after_reset(|s| {
        write_raw(s, b"{not json");
        true
    }));
    assert!(fault.contains("malformed message"), "{fault}");
    let fault = step_fault(after_reset(|s| {
        write_raw(s, &[]);
        let _ = s.write_all(&(1u32 << 30).to_be_bytes());
        true
    }));
    assert!(
        fault.contains("malformed message") || fault.contains("at most"),
        "{fault}"
    );
}

#[test]
fn frames_come_exactly_when_asked_and_must_be_what_they_say() {
    let png = b"\x89PNG\r\n\x1a\n0123".to_vec();
    // Asked and sent: kept as the render state's frame.
    let sent = png.clone();
    let url = env(move |s, r| {
        let frame = json!({"format": "png", "width": 4, "height": 2, "bytes": sent.len()});
        write(
            s,
            &json!({"type": "reset", "obs": [0.0, 0.0], "frame": frame}),
        );
        let _ = s.write_all(&sent);
        r["render"] == true
    });
    let mut e = RemoteEnv::connect(&url, fast()).unwrap();
    e.set_frames(true);
    e.try_reset(0).unwrap();
    match e.render() {
        crate::sim::RenderState::Remote { frame: Some(f), .. } => {
            assert_eq!((f.width, f.height, &f.data[..]), (4, 2, &png[..]));
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        e.geometry(),
        crate::sim::Geometry::Remote {
            frame_size: Some([4, 2]),
            ..
        }
    ));
    // Not asked, but sent.
    let sent = png.clone();
    let url = env(move |s, _| {
        let frame = json!({"format": "png", "width": 4, "height": 2, "bytes": sent.len()});
        write(
            s,
            &json!({"type": "reset", "obs": [0.0, 0.0], "frame": frame}),
        );
        let _ = s.write_all(&sent);
        true
    });
    let mut e = RemoteEnv::connect(&url, fast()).unwrap();
    assert!(e.try_reset(0).unwrap_err().0.contains("nobody asked"));
    // Asked, and a GIF announced as a PNG.
    let url = env(|s, _| {
        write(
            s,
            &json!({"type": "reset", "obs": [0.0, 0.0],
                         "frame": {"format": "png", "width": 1, "height": 1, "bytes": 6}}),
        );
        let _ = s.write_all(b"GIF89a");
        true
    });
    let mut e = RemoteEnv::connect(&url, fast()).unwrap();
    e.set_frames(true);
    assert!(e.try_reset(0).unwrap_err().0.contains("not a png file"));
}

#[test]
fn an_unreachable_env_or_a_bad_hello_fails_the_connection() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("tcp://{}", listener.local_addr().unwrap());
    drop(listener);
    let fault = RemoteEnv::connect(&url, fast()).err().unwrap().0;
    assert!(fault.contains("unreachable"), "{fault}");
    // An env that speaks another protocol version.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("tcp://{}", listener.local_addr().unwrap());
    std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        read(&mut s);
        let mut h = hello();
        h["protocol"] = json!(2);
        write(&mut s, &h);
    });
    let fault = RemoteEnv::connect(&url, fast()).err().unwrap().0;
    assert!(fault.contains("protocol 2"), "{fault}");
}

#[test]
fn a_connection_says_close_when_it_is_let_go_and_a_broken_one_does_not() {
    let (seen_tx, seen) = std::sync::mpsc::channel::<String>();
    let url = env(move |s, r| {
        let kind = r["type"].as_str().unwrap().to_string();
        let _ = seen_tx.send(kind.clone());
        match kind.as_str() {
            "reset" => reset_ok(s),
            "close" => {
                write(s, &json!({"type": "close"}));
                return false;
            }
            _ => return false,
        }
        true
    });
    let mut e = RemoteEnv::connect(&url, fast()).unwrap();
    e.try_reset(1).unwrap();
    drop(e);
    let wait = Duration::from_secs(5);
    assert_eq!(seen.recv_timeout(wait).unwrap(), "reset");
    assert_eq!(
        seen.recv_timeout(wait).unwrap(),
        "close",
        "dropping the env says goodbye"
    );

    // After a fault the connection is gone: no goodbye, and no wait for one.
    let (seen_tx, seen) = std::sync::mpsc::channel::<String>();
    let url = env(move |_, r| {
        let _ = seen_tx.send(r["type"].as_str().unwrap().to_string());
        false // closes on the first request
    });
    let mut e = RemoteEnv::connect(&url, fast()).unwrap();
    assert!(e.try_reset(1).is_err());
    let start = Instant::now();
    drop(e);
    assert!(start.elapsed() < Duration::from_millis(400));
    assert_eq!(seen.recv_timeout(wait).unwrap(), "reset");
    assert!(seen.recv_timeout(Duration::from_millis(200)).is_err());
}
