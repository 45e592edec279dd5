//! The database: SQLite through sqlx, schema in `migrations/` (applied at open). One file per
//! table family. WAL mode with `synchronous = FULL`, so a committed answer survives a killed
//! process and a power cut alike; answers are acknowledged only after their commit.
//!
//! - `sessions`: launch config, status, progress.
//! - `queries`: what was asked (kind, step, abstract state, payload) and the answers given.
//! - `transitions`: the step each query of a session on a remote env asked about, as its run
//!   stored it, and the stored moments such a session resumes with.
//! - `answer_revisions`: undos and the answers given after them.
//! - `episodes`: finished episodes' metrics.
//! - `checkpoints`: where a session was, and the learner's digest.
//! - `datasets`: answered queries with what the learner saw, for Parquet exports.
//! - `surveys`: the trainer's answers to the paper's three questions.
//! - `trainers`: named trainers, each one's own answers (sessions that combine several per
//!   query) and surveys.
//! - `alignments`: a preference session's alignment after every answer.
//! - `studies`: studies, their participants, each participant's session per condition, and
//!   their survey answers.

/// The current time as the RFC 3339 text every table stores (UTC, milliseconds), as a literal
/// for `concat!`: sqlx takes only static SQL.
macro_rules! now {
    () => {
        "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')"
    };
}

mod alignments;
mod checkpoints;
mod columns;
mod datasets;
mod episodes;
mod queries;
mod revisions;
mod sessions;
mod studies;
mod surveys;
mod trainers;
mod transitions;

use std::path::Path;
use std::str::FromStr;
use std::time::Duration;

use sqlx::SqlitePool;
use sqlx::sqlite::SqliteConnectOptions;

pub use alignments::AlignmentRow;
pub use checkpoints::CheckpointRow;
pub use datasets::DatasetRow;
pub use episodes::EpisodeRow;
pub use queries::{AnswerCounts, AnswerRow, CommitOutcome, QueryRow, SyntheticAnswer};
pub use revisions::{ReanswerOutcome, UndoOutcome};
pub use sessions::{NewSession, SessionRow, Status, StoredSpecError};
pub use studies::{ParticipantRow, StudyAnswerRow, StudyRow, StudySessionRow, SurveyOutcome};
pub use surveys::{Survey, SurveyError};
pub use trainers::{
    AddTrainer, NameError, PersonAnswer, TrainerOrigin, TrainerRef, TrainerRow, VoteOutcome,
    check_name,
};

/// The database file inside the data dir.
pub const DB_FILE: &str = "dualrep.db";

/// What a store call can fail with.
pub type Result<T> = std::result::Result<T, sqlx::Error>;

#[derive(Clone, Debug)]
pub struct Store {
    /// Readers (WAL lets them run beside the writer).
    pool: SqlitePool,
    /// One connection for every write: writers queue here, in order, instead of contending for
    /// SQLite's lock (whose busy handler sleeps in steps of milliseconds).
    writer: SqlitePool,
    /// The answer writer's queue (`queries::group_commit`).
    committer: tokio::sync::mpsc::Sender<queries::CommitRequest>,
}

impl Store {
    /// Open (creating on first run) `<data_dir>/dualrep.db` and apply the migrations.
    pub async fn open(data_dir: &Path) -> anyhow::Result<Self> {
        std::fs::create_dir_all(data_dir)?;
        let options = SqliteConnectOptions::from_str("sqlite://")?
            .filename(data_dir.join(DB_FILE))
            .create_if_missing(true)
            .journal_mode(sqlx::sqlite::SqliteJournalMode::Wal)
            .synchronous(sqlx::sqlite::SqliteSynchronous::Full)
            .foreign_keys(true)
            .busy_timeout(Duration::from_secs(10));
        let writer = sqlx::sqlite::SqlitePoolOptions::new()
            .max_connections(1)
            .connect_with(options.clone())
            .await?;
        let pool = sqlx::sqlite::SqlitePoolOptions::new()
            .max_connections(8)
            .connect_with(options)
            .await?;
        let store = Self::assemble(pool, writer);
        store.migrate().await?;
        Ok(store)
    }

    /// A store over an existing pool (`#[sqlx::test]` hands one in); migrations applied.
    pub async fn from_pool(pool: SqlitePool) -> anyhow::Result<Self> {
        let store = Self::assemble(pool.clone(), pool);
        store.migrate().await?;
        Ok(store)
    }

    /// The store over its pools, with its answer writer running on the current runtime.
    fn assemble(pool: SqlitePool, writer: SqlitePool) -> Self {
        let (committer, requests) = tokio::sync::mpsc::channel(4096);
        tokio::spawn(queries::group_commit(writer.clone(), requests));
        Self {
            pool,
            writer,
            committer,
        }
    }

    async fn migrate(&self) -> anyhow::Result<()> {
        sqlx::migrate!("./migrations").run(&self.writer).await?;
        Ok(())
    }

    pub fn pool(&self) -> &SqlitePool {
        &self.pool
    }

    fn writer(&self) -> &SqlitePool {
        &self.writer
    }

    /// Whether the database answers (for `/healthz`).
    pub async fn ping(&self) -> Result<()> {
        sqlx::query("SELECT 1")
            .execute(&self.pool)
            .await
            .map(|_| ())
    }
}
