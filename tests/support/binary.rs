//! The real `dualrep serve` binary on a free port, for tests that kill it or drive it from a
//! browser.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// Start `dualrep serve --addr 127.0.0.1:0 --token <token> --data-dir <data> <extra...>` from the
/// crate root; returns the child and the URL its "listening on" line names. Its output keeps
/// being drained (echoed as `[serve] ...`) so the child never blocks on a full pipe.
pub fn start_serve(data: &Path, token: &str, extra: &[&str], stderr: Stdio) -> (Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_dualrep"))
        .args(["serve", "--addr", "127.0.0.1:0", "--token", token])
        .args(extra)
        .arg("--data-dir")
        .arg(data)
        // Not the repository: the binary serves the UI and experts it carries, from anywhere.
        .current_dir(data)
        .stdout(Stdio::piped())
        .stderr(stderr)
        .spawn()
        .expect("starting dualrep serve");
    let stdout = child.stdout.take().expect("piped stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut sent = false;
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if !sent && let Some(rest) = line.split("listening on ").nth(1) {
                let url = rest
                    .split_whitespace()
                    .next()
                    .unwrap_or_default()
                    .to_string();
                let _ = tx.send(url);
                sent = true;
            }
            println!("[serve] {line}");
        }
    });
    let url = rx
        .recv_timeout(Duration::from_secs(60))
        .unwrap_or_else(|_| {
            let _ = child.kill();
            panic!("dualrep serve did not print \"listening on http://ADDR\" within 60 s")
        });
    assert!(
        url.starts_with("http://"),
        "unexpected listening line: {url}"
    );
    (child, url)
}
