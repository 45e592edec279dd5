//! Datasets for other tools: a session's labelled transitions and preference pairs as Parquet,
//! read back by Python's pyarrow with as many rows as the API lists answers; the DRPL posterior
//! and the learner's policy as safetensors; `dualrep export` giving the same files from the
//! data dir alone.

use std::time::{Duration, Instant};

use crate::support::pyarrow_py::read_parquet;
use crate::support::server::{Api, TOKEN, serve};
use dualrep::guidance::drpl::posterior_file::read_posterior;
use serde_json::{Value, json};

/// Launch `body` and wait until the session has finished.
async fn finished(api: &Api, body: Value) -> String {
    let (status, created) = api.post("/api/sessions", body).await;
    assert_eq!(status, 201, "{created}");
    let id = created["id"].as_str().unwrap().to_string();
    let start = Instant::now();
    loop {
        let s = api.get(&format!("/api/sessions/{id}")).await;
        match s["status"].as_str() {
            Some("finished") => return id,
            Some("queued" | "running" | "waiting") => {}
            other => panic!("session {id} ended {other:?}: {s}"),
        }
        assert!(start.elapsed() < Duration::from_secs(120), "{s}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// `GET path` as bytes, with its status.
async fn bytes(api: &Api, path: &str) -> (u16, Vec<u8>) {
    let r = api
        .http
        .get(format!("{}{path}", api.base))
        .bearer_auth(TOKEN)
        .send()
        .await
        .unwrap();
    (r.status().as_u16(), r.bytes().await.unwrap().to_vec())
}

fn safetensor_names(bytes: &[u8]) -> Vec<String> {
    safetensors::SafeTensors::deserialize(bytes)
        .unwrap()
        .names()
        .into_iter()
        .map(String::from)
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn parquet_exports_read_back_in_pyarrow_with_the_apis_rows() {
    let dir = tempfile::tempdir().unwrap();
    let server = serve(dir.path()).await;
    let api = Api::new(server.addr);
    let out = tempfile::tempdir().unwrap();

    // An evaluative session: every step asked, so every transition is labelled.
    let ef = finished(
        &api,
        json!({"task": "reaching", "method": "ef-100", "trainer": "synthetic", "seed": 2, "steps": 120,
               "params": {"hidden": [16, 16], "batch_size": 16, "checkpoint_every": 50}}),
    )
    .await;
    let answers = api.get(&format!("/api/sessions/{ef}/answers")).await;
    let answers = answers.as_array().unwrap();
    assert_eq!(answers.len(), 120);
    let (status, parquet) = bytes(&api, &format!("/api/sessions/{ef}/dataset.parquet")).await;
    assert_eq!(status, 200);
    let file = out.path().join("transitions.parquet");
    std::fs::write(&file, &parquet).unwrap();
    let table = read_parquet(&file);
    assert_eq!(table["num_rows"].as_u64(), Some(answers.len() as u64));
    assert_eq!(table["columns"]["observation"], "list<item: float>");
    let rows = table["rows"].as_array().unwrap();
    for (row, answer) in rows.iter().zip(answers) {
        assert_eq!(row["query_id"], answer["query_id"]);
        assert_eq!(row["label"].as_f64(), answer["value"].as_f64(), "{row}");
        assert_eq!(row["who"], "synthetic");
        assert_eq!(
            row["observation"].as_array().unwrap().len(),
            2,
            "Reaching observes the gripper's x and y"
        );
        assert_eq!(row["action"].as_array().unwrap().len(), 2);
        assert!(row["reward"].is_number() && row["next_observation"].is_array());
    }
    // The policy: the actor's weights, no posterior.
    let (status, policy) = bytes(&api, &format!("/api/sessions/{ef}/policy.safetensors")).await;
    assert_eq!(status, 200);
    let names = safetensor_names(&policy);
    assert!(
        !names.is_empty() && names.iter().all(|n| n.starts_with("actor.")),
        "{names:?}"
    );
    let (status, _) = bytes(&api, &format!("/api/sessions/{ef}/posterior.safetensors")).await;
    assert_eq!(status, 404, "an evaluative session has no posterior");

    // A preference session: the pairs, both segments' features, and the posterior.
    let drpl = finished(
        &api,
        json!({"task": "reaching", "method": "drpl", "trainer": "synthetic", "seed": 3, "queries": 6,
               "params": {"trajectories": 12}}),
    )
    .await;
    let answers = api.get(&format!("/api/sessions/{drpl}/answers")).await;
    let answers = answers.as_array().unwrap();
    let (_, parquet) = bytes(&api, &format!("/api/sessions/{drpl}/dataset.parquet")).await;
    let file = out.path().join("pairs.parquet");
    std::fs::write(&file, &parquet).unwrap();
    let table = read_parquet(&file);
    assert_eq!(table["num_rows"].as_u64(), Some(answers.len() as u64));
    for (row, answer) in table["rows"].as_array().unwrap().iter().zip(answers) {
        assert_eq!(row["choice"], answer["value"], "{row}");
        for side in ["left", "right"] {
            assert_eq!(row[format!("{side}_features")].as_array().unwrap().len(), 4);
            assert!(row[format!("{side}_end")].as_i64() > row[format!("{side}_start")].as_i64());
        }
    }
    let (status, posterior) =
        bytes(&api, &format!("/api/sessions/{drpl}/posterior.safetensors")).await;
    assert_eq!(status, 200);
    let (samples, mean) = read_posterior(&posterior).unwrap();
    assert_eq!(
        (samples.len(), mean.len()),
        (100, 4),
        "APReL's 100 samples of theta"
    );
    server.shutdown().await.unwrap();

    // The same files from the data dir alone.
    for (id, what) in [(&ef, "table"), (&drpl, "posterior")] {
        let target = out.path().join(format!("{id}-{what}"));
        let output = crate::support::cli::dualrep_in(
            &[
                "export",
                "--data-dir",
                dir.path().to_str().unwrap(),
                "--session",
                id,
                "--what",
                what,
                "--out",
                target.to_str().unwrap(),
            ],
            None,
        );
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        let written = std::fs::read(&target).unwrap();
        if what == "table" {
            assert_eq!(read_parquet(&target)["num_rows"], 120);
        } else {
            assert_eq!(
                &written, &posterior,
                "the posterior file as the API gave it"
            );
        }
    }
}
