//! The Python package in `clients/python/`, installed with its test extras (pytest, mypy,
//! Gymnasium's classic-control envs) into a virtual environment the tests create on first use:
//! `$DUALREP_CLIENT_VENV`, default `~/.cache/dualrep/venv-client`, never the repository.
//!
//! The install is redone only when the package's sources change (a digest of them is kept in
//! the venv) or the venv lacks a package; a lock file beside it serialises installs between
//! concurrent test processes. Also: env servers (`python -m dualrep.env`) as child processes.

use std::fs;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

use super::py_venv::{Venv, pip_install, run, runs};

fn package_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("clients/python")
}

/// FNV-1a over the package's source files (paths and contents), as hex.
fn source_digest() -> String {
    fn walk(dir: &Path, files: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for path in entries {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let generated = name == "build"
                || name.ends_with(".egg-info")
                || name.starts_with('.')
                || name == "__pycache__";
            if generated {
                continue;
            }
            if path.is_dir() {
                walk(&path, files);
            } else {
                files.push(path);
            }
        }
    }
    let root = package_dir();
    let mut files = Vec::new();
    walk(&root, &mut files);
    let mut bytes = Vec::new();
    for f in files {
        bytes.extend_from_slice(f.strip_prefix(&root).unwrap().to_string_lossy().as_bytes());
        bytes.extend_from_slice(&fs::read(&f).unwrap());
    }
    dualrep::session::digest(&bytes)
}

/// The venv's interpreter, with the current `clients/python` and its test extras importable.
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = Venv {
            var: "DUALREP_CLIENT_VENV",
            name: "venv-client",
        };
        let stamp = venv.dir().join("dualrep-source.digest");
        let digest = source_digest();
        venv.ensure(
            "clients/python[test]",
            |python| {
                fs::read_to_string(&stamp).is_ok_and(|s| s.trim() == digest)
                    && runs(
                        python,
                        "import dualrep, dualrep.env, gymnasium, pygame, pytest, mypy",
                    )
            },
            |python| {
                // From a copy: pip builds in the source tree, and the repository stays clean.
                let copy = tempfile::tempdir().unwrap();
                let src = copy.path().join("python");
                run(Command::new("cp").arg("-r").arg(package_dir()).arg(&src));
                pip_install(python, &[&format!("{}[test]", src.display())]);
                fs::write(&stamp, &digest).unwrap();
            },
        )
    })
}

/// `python -m dualrep.env ...` on a port, killed when dropped.
pub struct EnvServer {
    child: Child,
    pub url: String,
}

impl EnvServer {
    /// Serve Gymnasium's `gym_id` with `args` (e.g. `--predicates MODULE:FUNC`) on `port` (0:
    /// any free one); waits for the line that names its URL.
    pub fn start(gym_id: &str, args: &[&str], port: u16) -> Self {
        let mut child = Command::new(python())
            .args([
                "-m",
                "dualrep.env",
                "--gym",
                gym_id,
                "--port",
                &port.to_string(),
            ])
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("starting python -m dualrep.env");
        let stdout = child.stdout.take().expect("piped stdout");
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if let Some(url) = line
                    .split(" on ")
                    .nth(1)
                    .filter(|u| u.starts_with("tcp://"))
                {
                    let _ = tx.send(url.trim().to_string());
                }
            }
        });
        let url = rx
            .recv_timeout(Duration::from_secs(60))
            .unwrap_or_else(|_| {
                let _ = child.kill();
                panic!("python -m dualrep.env --gym {gym_id} did not print its URL within 60 s")
            });
        Self { child, url }
    }

    pub fn port(&self) -> u16 {
        self.url.rsplit(':').next().unwrap().parse().unwrap()
    }

    /// Kill it at once (the env dies mid-episode).
    pub fn kill(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for EnvServer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
