//! The hub: every session the server knows, each owned by one task (module `owner`) that
//! holds its live state, waits for one of a capped number of slots while queued, and runs the
//! session on its own thread. Launch, stop, resume and graceful shutdown go through here; the
//! rest of the server reaches a session through its [`SessionHandle`].
//!
//! - `handle`: the commands an owner takes and the snapshot it publishes.
//! - `owner`: the session's task, its `select!` loop and its status.
//! - `events`: applying the session thread's events (store, browsers).
//! - `answers`: the answer path, deadlines and undo.
//! - `votes`: several named trainers' answers to one query, combined.
//! - `thread`: starting the session thread; `sink`: the channel it reports into.
//! - `remote`: reaching a session's remote env from its thread, and what it resumes from.
//! - `recording`: the session's Rerun recording as its observer.
//! - `episode_frames`: the frames kept for replay.
//! - `leases`: on PostgreSQL, several servers share the sessions: each claims sessions for its
//!   free slots and holds them under a lease it renews (docs/serving-several.md).
//! - `bus`: there, what servers say to each other through the database (LISTEN/NOTIFY);
//!   `relay`: a session another server runs, as this server's sockets and routes reach it.

mod answers;
mod bus;
mod episode_frames;
mod events;
mod handle;
mod leases;
mod owner;
mod recording;
mod relay;
mod remote;
mod sink;
mod thread;
mod votes;

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

use rand::Rng;
use tokio::sync::Semaphore;
use tokio::task::JoinHandle;

pub use answers::UNDO_WINDOW;
pub use bus::ASK_TIMEOUT;
pub use handle::{AnswerReply, Identity, Joined, SessionHandle, Snapshot};
pub use leases::{CLAIM_EVERY, LEASE};
pub use relay::Reach;

use crate::session::{PlanError, SessionPlan, SessionSpec};
use crate::store::{NewSession, SessionRow, Status, Store, StoredSpecError};

/// How the hub runs sessions.
#[derive(Clone, Debug)]
pub struct HubConfig {
    pub data_dir: PathBuf,
    /// Where the synthetic trainers' experts are (`<task>.safetensors`); `None`: the ones the
    /// binary ships.
    pub models_dir: Option<PathBuf>,
    /// Sessions running at once; the rest wait as `queued`.
    pub max_running: usize,
    /// Stream every session's recording to this Rerun viewer too (`--rerun-connect`).
    pub rerun_connect: Option<String>,
    /// Stack size of each session's thread in bytes (`None`: the platform's default). A size
    /// the system cannot give makes the thread fail to start, and the session fails with it.
    pub session_stack_size: Option<usize>,
}

pub struct Hub {
    pub store: Store,
    pub config: HubConfig,
    sessions: Mutex<HashMap<String, SessionHandle>>,
    slots: Arc<Semaphore>,
    tasks: Mutex<Vec<JoinHandle<()>>>,
    /// This process's id among the servers of one PostgreSQL (random, logged at start): the
    /// `owner` of the sessions it runs.
    pub server_id: String,
    /// Wakes the claim loop (a launch or resume on PostgreSQL).
    claim_now: tokio::sync::Notify,
    /// One claim at a time (the loop's, a launch's), so that free slots are counted once.
    claiming: tokio::sync::Mutex<()>,
    /// The way to the other servers of one PostgreSQL (none on SQLite).
    bus: OnceLock<bus::Bus>,
    /// Sessions other servers run that sockets or routes here reached.
    relays: Mutex<HashMap<String, relay::RelayEntry>>,
    /// The bus's listening and sending tasks, which end last.
    bus_tasks: Mutex<Vec<JoinHandle<()>>>,
}

