//! Environments in another process through the env protocol, end to end: Gymnasium's
//! Pendulum-v1 served by `python -m dualrep.env` (the package in `clients/python/`, installed
//! into a venv the tests create) trains a synthetic DREF session and a DRPL session through a
//! running server; an env server killed mid-session and started again lets the session resume
//! from its latest checkpoint without asking an answered query again; and the package's own
//! pytest suite runs against the server.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use crate::support::cli::{dualrep_in, ok};
use crate::support::python_client::{EnvServer, python};
use crate::support::server::{Api, TOKEN, root};
use dualrep::cli::serve::{ServeArgs, start};
use serde_json::{Value, json};

const PENDULUM_SCENE: &[&str] = &["--predicates", "dualrep.scenes:pendulum"];

async fn serve_with_models(data: &Path, models: &Path) -> dualrep::cli::serve::Running {
    start(ServeArgs {
        addr: "127.0.0.1:0".parse().unwrap(),
        data_dir: data.to_path_buf(),
        database: None,
        token: Some(TOKEN.into()),
        max_sessions: Some(2),
        web_dir: Some(root().join("web")),
        models_dir: Some(models.to_path_buf()),
        cors_origins: vec![],
        shutdown_grace_s: 30.0,
        rerun_connect: None,
    })
    .await
    .unwrap()
}

async fn launch(api: &Api, body: Value) -> String {
    let (status, r) = api.post("/api/sessions", body).await;
    assert_eq!(status, 201, "{r}");
    r["id"].as_str().unwrap().to_string()
}

