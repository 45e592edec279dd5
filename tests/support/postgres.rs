//! A throwaway PostgreSQL for tests: Debian's `postgresql` (installed with apt-get when no
//! `initdb` is found under /usr/lib/postgresql/*/bin, and only then), a cluster made by `initdb`
//! in a private temporary directory, `postgres` in the foreground as a child of the test on a
//! free port on 127.0.0.1 (its socket in that directory too), and a fresh database per test.
//!
//! initdb refuses to run as root, and the tests run as root in CI and containers: there the
//! cluster belongs to an unprivileged user created for it, `dualrep-pg` (made with useradd if
//! missing), and `initdb` and `postgres` run as that user. Anyone else runs them as themself.
//! Authentication is `trust` on loopback only: nothing outside this machine can reach it.
//!
//! Tests that run at once share one cluster, each with its own database; the cluster stops when
//! the last of them lets go of it (a test that panics too), and the next test starts another.
//! `DUALREP_SKIP_POSTGRES=1` skips the PostgreSQL tests, loudly, where PostgreSQL can be neither
//! found nor installed; without it, that is a failure.

use std::fs;
use std::net::TcpListener;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, Weak};
use std::thread;
use std::time::{Duration, Instant};

use sqlx::Connection;

/// The user that owns the cluster when the tests run as root.
const USER: &str = "dualrep-pg";
/// The superuser `initdb` makes (trusted on loopback).
const SUPERUSER: &str = "postgres";

/// The running cluster the tests share, if one runs.
static SHARED: Mutex<Weak<Cluster>> = Mutex::new(Weak::new());

pub struct Cluster {
    dir: tempfile::TempDir,
    child: Child,
    port: u16,
    /// `postgres --version`, e.g. "postgres (PostgreSQL) 15.18 (Debian 15.18-0+deb12u1)".
    pub version: String,
    databases: AtomicUsize,
}

/// A fresh database on the shared cluster; the cluster stays up while this lives.
pub struct TestDatabase {
    pub url: String,
    /// Holds the cluster up while the test runs.
    _cluster: Arc<Cluster>,
}

/// A new database for one test, or `None` when `DUALREP_SKIP_POSTGRES=1` and PostgreSQL is not
/// installed (and cannot be).
pub async fn database() -> Option<TestDatabase> {
    let cluster = tokio::task::spawn_blocking(Cluster::shared)
        .await
        .expect("starting PostgreSQL")?;
    let name = format!("t{}", cluster.databases.fetch_add(1, Ordering::Relaxed));
    let mut admin = sqlx::PgConnection::connect(&cluster.url("postgres"))
        .await
        .unwrap_or_else(|e| panic!("connecting to the test cluster: {e}\n{}", cluster.log()));
    sqlx::raw_sql(sqlx::AssertSqlSafe(format!("CREATE DATABASE {name}")))
        .execute(&mut admin)
        .await
        .unwrap();
    admin.close().await.unwrap();
    Some(TestDatabase {
        url: cluster.url(&name),
        _cluster: cluster,
    })
}

/// The newest `/usr/lib/postgresql/<version>/bin` that holds `initdb`.
fn bin_dir() -> Option<PathBuf> {
    let mut found: Vec<(u32, PathBuf)> = fs::read_dir("/usr/lib/postgresql")
        .ok()?
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let version = e.file_name().to_str()?.parse().ok()?;
            let bin = e.path().join("bin");
            bin.join("initdb").is_file().then_some((version, bin))
        })
        .collect();
    found.sort();
    found.pop().map(|(_, bin)| bin)
}

/// Debian's PostgreSQL, installed if missing (as root; else a failure that says what to do).
fn install() -> Option<PathBuf> {
    if let Some(bin) = bin_dir() {
        return Some(bin);
    }
    if std::env::var("DUALREP_SKIP_POSTGRES").is_ok_and(|v| v == "1") {
        eprintln!(
            "\n!!!!!!!! POSTGRESQL TESTS SKIPPED (DUALREP_SKIP_POSTGRES=1): the store on \
             PostgreSQL is NOT tested !!!!!!!!\n"
        );
        return None;
    }
    super::debian::install(
        "postgresql",
        ", or set DUALREP_SKIP_POSTGRES=1 to skip the PostgreSQL tests",
    );
    Some(bin_dir().expect("postgresql installed, yet no initdb under /usr/lib/postgresql/*/bin"))
}

/// The uid and gid the cluster runs as: `dualrep-pg`'s (created if missing) when root, else
/// none (this process's own).
fn owner() -> Option<(u32, u32)> {
    if !super::debian::is_root() {
        return None;
    }
    let id = |flag: &str| {
        Command::new("id")
            .args([flag, USER])
            .output()
            .ok()
            .filter(|o| o.status.success())
            .and_then(|o| String::from_utf8(o.stdout).ok()?.trim().parse().ok())
    };
    if id("-u").is_none() {
        // Another test process may create it at the same moment: its failure is fine as long
        // as the user exists afterwards.
        let _ = Command::new("useradd")
            .args([
                "--system",
                "--user-group",
                "--no-create-home",
                "--home-dir",
                "/nonexistent",
                "--shell",
                "/usr/sbin/nologin",
                USER,
            ])
            .status();
    }
    match (id("-u"), id("-g")) {
        (Some(uid), Some(gid)) => Some((uid, gid)),
        _ => panic!("could not create the user {USER} (useradd) for the test's PostgreSQL"),
    }
}

