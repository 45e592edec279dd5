//! Which database the store talks to: the pools of each, how they are opened, their
//! migrations, and the one trait that lets a row of either be read by the same code.
//!
//! Why two native drivers and not sqlx's `Any`: `Any` opens SQLite from the URL alone
//! (`SqliteConnectOptions::from_url`), which carries none of the pragmas the store's durability
//! rests on (WAL, `synchronous = FULL`, foreign keys, the busy timeout); its `QueryBuilder`
//! writes `?` placeholders, which PostgreSQL refuses (sqlx issue #3000), and the group commit
//! builds its statements; and it decodes through a narrow set of kinds (no `NUMERIC`, no custom
//! column types). With the native drivers each backend keeps its own options and types, and the
//! later work on PostgreSQL (leases, LISTEN/NOTIFY) has its `PgPool` at hand. The price is that
//! each query is compiled once per driver, through `on_db!` (`store/mod.rs`); the SQL text is one.

use std::path::Path;
use std::str::FromStr;
use std::time::Duration;

use anyhow::Context;
use sqlx::postgres::{PgConnectOptions, PgPool, PgPoolOptions, PgRow};
use sqlx::sqlite::{SqliteConnectOptions, SqlitePool, SqlitePoolOptions, SqliteRow};
use sqlx::{ConnectOptions, Connection, Postgres, Sqlite};

/// The pools of the store's database.
#[derive(Clone, Debug)]
pub enum Db {
    /// SQLite in WAL mode: readers run beside the writer, and every write goes through one
    /// connection, in order, instead of contending for SQLite's lock (whose busy handler sleeps
    /// in steps of milliseconds). `synchronous = FULL`: a commit is on disk when it returns.
    Sqlite {
        reader: SqlitePool,
        writer: SqlitePool,
    },
    /// PostgreSQL: one pool for reads and writes. The server orders concurrent writers itself
    /// (row locks; the store's read-then-write transactions take theirs first), whether they
    /// are this process's connections or another server's, and with its default
    /// `synchronous_commit = on` a commit is durable when it returns.
    Postgres(PgPool),
}

/// The pool sizes: SQLite's readers (its one writer aside); PostgreSQL's connections in all.
const SQLITE_READERS: u32 = 8;
const POSTGRES_CONNECTIONS: u32 = 16;

impl Db {
    /// The SQLite file at `path`, created on first use.
    pub(super) async fn sqlite_file(path: &Path) -> anyhow::Result<Db> {
        let options = SqliteConnectOptions::from_str("sqlite://")?.filename(path);
        Self::sqlite(options, &path.display().to_string()).await
    }

    /// The database at `url`: `sqlite://PATH` (created on first use) or
    /// `postgres://USER[:PASSWORD]@HOST[:PORT]/DATABASE` (the database must exist).
    pub(super) async fn connect(url: &str) -> anyhow::Result<Db> {
        let shown = redacted(url);
        let scheme = url.split_once(':').map(|(s, _)| s).unwrap_or_default();
        match scheme {
            "sqlite" => {
                let options = SqliteConnectOptions::from_str(url)
                    .with_context(|| format!("{shown} is not a valid SQLite URL"))?;
                let path = options.get_filename().display().to_string();
                Self::sqlite(options, &path).await
            }
            "postgres" | "postgresql" => {
                let options = PgConnectOptions::from_str(url)
                    .with_context(|| format!("{shown} is not a valid PostgreSQL URL"))?;
                Self::postgres(options).await
            }
            _ => anyhow::bail!(
                "the database URL {shown} names neither SQLite nor PostgreSQL: give \
                 sqlite://PATH or postgres://USER:PASSWORD@HOST:PORT/DATABASE"
            ),
        }
    }

    async fn sqlite(options: SqliteConnectOptions, shown: &str) -> anyhow::Result<Db> {
        let options = options
            .create_if_missing(true)
            .journal_mode(sqlx::sqlite::SqliteJournalMode::Wal)
            .synchronous(sqlx::sqlite::SqliteSynchronous::Full)
            .foreign_keys(true)
            .busy_timeout(Duration::from_secs(10));
        // One connection first, for the error of a file that cannot be opened (a pool would
        // retry it until its timeout and then report only that).
        options
            .connect()
            .await
            .with_context(|| format!("opening the SQLite database {shown}"))?
            .close()
            .await?;
        let writer = SqlitePoolOptions::new()
            .max_connections(1)
            .connect_with(options.clone())
            .await?;
        // Read-only: a write sent to a reader by mistake fails at once ("attempt to write a
        // readonly database") instead of racing the writer, which it would fail with "database
        // is locked" now and then (a read-then-write transaction whose snapshot it moved).
        let reader = SqlitePoolOptions::new()
            .max_connections(SQLITE_READERS)
            .connect_with(options.create_if_missing(false).read_only(true))
            .await?;
        Ok(Db::Sqlite { reader, writer })
    }

