//! `dualrep serve`: the main job. Opens (creating on first start) the database in the data dir,
//! marks sessions cut off by a crash as interrupted, serves the UI, API and websockets, and on
//! SIGINT/SIGTERM drains: sessions checkpoint, browsers get `ended`, then the process exits.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context;
use axum::http::HeaderValue;
use clap::Args;

use crate::hub::random_hex;
use crate::server::{Server, ServerConfig};

#[derive(Debug, Args)]
pub struct ServeArgs {
    /// Address to listen on (port 0 picks a free one; the line "listening on" says which).
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: SocketAddr,
    /// Where the database (unless --database), checkpoints, recordings and the generated token
    /// live.
    #[arg(long, default_value = "./data")]
    pub data_dir: PathBuf,
    /// The database: sqlite://PATH, or postgres://USER:PASSWORD@HOST:PORT/DATABASE (an existing
    /// database; the schema is created at first start) [default: the SQLite file dualrep.db in
    /// the data dir]. Checkpoints and recordings stay in the data dir either way.
    #[arg(
        long,
        env = "DUALREP_DATABASE",
        hide_env_values = true,
        value_name = "URL"
    )]
    pub database: Option<String>,
    /// The researcher token [default: DUALREP_TOKEN, else `<data-dir>/token`, generated at first start].
    #[arg(long, env = "DUALREP_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Sessions that run at once; the rest queue [default: the number of cores].
    #[arg(long)]
    pub max_sessions: Option<usize>,
    /// Serve the web UI from this folder instead of the copy inside the binary (development).
    #[arg(long)]
    pub web_dir: Option<PathBuf>,
    /// Load the synthetic trainers' experts (`<task>.safetensors`) from this folder instead of
    /// the ones inside the binary.
    #[arg(long)]
    pub models_dir: Option<PathBuf>,
    /// Origins allowed to call the API cross-site (repeatable); none by default.
    #[arg(long = "cors-origin")]
    pub cors_origins: Vec<String>,
    /// Stream every session's recording to a running Rerun viewer too (e.g.
    /// rerun+http://127.0.0.1:9876/proxy); a session's `rerun_connect` param overrides it.
    #[arg(long)]
    pub rerun_connect: Option<String>,
    /// Seconds sessions get to checkpoint at shutdown.
    #[arg(long, default_value_t = 30.0)]
    pub shutdown_grace_s: f64,
}

/// The token from the flag or environment, else the one stored in the data dir, else a new one
/// (stored with owner-only permissions and printed once).
fn researcher_token(given: Option<String>, data_dir: &Path) -> anyhow::Result<String> {
    if let Some(t) = given.filter(|t| !t.trim().is_empty()) {
        return Ok(t.trim().to_string());
    }
    let path = data_dir.join("token");
    if let Ok(t) = std::fs::read_to_string(&path) {
        let t = t.trim();
        anyhow::ensure!(
            !t.is_empty(),
            "{} is empty: delete it to have a new token generated",
            path.display()
        );
        return Ok(t.to_string());
    }
    let token = random_hex(24);
    write_private(&path, &token)
        .with_context(|| format!("storing the token in {}", path.display()))?;
    println!("researcher token (stored in {}): {token}", path.display());
    Ok(token)
}

fn write_private(path: &Path, content: &str) -> std::io::Result<()> {
    use std::io::Write;
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::mode(&mut options, 0o600);
    options.open(path)?.write_all(content.as_bytes())
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = term => {},
    }
}

pub fn run(args: ServeArgs) -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "dualrep=info,tower_http=warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?
        .block_on(serve(args))
}

/// A server started in this process: where it listens, its researcher token, and the task that
/// serves until a signal (or `shutdown`) drains it.
pub struct Running {
    pub addr: SocketAddr,
    pub token: String,
    pub max_running: usize,
    stop: tokio::sync::oneshot::Sender<()>,
    task: tokio::task::JoinHandle<std::io::Result<()>>,
}

impl Running {
    /// Serve until SIGINT/SIGTERM has drained the sessions.
    pub async fn wait(self) -> anyhow::Result<()> {
        let _keep_open = self.stop;
        Ok(self.task.await??)
    }

    /// Drain now, as a signal would.
    pub async fn shutdown(self) -> anyhow::Result<()> {
        let _ = self.stop.send(());
        Ok(self.task.await??)
    }
}

async fn serve(args: ServeArgs) -> anyhow::Result<()> {
    let data_dir = args.data_dir.clone();
    let database = match &args.database {
        Some(url) => format!(", database {}", crate::store::redacted(url)),
        None => String::new(),
    };
    let running = start(args).await?;
    // Tests and scripts read this line to find the port.
    println!(
        "dualrep listening on http://{} (data in {}{database}, {} session(s) at once)",
        running.addr,
        data_dir.display(),
        running.max_running
    );
    let threads = crate::rl::kernels::max_threads();
    println!(
        "sessions compute with the {} kernels, on {threads} thread(s) while one runs alone, the \
         {} core(s) shared out while several run",
        crate::rl::kernels::default_path(),
        crate::rl::kernels::cores()
    );
    running.wait().await
}

/// Open the server, bind and serve in the background.
pub async fn start(args: ServeArgs) -> anyhow::Result<Running> {
    std::fs::create_dir_all(&args.data_dir)
        .with_context(|| format!("creating the data dir {}", args.data_dir.display()))?;
    let token = researcher_token(args.token, &args.data_dir)?;
    let cors_origins = args
        .cors_origins
        .iter()
        .map(|o| {
            HeaderValue::from_str(o)
                .with_context(|| format!("--cors-origin {o:?} is not a valid origin"))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let max_running = args
        .max_sessions
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let server = Server::open(ServerConfig {
        data_dir: args.data_dir.clone(),
        database: args.database.clone(),
        token: token.clone(),
        web_dir: args.web_dir.clone(),
        models_dir: args.models_dir.clone(),
        max_running,
        rerun_connect: args.rerun_connect.clone(),
        cors_origins,
        shutdown_grace: Duration::from_secs_f64(args.shutdown_grace_s),
    })
    .await?;
    if !server.interrupted.is_empty() {
        tracing::warn!(
            "{} session(s) were cut off when the server last stopped and can be resumed: {}",
            server.interrupted.len(),
            server.interrupted.join(", ")
        );
    }
    let listener = tokio::net::TcpListener::bind(args.addr)
        .await
        .with_context(|| format!("listening on {}", args.addr))?;
    let addr = listener.local_addr()?;
    let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
    let shutdown = async move {
        tokio::select! {
            () = shutdown_signal() => {},
            _ = stopped => {},
        }
    };
    let task = tokio::spawn(server.run(listener, shutdown));
    Ok(Running {
        addr,
        token,
        max_running,
        stop,
        task,
    })
}
