//! Running the `dualrep` binary from integration tests.

use std::path::Path;
use std::process::{Command, Output};

/// Run `dualrep args...`, in `dir` when given.
pub fn dualrep_in(args: &[&str], dir: Option<&Path>) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_dualrep"));
    command.args(args);
    if let Some(dir) = dir {
        command.current_dir(dir);
    }
    command.output().expect("binary runs")
}

/// The one-line JSON summary a successful command prints last.
pub fn ok(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.lines().last().expect("a summary line")).unwrap()
}

/// The stderr of a command that had to fail, asserting that it did.
pub fn refused(out: &Output) -> String {
    assert!(
        !out.status.success(),
        "succeeded where it should fail; stdout: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `dualrep args` started in `d`, returned running once `file` (under `d`) exists.
pub fn running_once<S: AsRef<std::ffi::OsStr>>(
    args: &[S],
    d: &Path,
    file: &str,
) -> std::process::Child {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_dualrep"))
        .args(args)
        .current_dir(d)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while !d.join(file).exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before {file} was written"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child
}
