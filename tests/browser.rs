//! Browser tests of the web UI: the real `dualrep serve` binary, Debian's Chromium driven by
//! `playwright-core` from plain Node scripts in `tests/browser/`. Each test starts its own server
//! on a free port with a fresh data dir and runs one script; screenshots land in
//! `$DUALREP_ARTIFACTS` (default `<target dir>/browser-artifacts`).
//!
//! Needs `chromium`, `node` and `npm` (`bash tests/run.sh` installs whichever is missing; Debian's `npm`
//! only where Node.js itself comes from Debian). `DUALREP_SKIP_BROWSER=1` skips these tests, loudly; without it a missing
//! browser is a failure.

use crate::support::binary;
use std::path::{Path, PathBuf};

use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::Instant;

/// One browser test at a time: each runs a server, a session and a Chromium.
static SERIAL: Mutex<()> = Mutex::new(());

const TOKEN: &str = "browser-test-token";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn which(program: &str) -> Option<PathBuf> {
    let out = Command::new("which").arg(program).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let path = String::from_utf8_lossy(&out.stdout).trim().to_string();
    (!path.is_empty()).then(|| PathBuf::from(path))
}

/// Chromium's path, or `None` when the tests are to be skipped.
fn chromium() -> Option<PathBuf> {
    let skip = std::env::var("DUALREP_SKIP_BROWSER").is_ok_and(|v| v == "1");
    let found = (which("chromium"), which("node"), which("npm"));
    match found {
        (Some(chromium), Some(_), Some(_)) => Some(chromium),
        _ if skip => {
            eprintln!(
                "\n!!!!!!!! BROWSER TESTS SKIPPED (DUALREP_SKIP_BROWSER=1): the web UI is NOT tested !!!!!!!!\n"
            );
            None
        }
        (c, n, p) => {
            // Only what is missing: a Node.js from another source ships its own npm, and
            // Debian's `npm` package conflicts with it.
            let mut missing = Vec::new();
            if c.is_none() {
                missing.push("chromium");
            }
            if n.is_none() {
                missing.push("nodejs");
            }
            if p.is_none() && n.is_none() {
                missing.push("npm");
            }
            let install = if missing.is_empty() {
                format!(
                    "npm is missing beside the Node.js at {}: install the npm that goes with it",
                    n.as_ref()
                        .map_or_else(String::new, |n| n.display().to_string())
                )
            } else {
                format!(
                    "install them with `sudo apt-get install -y {}`",
                    missing.join(" ")
                )
            };
            panic!(
                "the browser tests need Debian's chromium, node and npm (found: chromium {}, \
                 node {}, npm {}).\n{install} (`bash tests/run.sh` installs what is missing, then runs \
                 every test), or set DUALREP_SKIP_BROWSER=1 to skip these tests.",
                c.is_some(),
                n.is_some(),
                p.is_some(),
            )
        }
    }
}

/// `npm ci` (or `npm install` without a lock file) when `node_modules` is missing.
fn node_modules() {
    let dir = root().join("tests/browser");
    if dir.join("node_modules/playwright-core").is_dir() {
        return;
    }
    let sub = if dir.join("package-lock.json").is_file() {
        "ci"
    } else {
        "install"
    };
    let status = Command::new("npm")
        .args([sub, "--no-audit", "--no-fund"])
        .current_dir(&dir)
        .status()
        .expect("running npm");
    assert!(status.success(), "`npm {sub}` in tests/browser failed");
}

fn artifacts() -> PathBuf {
    if let Ok(dir) = std::env::var("DUALREP_ARTIFACTS") {
        return PathBuf::from(dir);
    }
    let target =
        std::env::var("CARGO_TARGET_DIR").map_or_else(|_| root().join("target"), PathBuf::from);
    target.join("browser-artifacts")
}

/// A running `dualrep serve`, killed on drop.
struct Server {
    child: Child,
    url: String,
    _data: tempfile::TempDir,
}