/// Poll until the session's status is one of `until`.
async fn wait_until(api: &Api, id: &str, until: &[&str], within: Duration) -> Value {
    let start = Instant::now();
    loop {
        let v = api.get(&format!("/api/sessions/{id}")).await;
        if until.contains(&v["status"].as_str().unwrap()) {
            return v;
        }
        assert!(start.elapsed() < within, "session {id} still {v}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Stored answers by query number.
async fn answers(api: &Api, id: &str) -> BTreeMap<i64, Value> {
    api.get(&format!("/api/sessions/{id}/answers"))
        .await
        .as_array()
        .unwrap()
        .iter()
        .map(|a| (a["query_id"].as_i64().unwrap(), a["value"].clone()))
        .collect()
}

/// A small expert for Pendulum-v1, trained on the remote env by the CLI.
fn train_expert(url: &str, models: &Path) {
    let out = models.join("Pendulum-v1.safetensors");
    let note = ok(&dualrep_in(
        &[
            "expert",
            "--env-url",
            url,
            "--steps",
            "1500",
            "--set",
            "hidden=32,32",
            "--set",
            "batch_size=64",
            "--eval-episodes",
            "1",
            "--out",
            out.to_str().unwrap(),
        ],
        None,
    ));
    assert_eq!(note["task"], "Pendulum-v1");
    assert_eq!(note["env_url"], url);
    assert!(out.is_file());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_gymnasium_env_trains_dref_and_drpl_sessions_and_its_death_loses_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    let env = tokio::task::spawn_blocking(|| EnvServer::start("Pendulum-v1", PENDULUM_SCENE, 0))
        .await
        .unwrap();
    let url = env.url.clone();
    {
        let (url, models) = (url.clone(), models.clone());
        tokio::task::spawn_blocking(move || train_expert(&url, &models))
            .await
            .unwrap();
    }
    let server = serve_with_models(&dir.path().join("data"), &models).await;
    let api = Api::new(server.addr);
    let small = json!({"hidden": [32, 32], "batch_size": 64});

    // A synthetic DREF session on the env's own task: its predicates, the expert trained above.
    let dref = launch(
        &api,
        json!({"env": {"url": url}, "method": "dref", "trainer": "synthetic", "steps": 1000, "params": small}),
    )
    .await;
    // A synthetic DRPL session: trajectories recorded on the env, features from its observation.
    let drpl = launch(
        &api,
        json!({"env": {"url": url}, "method": "drpl", "trainer": "synthetic", "queries": 8,
               "params": {"trajectories": 12}}),
    )
    .await;
    let v = wait_until(
        &api,
        &dref,
        &["finished", "failed"],
        Duration::from_secs(300),
    )
    .await;
    assert_eq!(v["status"], "finished", "{v}");
    assert_eq!(
        (v["task"].as_str(), v["progress"].as_i64()),
        (Some("remote"), Some(1000))
    );
    let episodes = api.get(&format!("/api/sessions/{dref}/episodes")).await;
    assert_eq!(
        episodes.as_array().unwrap().len(),
        5,
        "Pendulum's episodes are 200 steps"
    );
    let asked = answers(&api, &dref).await;
    let last = &episodes.as_array().unwrap()[4];
    assert_eq!(asked.len() as i64, last["feedback_count"].as_i64().unwrap());
    assert!(
        !asked.is_empty()
            && asked
                .values()
                .all(|a| [-1, 0, 1].contains(&a.as_i64().unwrap()))
    );
    let v = wait_until(
        &api,
        &drpl,
        &["finished", "failed"],
        Duration::from_secs(300),
    )
    .await;
    assert_eq!(v["status"], "finished", "{v}");
    let alignment = api.get(&format!("/api/sessions/{drpl}/alignment")).await;
    assert_eq!(alignment.as_array().unwrap().len(), 8, "one row per query");
    assert_eq!(answers(&api, &drpl).await.len(), 8);

    // Kill the env mid-session: the session fails with the reason and keeps its answers.
    let long = launch(
        &api,
        json!({"env": {"url": url}, "method": "dref", "trainer": "synthetic", "steps": 2400,
               "params": {"hidden": [32, 32], "batch_size": 64, "checkpoint_every": 200}}),
    )
    .await;
    let start = Instant::now();
    while api.get(&format!("/api/sessions/{long}")).await["progress"]
        .as_i64()
        .unwrap()
        < 700
    {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "the session does not progress"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let port = env.port();
    env.kill();
    let v = wait_until(
        &api,
        &long,
        &["failed", "finished"],
        Duration::from_secs(60),
    )
    .await;
    assert_eq!(v["status"], "failed", "{v}");
    let reason = v["reason"].as_str().unwrap();
    assert!(
        reason.contains("closed the connection") || reason.contains("connection failed"),
        "{reason}"
    );
    assert!(reason.contains(&url), "{reason}");
    let before = answers(&api, &long).await;
    let episodes_before = api
        .get(&format!("/api/sessions/{long}/episodes"))
        .await
        .as_array()
        .unwrap()
        .len();
    assert!(
        episodes_before >= 3,
        "{episodes_before} episodes before the env died"
    );

    // Resuming while the env is down fails again, with the reason, and loses nothing.
    let (status, _) = api
        .post(&format!("/api/sessions/{long}/resume"), json!({}))
        .await;
    assert_eq!(status, 200);
    let v = wait_until(&api, &long, &["failed"], Duration::from_secs(60)).await;
    assert!(v["reason"].as_str().unwrap().contains("unreachable"), "{v}");
    assert_eq!(answers(&api, &long).await, before);

    // The env comes back on its port: the session resumes from its latest checkpoint.
    let env =
        tokio::task::spawn_blocking(move || EnvServer::start("Pendulum-v1", PENDULUM_SCENE, port))
            .await
            .unwrap();
    assert_eq!(env.url, url);
    let (status, _) = api
        .post(&format!("/api/sessions/{long}/resume"), json!({}))
        .await;
    assert_eq!(status, 200);
    let v = wait_until(
        &api,
        &long,
        &["finished", "failed"],
        Duration::from_secs(300),
    )
    .await;
    assert_eq!(v["status"], "finished", "{v}");
    let after = answers(&api, &long).await;
    // Nothing stored was lost or changed, and every new query has a number of its own.
    for (id, value) in &before {
        assert_eq!(after.get(id), Some(value), "query {id}");
    }
    let first_new = before.keys().max().map_or(0, |m| m + 1);
    assert!(
        after
            .keys()
            .filter(|id| !before.contains_key(id))
            .all(|&id| id >= first_new)
    );
    let episodes = api.get(&format!("/api/sessions/{long}/episodes")).await;
    let episodes = episodes.as_array().unwrap();
    assert_eq!(episodes.len(), 12, "2400 steps of 200-step episodes");
    let steps: Vec<i64> = episodes
        .iter()
        .map(|e| e["step"].as_i64().unwrap())
        .collect();
    assert_eq!(steps, (1..=12).map(|e| e * 200).collect::<Vec<_>>());
    // The run resumed from a checkpoint, not from step 0: it kept the episodes before it, and
    // lost at most the queries of the one episode the env died in.
    let run_feedback = episodes[11]["feedback_count"].as_i64().unwrap();
    let lost = after.len() as i64 - run_feedback;
    assert!(
        (0..=200).contains(&lost),
        "{lost} answered queries the run does not have"
    );
    drop(env);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_python_package_tests_pass_against_a_running_server() {
    let dir = tempfile::tempdir().unwrap();
    let server = crate::support::server::serve(dir.path()).await;
    let url = format!("http://{}", server.addr);
    let out = tokio::task::spawn_blocking(move || {
        std::process::Command::new(python())
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider", "-rs"])
            .arg(root().join("clients/python/tests"))
            .env("DUALREP_TEST_URL", url)
            .env("DUALREP_TEST_TOKEN", TOKEN)
            .output()
            .expect("pytest runs")
    })
    .await
    .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "pytest failed:\n{text}");
    // With a server given, nothing may be skipped.
    let summary = text
        .lines()
        .rev()
        .find(|l| l.contains(" passed"))
        .unwrap_or_default();
    assert!(
        !summary.contains("skipped") && !summary.contains("failed"),
        "{summary}"
    );
    server.shutdown().await.unwrap();
}
