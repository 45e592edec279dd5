//! Python virtual environments the tests create on first use, outside the repository, and reuse
//! across runs and clones: one place that finds the folder, creates the venv, serialises
//! installs between concurrent test processes with a lock file beside it, and repairs a venv
//! whose install was interrupted (it is not ready, so the next run installs again).

use std::fs::{self, File};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A venv at `$<var>`, default `~/.cache/dualrep/<name>`.
pub struct Venv {
    pub var: &'static str,
    pub name: &'static str,
}

impl Venv {
    pub fn dir(&self) -> PathBuf {
        if let Some(dir) = std::env::var_os(self.var) {
            return PathBuf::from(dir);
        }
        let home =
            std::env::var_os("HOME").unwrap_or_else(|| panic!("HOME is set (or set {})", self.var));
        PathBuf::from(home).join(".cache/dualrep").join(self.name)
    }

    /// The venv's interpreter once `ready` holds for it: if it does not, `install` runs (after
    /// the venv is created where missing) under the lock, and `ready` must hold after it.
    pub fn ensure(
        &self,
        what: &str,
        ready: impl Fn(&Path) -> bool,
        install: impl FnOnce(&Path),
    ) -> PathBuf {
        let venv = self.dir();
        let python = venv.join("bin/python");
        if ready(&python) {
            return python;
        }
        fs::create_dir_all(venv.parent().expect("the venv path has a parent")).unwrap();
        let lock = File::create(venv.with_extension("lock")).unwrap();
        // Another test process may be installing: wait for it, then look again.
        lock.lock().unwrap();
        if !ready(&python) {
            if !python.exists() {
                run(Command::new("python3")
                    .args(["-m", "venv", "--clear"])
                    .arg(&venv));
            }
            eprintln!("installing {what} into {}", venv.display());
            install(&python);
            assert!(
                ready(&python),
                "{what} is not importable after installing it"
            );
        }
        lock.unlock().unwrap();
        python
    }
}

/// Whether `python` exists and runs `code` successfully (an import check).
pub fn runs(python: &Path, code: &str) -> bool {
    python.exists()
        && Command::new(python)
            .args(["-c", code])
            .output()
            .is_ok_and(|o| o.status.success())
}

/// `python -m pip install --quiet <args>`.
pub fn pip_install(python: &Path, args: &[&str]) {
    run(Command::new(python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .args(args));
}

/// Run `command`, panicking with its output if it fails.
pub fn run(command: &mut Command) {
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
