//! The Python `rerun-sdk` of the same version as the `rerun` crate, in a virtual environment the
//! tests create on first use, for reading `.rrd` files back (system.md: both SDKs must read
//! them).
//!
//! The venv lives at `$DUALREP_PY_VENV`, default `~/.cache/dualrep/venv-rerun`, and is reused
//! across runs and clones. A lock file next to it serialises installs between concurrent test
//! processes; a venv whose install was interrupted is repaired on the next run.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use super::py_venv::{Venv, pip_install, runs};

/// Must equal the `rerun` crate's version in Cargo.toml.
pub const RERUN_VERSION: &str = "0.36.3";

/// The venv's Python interpreter, with `rerun-sdk==RERUN_VERSION` importable.
pub fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        let venv = Venv {
            var: "DUALREP_PY_VENV",
            name: "venv-rerun",
        };
        // Exactly our version: another one may not read our files.
        let check = format!("import sys, rerun; sys.exit(rerun.__version__ != '{RERUN_VERSION}')");
        venv.ensure(
            &format!("rerun-sdk=={RERUN_VERSION}"),
            |python| runs(python, &check),
            |python| pip_install(python, &[&format!("rerun-sdk=={RERUN_VERSION}")]),
        )
    })
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