/// A port that was free a moment ago (postgres binds it right after).
pub fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

impl Cluster {
    /// The running cluster, started if none runs; `None` when skipped.
    fn shared() -> Option<Arc<Cluster>> {
        let mut shared = SHARED.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(cluster) = shared.upgrade() {
            return Some(cluster);
        }
        let bin = install()?;
        let owner = owner();
        // A port taken between choosing it and binding it stops postgres: try again on another.
        let mut last_error = String::new();
        for _ in 0..3 {
            match Cluster::start(&bin, owner) {
                Ok(cluster) => {
                    let cluster = Arc::new(cluster);
                    *shared = Arc::downgrade(&cluster);
                    return Some(cluster);
                }
                Err(why) => last_error = why,
            }
        }
        panic!("the test's PostgreSQL did not start: {last_error}");
    }

    fn start(bin: &Path, owner: Option<(u32, u32)>) -> Result<Cluster, String> {
        let started = Instant::now();
        let dir = tempfile::Builder::new()
            .prefix("dualrep-pg-")
            .tempdir()
            .unwrap();
        if let Some((uid, gid)) = owner {
            std::os::unix::fs::chown(dir.path(), Some(uid), Some(gid)).unwrap();
        }
        let as_owner = |program: &str| {
            let mut command = Command::new(bin.join(program));
            command.current_dir(dir.path()).stdin(Stdio::null());
            if let Some((uid, gid)) = owner {
                // std drops the supplementary groups too.
                command.uid(uid).gid(gid);
            }
            command
        };
        let data = dir.path().join("data");
        let init = as_owner("initdb")
            .arg("-D")
            .arg(&data)
            .args(["-U", SUPERUSER, "--auth=trust", "-E", "UTF8", "--no-locale"])
            // Nothing to keep: skip initdb's fsync of every file it wrote.
            .arg("--no-sync")
            .output()
            .map_err(|e| format!("running initdb: {e}"))?;
        if !init.status.success() {
            return Err(format!(
                "initdb failed:\n{}{}",
                String::from_utf8_lossy(&init.stdout),
                String::from_utf8_lossy(&init.stderr)
            ));
        }
        let version = String::from_utf8_lossy(
            &as_owner("postgres")
                .arg("--version")
                .output()
                .map_err(|e| format!("running postgres --version: {e}"))?
                .stdout,
        )
        .trim()
        .to_string();
        let port = free_port();
        let log = fs::File::create(dir.path().join("postgres.log")).unwrap();
        let child = as_owner("postgres")
            .arg("-D")
            .arg(&data)
            .args(["-p", &port.to_string(), "-c", "listen_addresses=127.0.0.1"])
            // A throwaway cluster: nothing in it needs to survive a power cut, and without
            // fsync its databases are made and its shutdown checkpoint written in a moment.
            // (The server's `synchronous_commit = on` stays as it is; `--database` servers are
            // not run like this.)
            .args(["-c", "fsync=off"])
            .arg("-k")
            .arg(dir.path())
            .stdout(log.try_clone().unwrap())
            .stderr(log)
            .spawn()
            .map_err(|e| format!("starting postgres: {e}"))?;
        let mut cluster = Cluster {
            dir,
            child,
            port,
            version,
            databases: AtomicUsize::new(0),
        };
        // Ready once it accepts connections (pg_isready exits 0).
        loop {
            if let Ok(Some(status)) = cluster.child.try_wait() {
                return Err(format!("postgres exited ({status}):\n{}", cluster.log()));
            }
            let ready = Command::new(bin.join("pg_isready"))
                .args(["-q", "-h", "127.0.0.1", "-p", &port.to_string()])
                .status()
                .is_ok_and(|s| s.success());
            if ready {
                break;
            }
            if started.elapsed() > Duration::from_secs(60) {
                return Err(format!(
                    "postgres did not accept connections within 60 s:\n{}",
                    cluster.log()
                ));
            }
            thread::sleep(Duration::from_millis(50));
        }
        eprintln!(
            "postgres: {} on 127.0.0.1:{port}{}, ready {:.2} s after initdb began",
            cluster.version,
            owner.map_or(String::new(), |_| format!(" as {USER}")),
            started.elapsed().as_secs_f64()
        );
        Ok(cluster)
    }

    /// The URL of one of its databases.
    pub fn url(&self, database: &str) -> String {
        format!("postgres://{SUPERUSER}@127.0.0.1:{}/{database}", self.port)
    }

    /// The server's log, for a failure message.
    pub fn log(&self) -> String {
        fs::read_to_string(self.dir.path().join("postgres.log")).unwrap_or_default()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let child = &mut self.child;
        let stop = Instant::now();
        // SIGINT: PostgreSQL's fast shutdown (clients are disconnected, not waited for).
        let _ = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status();
        let deadline = Instant::now() + Duration::from_secs(10);
        while child.try_wait().ok().flatten().is_none() && Instant::now() < deadline {
            thread::sleep(Duration::from_millis(20));
        }
        let how = if child.try_wait().ok().flatten().is_none() {
            let _ = child.kill();
            let _ = child.wait();
            "killed"
        } else {
            "stopped"
        };
        eprintln!(
            "postgres: {how} {:.2} s after SIGINT",
            stop.elapsed().as_secs_f64()
        );
    }
}
