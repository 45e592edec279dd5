//! Debian's nginx as a round-robin proxy in front of several `dualrep serve` processes, for
//! tests: installed with apt-get where missing (as root), run in the foreground as a child of
//! the test on a free port of 127.0.0.1, its config, logs, pid and temporary files in a private
//! temporary directory, stopped when dropped. The config is the one the Compose profile's
//! proxy uses (`deploy/nginx.conf`), with the servers' addresses for its upstream.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub struct Proxy {
    child: Child,
    dir: tempfile::TempDir,
    pub addr: SocketAddr,
}

/// Where Debian puts nginx.
fn binary() -> Option<PathBuf> {
    ["/usr/sbin/nginx", "/usr/bin/nginx"]
        .into_iter()
        .map(PathBuf::from)
        .find(|p| p.is_file())
}

/// `deploy/nginx.conf` with `upstreams` in place of the Compose servers, listening on `port`,
/// and its files in `dir`.
fn config(upstreams: &[SocketAddr], port: u16, dir: &Path) -> String {
    let template =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("deploy/nginx.conf"))
            .expect("reading deploy/nginx.conf");
    let servers: String = upstreams
        .iter()
        .map(|a| format!("        server {a} max_fails=1 fail_timeout=2s;\n"))
        .collect();
    let begin = template
        .find("    upstream dualrep {")
        .expect("deploy/nginx.conf has `upstream dualrep`");
    let end = begin
        + template[begin..]
            .find('}')
            .expect("the upstream block ends");
    let d = dir.display();
    // Root runs the workers as `nobody`: they reach their temporary files through `dir`.
    let user = if super::debian::is_root() {
        "user nobody nogroup;\n"
    } else {
        ""
    };
    format!(
        "{user}pid {d}/nginx.pid;\nerror_log {d}/error.log warn;\n{}    upstream dualrep {{\n{servers}    ",
        &template[..begin]
    ) + &template[end..]
        .replace("listen 8080;", &format!("listen 127.0.0.1:{port};"))
        .replace(
            "    access_log off;",
            &format!(
                "    access_log off;\n    client_body_temp_path {d}/body;\n    proxy_temp_path \
                 {d}/proxy;\n    fastcgi_temp_path {d}/fastcgi;\n    uwsgi_temp_path {d}/uwsgi;\n    \
                 scgi_temp_path {d}/scgi;"
            ),
        )
}

impl Proxy {
    /// nginx in front of `upstreams`, round robin; returns once it accepts connections.
    pub fn start(upstreams: &[SocketAddr]) -> Self {
        let bin = binary().unwrap_or_else(|| {
            super::debian::install("nginx", "");
            binary().expect("nginx installed, yet no /usr/sbin/nginx")
        });
        let dir = tempfile::tempdir().unwrap();
        // The workers (`nobody` under root) read and write under it.
        std::fs::set_permissions(
            dir.path(),
            std::os::unix::fs::PermissionsExt::from_mode(0o755),
        )
        .unwrap();
        let port = super::postgres::free_port();
        let conf = dir.path().join("nginx.conf");
        std::fs::write(&conf, config(upstreams, port, dir.path())).unwrap();
        let child = Command::new(&bin)
            .args(["-e", "stderr", "-p"])
            .arg(dir.path())
            .arg("-c")
            .arg(&conf)
            .args(["-g", "daemon off;"])
            .stdout(Stdio::null())
            .spawn()
            .expect("starting nginx");
        let addr: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
        let start = Instant::now();
        while std::net::TcpStream::connect(addr).is_err() {
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "nginx did not listen on {addr}: {}",
                std::fs::read_to_string(dir.path().join("error.log")).unwrap_or_default()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
        Self { child, dir, addr }
    }

    /// nginx's error log so far.
    pub fn log(&self) -> String {
        std::fs::read_to_string(self.dir.path().join("error.log")).unwrap_or_default()
    }
}

impl Drop for Proxy {
    fn drop(&mut self) {
        // SIGQUIT: a graceful stop; then make sure.
        let _ = Command::new("kill")
            .args(["-QUIT", &self.child.id().to_string()])
            .status();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(5) {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
