//! The Python `rerun-sdk` of the same version as the `rerun` crate, in a virtual environment the
//! tests create on first use, for reading `.rrd` files back (system.md: both SDKs must read
//! them).
//!
//! The venv lives at `$DUALREP_PY_VENV`, default `~/.cache/dualrep/venv-rerun`, and is reused
//! across runs and clones. A lock file next to it serialises installs between concurrent test
//! processes; a venv whose install was interrupted is repaired on the next run.

use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// Must equal the `rerun` crate's version in Cargo.toml.
pub const RERUN_VERSION: &str = "0.36.3";

/// The venv's Python interpreter, with `rerun-sdk==RERUN_VERSION` importable.
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(install)
}

fn venv_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("DUALREP_PY_VENV") {
        return PathBuf::from(dir);
    }
    let home = std::env::var_os("HOME").expect("HOME is set (or set DUALREP_PY_VENV)");
    PathBuf::from(home).join(".cache/dualrep/venv-rerun")
}

/// Whether `python` imports rerun at exactly our version.
fn has_rerun(python: &Path) -> bool {
    python.exists()
        && Command::new(python)
            .args([
                "-c",
                &format!("import sys, rerun; sys.exit(rerun.__version__ != '{RERUN_VERSION}')"),
            ])
            .output()
            .is_ok_and(|o| o.status.success())
}

fn install() -> PathBuf {
    let venv = venv_dir();
    let python = venv.join("bin/python");
    if has_rerun(&python) {
        return python;
    }
    let parent = venv.parent().expect("the venv path has a parent");
    fs::create_dir_all(parent).unwrap();
    let lock = File::create(venv.with_extension("lock")).unwrap();
    // Another test process may be installing: wait for it, then look again.
    lock.lock().unwrap();
    if !has_rerun(&python) {
        if !python.exists() {
            run(Command::new("python3")
                .args(["-m", "venv", "--clear"])
                .arg(&venv));
        }
        eprintln!(
            "installing rerun-sdk=={RERUN_VERSION} into {}",
            venv.display()
        );
        run(Command::new(&python).args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            &format!("rerun-sdk=={RERUN_VERSION}"),
        ]));
        assert!(
            has_rerun(&python),
            "rerun-sdk {RERUN_VERSION} is not importable after installing it"
        );
    }
    lock.unlock().unwrap();
    python
}

fn run(command: &mut Command) {
    let out = command
        .output()
        .unwrap_or_else(|e| panic!("running {command:?}: {e}"));
    assert!(
        out.status.success(),
        "{command:?} failed (python3 -m venv needs Debian's python3-venv):\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// What `tests/support/read_rrd.py` reads from `rrd`, as JSON.
pub fn read_rrd(rrd: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/support/read_rrd.py");
    let out = Command::new(python())
        .arg(script)
        .arg(rrd)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "read_rrd.py {} failed:\n{}",
        rrd.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("read_rrd.py prints JSON")
}
