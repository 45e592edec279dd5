//! What the REST routes (`http`) and the trainer websocket (`ws`) share: the state every handler
//! reaches, who may call what (`auth`) and every way a request is refused (`error`). It sits
//! below both, so that `http` can mount `ws` while `ws` uses these without reaching back up.

pub mod auth;
pub mod error;

use std::path::PathBuf;
use std::sync::Arc;

use axum::http::HeaderValue;

use crate::hub::Hub;
use crate::store::Store;

/// What every handler can reach.
#[derive(Clone)]
pub struct AppState {
    pub store: Store,
    pub hub: Arc<Hub>,
    /// The researcher token.
    pub token: Arc<str>,
    /// Serve the web UI from this folder; `None` serves the copy inside the binary.
    pub web_dir: Option<PathBuf>,
    pub data_dir: PathBuf,
    /// Origins allowed to call the API from other sites (none by default).
    pub cors_origins: Vec<HeaderValue>,
    /// Held while a study participant's session is launched and linked, so that two clicks
    /// on "start" cannot launch a condition twice.
    pub study_launches: Arc<tokio::sync::Mutex<()>>,
}
