//! Python's `pyarrow`, in a virtual environment the tests create on first use, for reading the
//! Parquet exports back as another tool would. The venv lives at `$DUALREP_PYARROW_VENV`,
//! default `~/.cache/dualrep/venv-pyarrow`, and is reused across runs; pyarrow is installed only
//! when the venv cannot import it. A lock file beside it serialises installs between test
//! processes.

use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The venv's Python interpreter, with `pyarrow` importable.
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(install)
}

fn venv_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("DUALREP_PYARROW_VENV") {
        return PathBuf::from(dir);
    }
    let home = std::env::var_os("HOME").expect("HOME is set (or set DUALREP_PYARROW_VENV)");
    PathBuf::from(home).join(".cache/dualrep/venv-pyarrow")
}

fn has_pyarrow(python: &Path) -> bool {
    python.exists()
        && Command::new(python)
            .args(["-c", "import pyarrow.parquet"])
            .output()
            .is_ok_and(|o| o.status.success())
}

fn install() -> PathBuf {
    let venv = venv_dir();
    let python = venv.join("bin/python");
    if has_pyarrow(&python) {
        return python;
    }
    fs::create_dir_all(venv.parent().expect("the venv path has a parent")).unwrap();
    let lock = File::create(venv.with_extension("lock")).unwrap();
    lock.lock().unwrap();
    if !has_pyarrow(&python) {
        if !python.exists() {
            run(Command::new("python3")
                .args(["-m", "venv", "--clear"])
                .arg(&venv));
        }
        eprintln!("installing pyarrow into {}", venv.display());
        run(Command::new(&python).args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "pyarrow",
        ]));
        assert!(
            has_pyarrow(&python),
            "pyarrow is not importable after installing it"
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

/// What `tests/support/read_parquet.py` reads from `file`: rows, columns and a few values.
pub fn read_parquet(file: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/support/read_parquet.py");
    let out = Command::new(python())
        .arg(script)
        .arg(file)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "read_parquet.py {} failed:\n{}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("read_parquet.py prints JSON")
}
