//! Python's `pyarrow`, in a virtual environment the tests create on first use, for reading the
//! Parquet exports back as another tool would. The venv lives at `$DUALREP_PYARROW_VENV`,
//! default `~/.cache/dualrep/venv-pyarrow`, and is reused across runs; pyarrow is installed only
//! when the venv cannot import it. A lock file beside it serialises installs between test
//! processes.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use super::py_venv::{Venv, pip_install, runs};

/// The venv's Python interpreter, with `pyarrow` importable.
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = Venv {
            var: "DUALREP_PYARROW_VENV",
            name: "venv-pyarrow",
        };
        venv.ensure(
            "pyarrow",
            |python| runs(python, "import pyarrow.parquet"),
            |python| pip_install(python, &["pyarrow"]),
        )
    })
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
