//! A server for tests: the router over a fresh data dir (for `oneshot`), or the whole server
//! started in-process on port 0 (for websocket clients).

use std::sync::Arc;

use dualrep::api::AppState;
use dualrep::cli::serve::{Running, ServeArgs, start};
use dualrep::hub::{Hub, HubConfig};
use dualrep::store::Store;
use serde_json::Value;

pub const TOKEN: &str = "researcher-test-token";

/// Where the tests run from: the crate root, whose `web/` and `models/` the server uses.
pub fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub async fn state(dir: &std::path::Path) -> AppState {
    state_with(dir, |_| {}).await
}

/// As [`state`], with the hub's configuration changed by `tweak`.
pub async fn state_with(dir: &std::path::Path, tweak: impl FnOnce(&mut HubConfig)) -> AppState {
    let store = Store::open(dir).await.unwrap();
    let mut config = HubConfig {
        data_dir: dir.to_path_buf(),
        models_dir: Some(root().join("models")),
        max_running: 4,
        rerun_connect: None,
        session_stack_size: None,
    };
    tweak(&mut config);
    let hub = Hub::new(store.clone(), config);
    AppState {
        store,
        hub,
        token: Arc::from(TOKEN),
        web_dir: Some(root().join("web")),
        data_dir: dir.to_path_buf(),
        cors_origins: vec![],
        study_launches: Default::default(),
    }
}

pub async fn serve(dir: &std::path::Path) -> Running {
    serve_on(dir, None).await
}

/// As [`serve`], on the database at `database` (a URL) instead of the data dir's.
pub async fn serve_on(dir: &std::path::Path, database: Option<&str>) -> Running {
    start(ServeArgs {
        addr: "127.0.0.1:0".parse().unwrap(),
        data_dir: dir.to_path_buf(),
        database: database.map(str::to_owned),
        token: Some(TOKEN.into()),
        max_sessions: Some(4),
        web_dir: Some(root().join("web")),
        models_dir: Some(root().join("models")),
        cors_origins: vec![],
        shutdown_grace_s: 30.0,
        rerun_connect: None,
    })
    .await
    .unwrap()
}

/// A REST client with the researcher token.
pub struct Api {
    pub base: String,
    pub http: reqwest::Client,
}

impl Api {
    pub fn new(addr: std::net::SocketAddr) -> Self {
        Self {
            base: format!("http://{addr}"),
            http: reqwest::Client::new(),
        }
    }

    pub async fn get(&self, path: &str) -> Value {
        let r = self
            .http
            .get(format!("{}{path}", self.base))
            .bearer_auth(TOKEN)
            .send()
            .await
            .unwrap();
        assert!(r.status().is_success(), "GET {path}: {}", r.status());
        r.json().await.unwrap()
    }

    pub async fn post(&self, path: &str, body: Value) -> (u16, Value) {
        let r = self
            .http
            .post(format!("{}{path}", self.base))
            .bearer_auth(TOKEN)
            .json(&body)
            .send()
            .await
            .unwrap();
        let status = r.status().as_u16();
        (status, r.json().await.unwrap_or(Value::Null))
    }
}
