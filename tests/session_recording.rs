//! A short synthetic session on the server records itself: the `.rrd` in the data dir (and
//! behind `GET .../recording.rrd`) is read back with the Python `rerun-sdk` of the same version
//! and checked against the session's step count, its stored answers and its episodes.

use crate::support::rerun_py;

use std::time::{Duration, Instant};

use crate::support::server::{TOKEN, state};
use axum::body::Body;
use axum::http::{Request, StatusCode, header};
use dualrep::http::app;
use dualrep::scene_graph::SceneGraph;
use dualrep::session::{SessionSpec, TrainerKind};
use dualrep::sim::Task;
use dualrep::store::Status;
use http_body_util::BodyExt;
use serde_json::{Value, json};
use tower::ServiceExt;

fn rows(file: &Value, path: &str) -> u64 {
    file["entities"][path]["rows"]
        .as_u64()
        .unwrap_or_else(|| panic!("no entity {path}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_synthetic_session_records_every_step_query_and_answer() {
    let dir = tempfile::tempdir().unwrap();
    let st = state(dir.path()).await;
    let steps = 250;
    let spec = SessionSpec {
        task: Some(Task::Placing),
        env: None,
        method: "ef-25".parse().unwrap(),
        trainer: TrainerKind::Synthetic,
        seed: 5,
        budget: steps,
        params: serde_json::from_value(json!({"hidden": [16, 16], "batch_size": 32})).unwrap(),
    };
    let id = st.hub.launch(spec).await.unwrap().id;
    let start = Instant::now();
    loop {
        // The stored status: the final one is written before the hub lets the session go.
        let row = st.store.session(&id).await.unwrap().unwrap();
        if !row.status.is_active() {
            assert_eq!(row.status, Status::Finished, "{:?}", row.reason);
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "the session did not finish"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let answers = st.store.answers(&id).await.unwrap();
    let episodes = st.store.episodes(&id).await.unwrap();
    assert!(!answers.is_empty());

    // The file the API serves is the one in the data dir.
    let rrd = st.hub.recording_path(&id);
    let response = app(st.clone())
        .oneshot(
            Request::get(format!("/api/sessions/{id}/recording.rrd"))
                .header(header::AUTHORIZATION, format!("Bearer {TOKEN}"))
                .body(Body::empty())
                .unwrap(),
        )
        .await
        .unwrap();
    assert_eq!(response.status(), StatusCode::OK);
    let served = response.into_body().collect().await.unwrap().to_bytes();
    assert_eq!(served.as_ref(), std::fs::read(&rrd).unwrap().as_slice());

    let file = rerun_py::read_rrd(&rrd);
    assert_eq!(
        file["recordings"],
        json!([{"application_id": "dualrep", "recording_id": id}])
    );
    assert_eq!(file["timelines"], json!(["episode", "step"]));
    for path in [
        "world/gripper",
        "world/ball",
        "gripper/closed",
        "reward",
        "cumulative_return",
    ] {
        assert_eq!(rows(&file, path), steps, "{path}: one row per step");
    }
    for p in SceneGraph::for_task(Task::Placing).predicates() {
        assert_eq!(rows(&file, &format!("predicates/{}", p.name)), steps);
    }
    let asked = answers.len() as u64;
    assert_eq!(
        (
            rows(&file, "queries"),
            rows(&file, "answers"),
            rows(&file, "answers/value")
        ),
        (asked, asked, asked)
    );
    let values: Vec<f64> = file["entities"]["answers/value"]["scalars"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let stored: Vec<f64> = answers.iter().map(|a| a.value.as_number()).collect();
    assert_eq!(
        values, stored,
        "the recording's answers are the stored ones, in order"
    );
    // The cumulative return at the end of each episode is the one the store holds.
    let cumulative = file["entities"]["cumulative_return"]["scalars"]
        .as_array()
        .unwrap();
    for e in &episodes {
        let at = cumulative[(e.step - 1) as usize].as_f64().unwrap();
        assert!(
            (at - e.cumulative_return).abs() < 1e-3,
            "episode {}: {at} vs {}",
            e.episode,
            e.cumulative_return
        );
    }
}