impl Server {
    fn start(args: &[&str]) -> Server {
        let data = tempfile::tempdir().expect("a temp dir");
        let (child, url) = binary::start_serve(data.path(), TOKEN, args, Stdio::inherit());
        Server {
            child,
            url,
            _data: data,
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Run `tests/browser/<script>` against a fresh server; `extra` adds environment variables.
fn browser_test(script: &str, extra: &[(&str, &str)]) {
    browser_test_serving(script, extra, &[]);
}

/// [`browser_test`] with `serve_args` added to `dualrep serve`; false when the browser tests
/// are skipped (`DUALREP_SKIP_BROWSER=1`), true once the script passed.
fn browser_test_serving(script: &str, extra: &[(&str, &str)], serve_args: &[&str]) -> bool {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let Some(chromium) = chromium() else {
        return false;
    };
    node_modules();
    let server = Server::start(serve_args);
    let artifacts = artifacts();
    std::fs::create_dir_all(&artifacts).expect("creating the artifacts dir");
    let started = Instant::now();
    let mut cmd = Command::new("node");
    cmd.arg(Path::new("tests/browser").join(script))
        .current_dir(root())
        .env("DUALREP_URL", &server.url)
        .env("DUALREP_TOKEN", TOKEN)
        .env("CHROMIUM", &chromium)
        .env("DUALREP_ARTIFACTS", &artifacts);
    for (k, v) in extra {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("running node");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stdout}");
    eprintln!("{stderr}");
    drop(server);
    assert!(
        out.status.success(),
        "browser test {script} failed after {:.1} s ({}):\n{stdout}\n{stderr}",
        started.elapsed().as_secs_f64(),
        out.status
    );
    true
}

#[test]
fn dashboard_launches_dref_and_the_trainer_answers_with_keys() {
    browser_test("dref_keys.mjs", &[]);
}

#[test]
fn trainer_answers_a_drpl_session_with_the_mouse() {
    browser_test("drpl_mouse.mjs", &[]);
}

#[test]
fn trainer_stores_the_three_questions() {
    browser_test("drpl_mouse.mjs", &[("SURVEY", "1")]);
}

#[test]
fn trainer_recovers_the_pending_query_after_a_dropped_socket() {
    browser_test("reconnect.mjs", &[]);
}

#[test]
fn trainer_page_sends_a_rate_limited_answer_again_after_the_wait() {
    browser_test("rate_limited.mjs", &[]);
}

#[test]
fn two_named_trainers_answer_each_query_and_the_review_shows_their_agreement() {
    browser_test("two_trainers.mjs", &[]);
}

#[test]
fn review_shows_episodes_answers_and_metrics() {
    browser_test("review.mjs", &[]);
}

#[test]
fn review_replays_an_episode() {
    browser_test("review.mjs", &[("REPLAY", "1")]);
}

#[test]
fn study_participants_train_every_condition_in_their_williams_order_and_the_results_count_them() {
    // Two sessions at once: of three participants starting together, one waits in the queue.
    let table = artifacts().join("study-table.parquet");
    let _ = std::fs::remove_file(&table);
    if !browser_test_serving("study.mjs", &[], &["--max-sessions", "2"]) {
        return;
    }
    // The Parquet table the results page downloaded, as pandas or R would read it.
    let read = crate::support::pyarrow_py::read_parquet(&table);
    assert_eq!(read["num_rows"], 9, "three participants x three conditions");
    let rows = read["rows"].as_array().unwrap();
    let mut cells: Vec<(String, String)> = rows
        .iter()
        .map(|r| {
            (
                r["participant_id"].as_str().unwrap().to_string(),
                r["condition"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    cells.sort();
    cells.dedup();
    assert_eq!(
        cells.len(),
        9,
        "each participant x condition once: {cells:?}"
    );
    for row in rows {
        for q in ["E", "I", "C"] {
            let answer = row[format!("survey_{q}")].as_i64();
            assert!(matches!(answer, Some(1..=5)), "survey_{q} in {row}");
        }
        assert_eq!(row["ended_early"], false, "{row}");
    }
}

#[test]
fn trainer_draws_a_remote_envs_own_frames() {
    // Gymnasium's Pendulum-v1 behind `python -m dualrep.env`, a task of its own.
    let env = crate::support::python_client::EnvServer::start(
        "Pendulum-v1",
        &["--predicates", "dualrep.scenes:pendulum"],
        0,
    );
    browser_test("remote_frames.mjs", &[("ENV_URL", &env.url)]);
}