    async fn postgres(options: PgConnectOptions) -> anyhow::Result<Db> {
        let shown = format!(
            "PostgreSQL at {}@{}:{}/{}",
            options.get_username(),
            options.get_host(),
            options.get_port(),
            options.get_database().unwrap_or(options.get_username())
        );
        // As for SQLite: a refused connection, a bad password or a missing database says so
        // at once, instead of as a pool timeout.
        sqlx::PgConnection::connect_with(&options)
            .await
            .with_context(|| format!("connecting to {shown}"))?
            .close()
            .await?;
        let pool = PgPoolOptions::new()
            .max_connections(POSTGRES_CONNECTIONS)
            .acquire_timeout(Duration::from_secs(30))
            .connect_with(options)
            .await
            .with_context(|| format!("connecting to {shown}"))?;
        Ok(Db::Postgres(pool))
    }

    /// Apply the backend's migrations (`migrations/` for SQLite, `migrations/postgres/` for
    /// PostgreSQL: the same numbers, the same schema in each one's types).
    pub(super) async fn migrate(&self) -> anyhow::Result<()> {
        match self {
            Db::Sqlite { writer, .. } => sqlx::migrate!("./migrations").run(writer).await?,
            // Migrations of several servers starting at once: sqlx holds an advisory lock
            // while it applies them.
            Db::Postgres(pool) => sqlx::migrate!("./migrations/postgres").run(pool).await?,
        }
        Ok(())
    }

    /// The backend's name, for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Db::Sqlite { .. } => "SQLite",
            Db::Postgres(_) => "PostgreSQL",
        }
    }
}

/// `url` with its password, if any, replaced by `***` (URLs are shown in errors and logs).
pub fn redacted(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else {
        return url.to_string();
    };
    // The last `@` ends the user info even when a password holds `/` or `@` unencoded: a
    // URL that does not parse is shown in its error too.
    match rest.rfind('@') {
        Some(at) if rest[..at].contains(':') => {
            let user = rest[..at].split_once(':').map_or("", |(u, _)| u);
            format!("{scheme}://{user}:***@{}", &rest[at + 1..])
        }
        _ => url.to_string(),
    }
}

/// A value both drivers decode (every column type the store reads).
pub(crate) trait Value:
    for<'r> sqlx::Decode<'r, Sqlite>
    + sqlx::Type<Sqlite>
    + for<'r> sqlx::Decode<'r, Postgres>
    + sqlx::Type<Postgres>
{
}

impl<T> Value for T where
    T: for<'r> sqlx::Decode<'r, Sqlite>
        + sqlx::Type<Sqlite>
        + for<'r> sqlx::Decode<'r, Postgres>
        + sqlx::Type<Postgres>
{
}

/// A row of either database, read by column name: row types are written once
/// (`SessionRow::from_row` and the like) for both.
pub(crate) trait StoreRow {
    /// The column's value; panics when the column is missing or holds another type, as
    /// `sqlx::Row::get` does (the schema and the queries are the store's own).
    fn get<T: Value>(&self, column: &str) -> T;
}

impl StoreRow for SqliteRow {
    fn get<T: Value>(&self, column: &str) -> T {
        sqlx::Row::get(self, column)
    }
}

impl StoreRow for PgRow {
    fn get<T: Value>(&self, column: &str) -> T {
        sqlx::Row::get(self, column)
    }
}

#[cfg(test)]
mod tests {
    use super::redacted;

    #[test]
    fn urls_are_shown_without_their_password() {
        assert_eq!(
            redacted("postgres://dualrep:s3cr:et@db:5432/dualrep?sslmode=disable"),
            "postgres://dualrep:***@db:5432/dualrep?sslmode=disable"
        );
        assert_eq!(redacted("postgres://u:a/b@c@db/x"), "postgres://u:***@db/x");
        assert_eq!(
            redacted("postgres://dualrep@db/x"),
            "postgres://dualrep@db/x"
        );
        assert_eq!(
            redacted("sqlite:///data/dualrep.db"),
            "sqlite:///data/dualrep.db"
        );
        assert_eq!(redacted("sqlite::memory:"), "sqlite::memory:");
    }
}
