//! The service as a library call: [`Server::open`] opens (creating on first start) the database,
//! marks sessions cut off by a crash as interrupted and queues the rest again; [`Server::run`]
//! serves the UI, API and websockets on a listener until `shutdown` resolves, then drains:
//! sessions checkpoint and end as interrupted, browsers get `ended`, open connections finish.
//! `dualrep serve` is this plus flags, a token file and signals; tests and embedders call it
//! directly.

use std::future::Future;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use axum::http::HeaderValue;
use tokio::net::TcpListener;

use crate::api::AppState;
use crate::http::app;
use crate::hub::{Hub, HubConfig};
use crate::store::Store;

/// Everything a server needs to know.
#[derive(Clone, Debug)]
pub struct ServerConfig {
    /// Where checkpoints, recordings and frames live, and the default database.
    pub data_dir: PathBuf,
    /// The database's URL (`sqlite://PATH` or `postgres://...`); `None`: the SQLite file in the
    /// data dir.
    pub database: Option<String>,
    /// The researcher token.
    pub token: String,
    /// Serve the web UI from this folder; `None`: the copy inside the binary.
    pub web_dir: Option<PathBuf>,
    /// The synthetic trainers' experts; `None`: the ones inside the binary.
    pub models_dir: Option<PathBuf>,
    /// Sessions that run at once; the rest queue.
    pub max_running: usize,
    /// Stream every session's recording to this Rerun viewer too.
    pub rerun_connect: Option<String>,
    /// Origins allowed to call the API cross-site.
    pub cors_origins: Vec<HeaderValue>,
    /// How long sessions get to checkpoint at shutdown.
    pub shutdown_grace: Duration,
}

/// An opened server, ready to serve.
pub struct Server {
    state: AppState,
    grace: Duration,
    /// Sessions that were cut off when the server last stopped (resumable).
    pub interrupted: Vec<String>,
}

impl Server {
    pub async fn open(config: ServerConfig) -> anyhow::Result<Self> {
        std::fs::create_dir_all(&config.data_dir)
            .with_context(|| format!("creating the data dir {}", config.data_dir.display()))?;
        if let Some(web) = config
            .web_dir
            .as_ref()
            .filter(|w| !w.join("index.html").exists())
        {
            anyhow::bail!(
                "--web-dir {} has no index.html (leave --web-dir out to serve the UI inside the binary)",
                web.display()
            );
        }
        let store = match &config.database {
            None => Store::open(&config.data_dir).await.with_context(|| {
                format!("opening the database in {}", config.data_dir.display())
            })?,
            // The error names the database (without its password) and what went wrong.
            Some(url) => Store::connect(url).await?,
        };
        let hub = Hub::new(
            store.clone(),
            HubConfig {
                data_dir: config.data_dir.clone(),
                models_dir: config.models_dir.clone(),
                max_running: config.max_running,
                rerun_connect: config.rerun_connect.clone(),
                session_stack_size: None,
            },
        );
        let interrupted = hub.recover().await?;
        Ok(Self {
            state: AppState {
                store,
                hub,
                token: Arc::from(config.token.as_str()),
                web_dir: config.web_dir,
                data_dir: config.data_dir,
                cors_origins: config.cors_origins,
                study_launches: Default::default(),
            },
            grace: config.shutdown_grace,
            interrupted,
        })
    }

    pub fn state(&self) -> &AppState {
        &self.state
    }

    /// Serve on `listener` until `shutdown` resolves; then drain the sessions first (their
    /// browsers get `ended` and close) and finish the connections still open.
    pub async fn run(
        self,
        listener: TcpListener,
        shutdown: impl Future<Output = ()> + Send + 'static,
    ) -> std::io::Result<()> {
        let hub = self.state.hub.clone();
        let grace = self.grace;
        let drain = async move {
            shutdown.await;
            tracing::info!(
                "shutting down: sessions checkpoint and end as interrupted (on PostgreSQL: go to \
                 the other servers)"
            );
            hub.shutdown(grace).await;
        };
        // Answers and acks are small messages: without TCP_NODELAY, Nagle's algorithm and the
        // peer's delayed ACK hold some of them back ~40 ms.
        let listener = axum::serve::ListenerExt::tap_io(listener, |tcp| {
            if let Err(e) = tcp.set_nodelay(true) {
                tracing::warn!("TCP_NODELAY: {e}");
            }
        });
        axum::serve(listener, app(self.state))
            .with_graceful_shutdown(drain)
            .await
    }
}

/// Open a server with `config` and serve on `listener` until `shutdown` resolves.
pub async fn run(
    listener: TcpListener,
    config: ServerConfig,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> anyhow::Result<()> {
    Server::open(config).await?.run(listener, shutdown).await?;
    Ok(())
}
