//! The hub: every session the server knows, started on their own threads under a cap on how
//! many run at once (the rest queue), each paired with an async consumer of its events.
//! Stop, resume and graceful shutdown go through here.
//!
//! - `live`: one session's live state and the answer path.
//! - `consumer`: applies a session's events to the store and the browsers.
//! - `sink`: the channel a session thread reports into.
//! - `recording`: the session's Rerun recording as its observer.
//! - `undo`: taking back an answer and answering the query again.

mod consumer;
pub mod live;
mod recording;
mod sink;
pub mod undo;

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use rand::Rng;
use tokio::sync::Semaphore;
use tokio::task::JoinHandle;

pub use live::{AnswerReply, Live};

use crate::session::{Controls, SessionContext, SessionSpec, run_session};
use crate::store::{NewSession, SessionRow, Status, Store};

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
    live: Mutex<HashMap<String, Arc<Live>>>,
    slots: Arc<Semaphore>,
    tasks: Mutex<Vec<JoinHandle<()>>>,
}

/// Why the hub refused.
#[derive(Debug, thiserror::Error)]
pub enum HubError {
    #[error("no session {0}")]
    NotFound(String),
    #[error("{0}")]
    Conflict(String),
    #[error("invalid session: {0}")]
    Invalid(String),
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
            live: Mutex::new(HashMap::new()),
            slots,
            tasks: Mutex::new(Vec::new()),
        })
    }

    /// After a restart: mark what was running as interrupted and start the queue again.
    pub async fn recover(self: &Arc<Self>) -> Result<Vec<String>, HubError> {
        let (interrupted, queued) = self.store.recover_after_restart().await?;
        for id in queued {
            if let Some(row) = self.store.session(&id).await? {
                self.start(row)?;
            }
        }
        Ok(interrupted)
    }

    /// Store a new session and queue it.
    pub async fn launch(self: &Arc<Self>, spec: SessionSpec) -> Result<SessionRow, HubError> {
        spec.validate().map_err(HubError::Invalid)?;
        let id = random_hex(6);
        let token = random_hex(16);
        let config = serde_json::to_value(&spec).expect("specs serialise");
        let method = spec.method.to_string();
        let trainer = serde_json::to_value(spec.trainer).expect("kinds serialise");
        let row = self
            .store
            .insert_session(NewSession {
                id: &id,
                task: spec.task.id(),
                method: &method,
                trainer: trainer.as_str().unwrap_or("human"),
                seed: spec.seed,
                budget: spec.budget,
                config: &config,
                trainer_token: &token,
            })
            .await?;
        self.start(row.clone())?;
        Ok(row)
    }

    pub fn live(&self, id: &str) -> Option<Arc<Live>> {
        self.live
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(id)
            .cloned()
    }

    /// Drop an ended session from the map (unless a resume already replaced it).
    /// A session that could not start: `failed` with `reason`, in the database and in memory,
    /// and no longer live, so that it can be resumed.
    async fn fail_to_start(&self, live: &Arc<Live>, reason: &str) {
        tracing::error!(session = %live.id, "{reason}");
        let _ = self
            .store
            .set_status(&live.id, Status::Failed, Some(reason))
            .await;
        live.lock().status = Status::Failed;
        self.forget(live);
    }

    fn forget(&self, live: &Arc<Live>) {
        let mut map = self.live.lock().unwrap_or_else(|e| e.into_inner());
        if map.get(&live.id).is_some_and(|l| Arc::ptr_eq(l, live)) {
            map.remove(&live.id);
        }
    }

    /// Queue a stored session: wait for a slot, then run it on its own thread.
    fn start(self: &Arc<Self>, row: SessionRow) -> Result<(), HubError> {
        let spec = row.spec().map_err(HubError::Invalid)?;
        let timeout = spec.settings().map_err(HubError::Invalid)?.answer_timeout_s;
        let live = Arc::new(Live::new(
            row.id.clone(),
            spec,
            row.trainer_token.clone(),
            Duration::from_secs_f64(timeout),
        ));
        {
            let mut map = self.live.lock().unwrap_or_else(|e| e.into_inner());
            if map
                .get(&row.id)
                .is_some_and(|l| l.lock().status.is_active())
            {
                return Err(HubError::Conflict(format!(
                    "session {} is already {}",
                    row.id, "active"
                )));
            }
            map.insert(row.id.clone(), live.clone());
        }
        let hub = self.clone();
        let task = tokio::spawn(async move { hub.run(live).await });
        let mut tasks = self.tasks.lock().unwrap_or_else(|e| e.into_inner());
        tasks.retain(|t| !t.is_finished());
        tasks.push(task);
        Ok(())
    }

    async fn run(self: Arc<Self>, live: Arc<Live>) {
        let Ok(_slot) = self.slots.clone().acquire_owned().await else {
            return; // the hub is shutting down
        };
        if live.lock().stop_requested {
            self.forget(&live); // stopped while queued; `stop` stored the status
            return;
        }
        let id = live.id.clone();
        let (stored_answers, stored_revisions, checkpoint) = match (
            self.store.replay_answers(&id).await,
            self.store.replay_revisions(&id).await,
            self.store.latest_checkpoint(&id).await,
        ) {
            (Ok(a), Ok(r), Ok(c)) => (a, r, c),
            (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => {
                let reason = format!("reading the session's answers: {e}");
                self.fail_to_start(&live, &reason).await;
                return;
            }
        };
        // A checkpoint is checked only if the replay reaches it with stored answers alone.
        let verify = checkpoint
            .filter(|c| c.answers as usize <= stored_answers.len())
            .map(|c| (c.progress as u64, c.digest));
        let recording = match self.recording_options(&live) {
            Ok(r) => r,
            Err(reason) => {
                self.fail_to_start(&live, &reason).await;
                return;
            }
        };
        let (control_tx, control_rx) = std::sync::mpsc::channel();
        let (event_tx, event_rx) = tokio::sync::mpsc::unbounded_channel();
        live.lock().control = Some(control_tx);
        let ctx = SessionContext {
            sink: Arc::new(sink::ChannelSink(event_tx.clone())),
            controls: Controls::new(control_rx),
            stored_answers,
            stored_revisions,
            verify,
            models_dir: self.config.models_dir.clone(),
            observer: None,
        };
        let spec = live.spec.clone();
        let spec_id = id.clone();
        let mut builder = std::thread::Builder::new().name(format!("session-{id}"));
        if let Some(bytes) = self.config.session_stack_size {
            builder = builder.stack_size(bytes);
        }
        let spawned = builder.spawn(move || {
            let mut ctx = ctx;
            // Opening the file (and a viewer connection) is blocking IO: here, not on the
            // async runtime.
            let (options, graph) = recording;
            match recording::start(&spec_id, graph, &options) {
                Ok(observer) => ctx.observer = observer,
                Err(e) => {
                    let _ = event_tx.send(crate::session::SessionEvent::Ended(
                        crate::session::Ending::Failed(format!(
                            "the recording could not start: {e:#}"
                        )),
                    ));
                    return;
                }
            }
            let result =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_session(&spec, ctx)));
            if let Err(panic) = result {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "unknown".into());
                let _ = event_tx.send(crate::session::SessionEvent::Ended(
                    crate::session::Ending::Failed(format!("the session panicked: {what}")),
                ));
            }
        });
        if let Err(e) = spawned {
            live.lock().control = None;
            let reason = format!("the session's thread could not start: {e}");
            self.fail_to_start(&live, &reason).await;
            return;
        }
        consumer::consume(self.clone(), live, event_rx).await;
    }

    /// Stop a session for good (it can still be resumed later).
    pub async fn stop(&self, id: &str) -> Result<(), HubError> {
        let row = self
            .store
            .session(id)
            .await?
            .ok_or_else(|| HubError::NotFound(id.into()))?;
        let Some(live) = self.live(id).filter(|l| l.lock().status.is_active()) else {
            return Err(HubError::Conflict(format!(
                "session {id} is {}, not running",
                row.status.as_str()
            )));
        };
        let queued = {
            let mut s = live.lock();
            s.stop_requested = true;
            match &s.control {
                Some(c) => {
                    let _ = c.send(crate::session::Control::Stop);
                    false
                }
                None => {
                    s.status = Status::Stopped;
                    true
                }
            }
        };
        if queued {
            self.store
                .set_status(id, Status::Stopped, Some("stopped while queued"))
                .await?;
        }
        Ok(())
    }

    /// Continue an interrupted, stopped or failed session: it replays its stored answers (never
    /// asking them again) and goes on.
    pub async fn resume(self: &Arc<Self>, id: &str) -> Result<SessionRow, HubError> {
        let row = self
            .store
            .session(id)
            .await?
            .ok_or_else(|| HubError::NotFound(id.into()))?;
        let live_status = self.live(id).map(|l| l.lock().status);
        let status = live_status.unwrap_or(row.status);
        if !status.is_resumable() {
            return Err(HubError::Conflict(format!(
                "session {id} is {}: only interrupted, stopped or failed sessions resume",
                status.as_str()
            )));
        }
        self.store.set_status(id, Status::Queued, None).await?;
        let row = self
            .store
            .session(id)
            .await?
            .ok_or_else(|| HubError::NotFound(id.into()))?;
        self.start(row.clone())?;
        Ok(row)
    }

    /// The status a client should see: the live one while the hub runs the session.
    pub fn status_of(&self, row: &SessionRow) -> Status {
        self.live(&row.id).map_or(row.status, |l| l.lock().status)
    }

    /// Graceful shutdown: every running session checkpoints and ends as `interrupted`; browsers
    /// get `ended`. Queued sessions stay queued for the next start.
    pub async fn shutdown(&self, grace: Duration) {
        self.slots.close();
        let lives: Vec<Arc<Live>> = self
            .live
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .values()
            .cloned()
            .collect();
        for live in &lives {
            if let Some(c) = &live.lock().control {
                let _ = c.send(crate::session::Control::Shutdown);
            }
        }
        let tasks: Vec<JoinHandle<()>> =
            std::mem::take(&mut *self.tasks.lock().unwrap_or_else(|e| e.into_inner()));
        let all = futures_util::future::join_all(tasks);
        if tokio::time::timeout(grace, all).await.is_err() {
            tracing::warn!(
                "sessions did not finish within {grace:?}; they will be marked interrupted at the next start"
            );
        }
    }

    /// `<data dir>/recordings/<id>.rrd`.
    pub fn recording_path(&self, id: &str) -> PathBuf {
        self.config
            .data_dir
            .join("recordings")
            .join(format!("{id}.rrd"))
    }

    /// Where and how a session records: its file unless recording is off, and the viewer to
    /// stream to (its own, else the server's).
    fn recording_options(
        &self,
        live: &Live,
    ) -> Result<
        (
            crate::record::RecordingOptions,
            crate::scene_graph::SceneGraph,
        ),
        String,
    > {
        let settings = live.spec.settings()?;
        let options = crate::record::RecordingOptions {
            path: settings.record.then(|| self.recording_path(&live.id)),
            connect: settings
                .rerun_connect
                .or_else(|| self.config.rerun_connect.clone()),
        };
        Ok((options, live.spec.scene_graph()?))
    }

    /// Where the frames of a human session's episode are kept: `<data dir>/frames/<id>/<n>.json`.
    pub fn frames_path(&self, id: &str, episode: u64) -> PathBuf {
        self.config
            .data_dir
            .join("frames")
            .join(id)
            .join(format!("{episode}.json"))
    }

    /// Write a learner checkpoint to `<data dir>/checkpoints/<id>.safetensors` (atomically) and
    /// return its path relative to the data dir.
    async fn write_checkpoint(&self, id: &str, bytes: Vec<u8>) -> std::io::Result<String> {
        let dir = self.config.data_dir.join("checkpoints");
        let relative = format!("checkpoints/{id}.safetensors");
        let path = self.config.data_dir.join(&relative);
        tokio::task::spawn_blocking(move || {
            std::fs::create_dir_all(&dir)?;
            let tmp = path.with_extension("safetensors.tmp");
            std::fs::write(&tmp, bytes)?;
            std::fs::rename(&tmp, &path)
        })
        .await
        .map_err(std::io::Error::other)??;
        Ok(relative)
    }
}
