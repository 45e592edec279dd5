//! Several `dualrep serve` processes on one PostgreSQL, as the tests run them
//! (`serving_several`, `serving_proxy`): start one, read who owns what, wait, and check that a
//! session finished with every query asked and answered once.

use std::collections::{HashMap, HashSet};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;
use sqlx::Row;

use super::binary::start_serve;
use super::server::{Api, TOKEN};

/// The lease (6 s) plus the claim period (1 s): `server/hub/leases.rs`.
pub const BOUND: Duration = Duration::from_secs(7);

/// A server process, killed with SIGKILL when dropped, so that a failing test leaves none
/// running.
pub struct ServerProcess(Child);

impl ServerProcess {
    /// SIGKILL, and reap it.
    pub fn kill(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

impl ServerProcess {
    /// SIGTERM (a graceful shutdown), and wait for the process to exit.
    pub fn terminate(&mut self) -> std::process::ExitStatus {
        let status = std::process::Command::new("kill")
            .args(["-TERM", &self.0.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        self.0.wait().unwrap()
    }
}

impl Drop for ServerProcess {
    fn drop(&mut self) {
        self.kill();
    }
}

/// `dualrep serve` on the PostgreSQL at `url` with `max` slots; the process and its API. Its
/// log goes to the test's stderr with `DUALREP_TEST_SERVER_LOG=1` (and `RUST_LOG`).
pub fn start(data: &std::path::Path, url: &str, max: &str) -> (ServerProcess, Api) {
    let log = if std::env::var_os("DUALREP_TEST_SERVER_LOG").is_some() {
        Stdio::inherit()
    } else {
        Stdio::null()
    };
    let (child, base) = start_serve(
        data,
        TOKEN,
        &["--database", url, "--max-sessions", max],
        log,
    );
    (
        ServerProcess(child),
        Api::new(base.trim_start_matches("http://").parse().unwrap()),
    )
}

/// `(id -> (status, owner))` of every session, from the database.
pub async fn owners(db: &mut sqlx::PgConnection) -> HashMap<String, (String, Option<String>)> {
    sqlx::query("SELECT id, status, owner FROM sessions")
        .fetch_all(db)
        .await
        .unwrap()
        .iter()
        .map(|r| (r.get("id"), (r.get("status"), r.get("owner"))))
        .collect()
}

/// Every answer of session `id` (read through `api`) is to a different query, and every query
/// stored for it has its one answer.
pub async fn asked_once(api: &Api, db: &mut sqlx::PgConnection, id: &str) {
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
pub async fn finishes(api: &Api, id: &str) {
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

pub async fn wait_for<T>(
    what: &str,
    within: Duration,
    mut check: impl AsyncFnMut() -> Option<T>,
) -> T {
    let start = Instant::now();
    loop {
        if let Some(t) = check().await {
            return t;
        }
        assert!(start.elapsed() < within, "{what} within {within:?}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}
