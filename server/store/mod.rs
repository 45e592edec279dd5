//! The database: embedded SQLite (the default, a file in the data dir) or PostgreSQL
//! (`dualrep serve --database postgres://...`), through sqlx. One file per table family; the
//! schema in `migrations/` (SQLite) and `migrations/postgres/` (the same migrations in
//! PostgreSQL's types), applied at open. Answers are acknowledged only after their commit, and a
//! commit is durable when it returns: SQLite runs in WAL mode with `synchronous = FULL` (a
//! committed answer survives a killed process and a power cut alike); PostgreSQL keeps its
//! default `synchronous_commit = on`.
//!
//! One SQL text serves both databases (see `backend` for why two native drivers rather than
//! sqlx's `Any`). What both accept:
//! - placeholders `$1`, `$2`, ...: PostgreSQL's own; sqlx's SQLite driver binds `$N` to the
//!   N-th argument as well (`sqlx-sqlite/src/arguments.rs`);
//! - times made in Rust and bound (`clock`), never the database's `strftime`/`now()`; spans
//!   computed in Rust from the stored texts, never with `julianday`;
//! - `INSERT ... ON CONFLICT ... DO NOTHING | DO UPDATE SET col = excluded.col` (never `INSERT OR
//!   REPLACE`), `RETURNING`, `COUNT(*) FILTER (WHERE ...)` (never `SUM` of a comparison);
//! - JSON columns are text, read in Rust (never `json_extract`);
//! - a read-then-write transaction starts with the `UPDATE` that locks its row (PostgreSQL has
//!   no single writer; SQLite's writer connection orders them anyway);
//! - every write goes through `on_db!(.., writer, ..)`: on SQLite the readers are opened
//!   read-only, so a write sent to one fails at once rather than, now and then, failing the
//!   writer's transaction with "database is locked".
//!
//! The schemas differ only where the types must: `INTEGER PRIMARY KEY AUTOINCREMENT` is an
//! identity column, `INTEGER` is `BIGINT` (what `i64` binds as), `REAL` is `DOUBLE PRECISION`,
//! `BLOB` is `BYTEA`, a 0/1 flag is `BOOLEAN`, and the two tables the store reads in insertion
//! order (SQLite's implicit `rowid`) have an explicit identity column of that name.
//!
//! Checkpoint files and recordings stay in the data dir on either database; on PostgreSQL a
//! remote session's resume checkpoint is in the database too, for the server that takes the
//! session over (`leases`, docs/serving-several.md).
//!
//! - `sessions`: launch config, status, progress.
//! - `queries`: what was asked (kind, step, abstract state, payload) and the answers given.
//! - `transitions`: the step each query of a session on a remote env asked about, as its run
//!   stored it, and the stored moments such a session resumes with.
//! - `answer_revisions`: undos and the answers given after them.
//! - `episodes`: finished episodes' metrics.
//! - `checkpoints`: where a session was, and the learner's digest.
//! - `leases` (PostgreSQL): which server runs a session and until when; remote sessions'
//!   resume checkpoints (`session_resumes`).
//! - `datasets`: answered queries with what the learner saw, for Parquet exports.
//! - `surveys`: the trainer's answers to the paper's three questions.
//! - `trainers`: named trainers, each one's own answers (sessions that combine several per
//!   query) and surveys.
//! - `alignments`: a preference session's alignment after every answer.
//! - `studies`: studies, their participants, each participant's session per condition, and
//!   their survey answers.