/// Why the hub refused.
#[derive(Debug, thiserror::Error)]
pub enum HubError {
    #[error("no session {0}")]
    NotFound(String),
    #[error("{0}")]
    Conflict(String),
    /// A launch, or a stored session, that cannot become a plan.
    #[error("invalid session: {0}")]
    Invalid(#[from] PlanError),
    /// A stored session whose spec no longer reads.
    #[error("invalid session: {0}")]
    StoredSpec(#[from] StoredSpecError),
    #[error(transparent)]
    Store(#[from] sqlx::Error),
}

/// A random lowercase-hex string of `bytes` bytes.
pub fn random_hex(bytes: usize) -> String {
    let mut rng = rand::rng();
    (0..bytes)
        .map(|_| format!("{:02x}", rng.random::<u8>()))
        .collect()
}

impl Hub {
    pub fn new(store: Store, config: HubConfig) -> Arc<Self> {
        let slots = Arc::new(Semaphore::new(config.max_running.max(1)));
        Arc::new(Self {
            store,
            config,
            sessions: Mutex::new(HashMap::new()),
            slots,
            tasks: Mutex::new(Vec::new()),
            server_id: random_hex(8),
            claim_now: tokio::sync::Notify::new(),
            claiming: tokio::sync::Mutex::new(()),
            bus: OnceLock::new(),
            relays: Mutex::new(HashMap::new()),
            bus_tasks: Mutex::new(Vec::new()),
        })
    }

    /// After a restart: mark what was running as interrupted and start the queue again.
    ///
    /// On PostgreSQL other servers may be running sessions: nothing is marked; this server's
    /// claim loop starts, and takes queued sessions and those whose lease ran out (a server,
    /// perhaps this one before its restart, died while running them) as it has free slots.
    pub async fn recover(self: &Arc<Self>) -> Result<Vec<String>, HubError> {
        if self.store.is_shared() {
            tracing::info!(
                server = %self.server_id,
                "sharing the database with any other servers: claiming sessions under leases of {:?}",
                leases::LEASE
            );
            self.start_bus()
                .await
                .map_err(|e| HubError::Conflict(format!("listening for other servers: {e:#}")))?;
            self.claim_once().await;
            let task = tokio::spawn(self.clone().run_leases());
            self.tasks
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(task);
            return Ok(Vec::new());
        }
        let (interrupted, queued) = self.store.recover_after_restart().await?;
        for id in queued {
            if let Some(row) = self.store.session(&id).await? {
                let plan = plan_of(&row)?;
                self.start(row, plan).await?;
            }
        }
        Ok(interrupted)
    }

    /// Store a new session and queue it. The kernels it computes with are recorded with it
    /// (this server's, unless the launch named them), so that a resume replays it bit for bit.
    pub async fn launch(self: &Arc<Self>, mut spec: SessionSpec) -> Result<SessionRow, HubError> {
        spec.params
            .session
            .kernels
            .get_or_insert_with(crate::rl::kernels::default_path);
        let plan = SessionPlan::new(spec)?;
        let spec = &plan.spec;
        let id = random_hex(6);
        let token = random_hex(16);
        let config = serde_json::to_value(spec).expect("specs serialise");
        let method = spec.method.to_string();
        let trainer = serde_json::to_value(spec.trainer).expect("kinds serialise");
        let row = self
            .store
            .insert_session(NewSession {
                id: &id,
                task: spec.task_name(),
                method: &method,
                trainer: trainer.as_str().unwrap_or("human"),
                seed: spec.seed,
                budget: spec.budget,
                config: &config,
                trainer_token: &token,
            })
            .await?;
        if self.store.is_shared() {
            // Whichever server has a free slot runs it: this one first, if it has one.
            self.claim_once().await;
            self.claim_now.notify_one();
        } else {
            self.start(row.clone(), plan).await?;
        }
        Ok(row)
    }

    /// The session's handle while this server runs it (queued, running or waiting), or the
    /// relay a socket here made to the server that runs it.
    pub fn session(&self, id: &str) -> Option<SessionHandle> {
        self.owned(id).or_else(|| self.relay(id))
    }

    /// The session's handle while this server runs it.
    fn owned(&self, id: &str) -> Option<SessionHandle> {
        self.sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(id)
            .cloned()
    }

    /// Drop an ended session from the map (unless a resume already replaced it).
    fn forget(&self, key: &Arc<str>) {
        let mut map = self.sessions.lock().unwrap_or_else(|e| e.into_inner());
        if map.get(&**key).is_some_and(|h| Arc::ptr_eq(&h.id, key)) {
            map.remove(&**key);
        }
    }

    /// Queue a stored session under a new owner (stored as `queued` before this returns).
    async fn start(self: &Arc<Self>, row: SessionRow, plan: SessionPlan) -> Result<(), HubError> {
        let timeout = Duration::from_secs_f64(plan.settings.answer_timeout_s);
        let (mut owner, handle, commands) = owner::Owner::new(
            self.clone(),
            row.id.clone(),
            plan,
            timeout,
            u64::try_from(row.progress).unwrap_or(0),
        );
        {
            let mut map = self.sessions.lock().unwrap_or_else(|e| e.into_inner());
            if map.get(&row.id).is_some_and(|h| h.status().is_active()) {
                return Err(HubError::Conflict(format!(
                    "session {} is already active",
                    row.id
                )));
            }
            map.insert(row.id.clone(), handle);
        }
        if row.status != Status::Queued {
            owner.set_status(Status::Queued, None).await;
        }
        let task = tokio::spawn(owner.run(commands));
        let mut tasks = self.tasks.lock().unwrap_or_else(|e| e.into_inner());
        tasks.retain(|t| !t.is_finished());
        tasks.push(task);
        Ok(())
    }

    /// Stop a session for good (it can still be resumed later).
    pub async fn stop(self: &Arc<Self>, id: &str) -> Result<(), HubError> {
        let row = self
            .store
            .session(id)
            .await?
            .ok_or_else(|| HubError::NotFound(id.into()))?;
        // Its owner here, or (PostgreSQL) a relay to the server that runs it.
        let handle = match self.reach(&row).await {
            Reach::Live(h) => Some(h).filter(|h| h.status().is_active()),
            Reach::Between | Reach::NotRunning => None,
        };
        match handle {
            Some(h) if h.stop().await => Ok(()),
            // PostgreSQL: queued and claimed by no server yet.
            None if self
                .store
                .stop_unclaimed(id, "stopped while queued")
                .await? =>
            {
                Ok(())
            }
            _ if self.store.is_shared() && row.status.is_active() => {
                Err(HubError::Conflict(format!(
                    "session {id} is moving between servers (its server stopped, and another \
                     has not taken it over yet): try again in a few seconds"
                )))
            }
            _ => Err(HubError::Conflict(format!(
                "session {id} is {}, not running",
                self.status_of(&row).as_str()
            ))),
        }
    }

    /// Continue an interrupted, stopped or failed session: it replays its stored answers (never
    /// asking them again) and goes on.
    pub async fn resume(self: &Arc<Self>, id: &str) -> Result<SessionRow, HubError> {
        let row = self
            .store
            .session(id)
            .await?
            .ok_or_else(|| HubError::NotFound(id.into()))?;
        let status = self.status_of(&row);
        if !status.is_resumable() {
            return Err(HubError::Conflict(format!(
                "session {id} is {}: only interrupted, stopped or failed sessions resume",
                status.as_str()
            )));
        }
        let plan = plan_of(&row)?;
        if self.store.is_shared() {
            if !self.store.requeue(id).await? {
                return Err(HubError::Conflict(format!(
                    "session {id} is no longer resumable"
                )));
            }
            self.claim_once().await;
            self.claim_now.notify_one();
        } else {
            self.start(row, plan).await?;
        }
        let row = self
            .store
            .session(id)
            .await?
            .ok_or_else(|| HubError::NotFound(id.into()))?;
        Ok(row)
    }

    /// The status a client should see: the live one while the hub runs the session.
    pub fn status_of(&self, row: &SessionRow) -> Status {
        self.session(&row.id).map_or(row.status, |h| h.status())
    }

    /// Graceful shutdown: every running session checkpoints and ends as `interrupted`; browsers
    /// get `ended`. Queued sessions stay queued for the next start.
    ///
    /// On PostgreSQL the server hands its sessions over instead: each copy ends as when its
    /// lease is lost (writing nothing more; its sockets close and connect again), then the
    /// leases are released, so that another server claims them within a second and resumes
    /// them from what is stored, as after a kill but without waiting for the leases to run out.
    pub async fn shutdown(&self, grace: Duration) {
        let shared = self.store.is_shared();
        self.slots.close();
        let sessions: Vec<SessionHandle> = self
            .sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .values()
            .cloned()
            .collect();
        for session in &sessions {
            if shared {
                session.lost();
            } else {
                session.shutdown();
            }
        }
        self.relays_moved(None);
        let tasks: Vec<JoinHandle<()>> =
            std::mem::take(&mut *self.tasks.lock().unwrap_or_else(|e| e.into_inner()));
        let all = futures_util::future::join_all(tasks);
        if tokio::time::timeout(grace, all).await.is_err() {
            tracing::warn!(
                "sessions did not finish within {grace:?}; they will be marked interrupted at the next start"
            );
        }
        if shared {
            match self.store.release_leases(&self.server_id).await {
                Ok(n) => tracing::info!("handed {n} session(s) over to the other servers"),
                Err(e) => tracing::warn!(
                    "releasing the leases: {e} (other servers take the sessions over when the leases run out)"
                ),
            }
        }
        // The last words to other servers (relays' leaves) go out; then the bus stops.
        tokio::time::sleep(Duration::from_millis(200)).await;
        for task in std::mem::take(&mut *self.bus_tasks.lock().unwrap_or_else(|e| e.into_inner())) {
            task.abort();
        }
    }

    /// `<data dir>/recordings/<id>.rrd`.
    pub fn recording_path(&self, id: &str) -> PathBuf {
        self.config
            .data_dir
            .join("recordings")
            .join(format!("{id}.rrd"))
    }

    /// Where the frames of a human session's episode are kept: `<data dir>/frames/<id>/<n>.json`.
    pub fn frames_path(&self, id: &str, episode: u64) -> PathBuf {
        self.config
            .data_dir
            .join("frames")
            .join(id)
            .join(format!("{episode}.json"))
    }

    /// What a session on a remote env resumes from: `<data dir>/checkpoints/<id>.resume` (its
    /// latest run checkpoint, or its recorded trajectories).
    pub fn resume_path(&self, id: &str) -> PathBuf {
        self.config
            .data_dir
            .join("checkpoints")
            .join(format!("{id}.resume"))
    }

    /// Write a learner checkpoint to `<data dir>/checkpoints/<id>.<extension>` (atomically)
    /// and return its path relative to the data dir.
    async fn write_checkpoint(
        &self,
        id: &str,
        extension: &str,
        bytes: Vec<u8>,
    ) -> std::io::Result<String> {
        let dir = self.config.data_dir.join("checkpoints");
        let relative = format!("checkpoints/{id}.{extension}");
        let path = self.config.data_dir.join(&relative);
        let tmp = path.with_extension(format!("{extension}.tmp"));
        tokio::task::spawn_blocking(move || {
            std::fs::create_dir_all(&dir)?;
            std::fs::write(&tmp, bytes)?;
            std::fs::rename(&tmp, &path)
        })
        .await
        .map_err(std::io::Error::other)??;
        Ok(relative)
    }
}

/// A stored session's plan, read and checked once more as it starts again (a resume, or a
/// queued session after a restart).
fn plan_of(row: &SessionRow) -> Result<SessionPlan, HubError> {
    Ok(SessionPlan::new(row.spec()?)?)
}

#[cfg(test)]
mod tests;