/// `$body` once per database of `$db` (a [`Db`]), with `$pool` the pool to read from
/// (`reader`) or to write through (`writer`; PostgreSQL has one pool for both), and optionally
/// `$t` the database's sqlx type (`|pool: DB|`, for `QueryBuilder::<DB>`): the same SQL text,
/// bound and decoded by each driver's own types. `$body` may use `?` and `.await`; it is
/// compiled twice, and both copies must give the same type.
macro_rules! on_db {
    ($db:expr, $role:ident, |$pool:ident| $body:expr) => {
        on_db!($db, $role, |$pool: _Db| $body)
    };
    ($db:expr, reader, |$pool:ident: $t:ident| $body:expr) => {
        match &$db {
            $crate::store::Db::Sqlite { reader: $pool, .. } => {
                #[allow(dead_code)]
                type $t = sqlx::Sqlite;
                $body
            }
            $crate::store::Db::Postgres($pool) => {
                #[allow(dead_code)]
                type $t = sqlx::Postgres;
                $body
            }
        }
    };
    ($db:expr, writer, |$pool:ident: $t:ident| $body:expr) => {
        match &$db {
            $crate::store::Db::Sqlite { writer: $pool, .. } => {
                #[allow(dead_code)]
                type $t = sqlx::Sqlite;
                $body
            }
            $crate::store::Db::Postgres($pool) => {
                #[allow(dead_code)]
                type $t = sqlx::Postgres;
                $body
            }
        }
    };
}

mod alignments;
mod backend;
mod checkpoints;
mod clock;
mod columns;
mod datasets;
mod episodes;
mod leases;
mod notify;
mod queries;
mod revisions;
mod sessions;
mod studies;
mod surveys;
mod trainers;
mod transitions;

use std::path::Path;

use anyhow::Context;

pub use alignments::AlignmentRow;
pub use backend::{Db, redacted};
pub use checkpoints::CheckpointRow;
pub use datasets::DatasetRow;
pub use episodes::EpisodeRow;
pub use leases::LeaseHolder;
pub use notify::Notifier;
pub use queries::{AnswerCounts, AnswerRow, CommitOutcome, QueryRow, SyntheticAnswer};
pub use revisions::{ReanswerOutcome, UndoOutcome};
pub use sessions::{NewSession, SessionRow, Status, StoredSpecError};
pub use studies::{ParticipantRow, StudyAnswerRow, StudyRow, StudySessionRow, SurveyOutcome};
pub use surveys::{Survey, SurveyError};
pub use trainers::{
    AddTrainer, NameError, PersonAnswer, TrainerOrigin, TrainerRef, TrainerRow, VoteOutcome,
    check_name,
};

/// The database file inside the data dir (the default database).
pub const DB_FILE: &str = "dualrep.db";

/// What a store call can fail with.
pub type Result<T> = std::result::Result<T, sqlx::Error>;

/// The store: cheap to clone (pools and a channel), and shared by every part of a server.
#[derive(Clone, Debug)]
pub struct Store {
    db: Db,
    /// The answer writer's queue (`queries::group_commit`).
    committer: tokio::sync::mpsc::Sender<queries::CommitRequest>,
}

impl Store {
    /// Open (creating on first run) `<data_dir>/dualrep.db` and apply the migrations.
    pub async fn open(data_dir: &Path) -> anyhow::Result<Self> {
        std::fs::create_dir_all(data_dir)?;
        Self::assemble(Db::sqlite_file(&data_dir.join(DB_FILE)).await?).await
    }

    /// Open the database at `url` (`sqlite://PATH`, created on first use, or
    /// `postgres://USER:PASSWORD@HOST:PORT/DATABASE`, which must exist) and apply the
    /// migrations. Errors name the database without its password.
    pub async fn connect(url: &str) -> anyhow::Result<Self> {
        Self::assemble(Db::connect(url).await?).await
    }

    /// The store over its database, migrated, with its answer writer running on the current
    /// runtime.
    async fn assemble(db: Db) -> anyhow::Result<Self> {
        db.migrate()
            .await
            .with_context(|| format!("applying the {} migrations", db.name()))?;
        let (committer, requests) = tokio::sync::mpsc::channel(4096);
        tokio::spawn(queries::group_commit(db.clone(), requests));
        Ok(Self { db, committer })
    }

    /// The pools (tests and tools that run their own SQL).
    pub fn db(&self) -> &Db {
        &self.db
    }

    /// Whether the database answers (for `/healthz`).
    pub async fn ping(&self) -> Result<()> {
        on_db!(self.db, reader, |pool| sqlx::query("SELECT 1")
            .execute(pool)
            .await
            .map(|_| ()))
    }
}
