//! What servers on one PostgreSQL say to each other, through it (docs/serving-several.md):
//! each server LISTENs on its own channel, and sends NOTIFYs in order on one connection of its
//! own ([`Notifier`]), so that what one server sends another arrives in the order it was sent.
//! A notification's payload must stay under 8000 bytes: a larger message is kept in
//! `relay_bodies` and the notification names its row; rows older than a minute go. Only
//! PostgreSQL has any of this: on SQLite one server owns the database.

use sqlx::postgres::{PgConnection, PgListener};
use sqlx::{Connection, Row};

use super::{Db, Result, Store};

/// How long a kept message body stays readable (a notification is read within milliseconds,
/// or its reader's connection was lost, and then it is not read at all).
const BODY_KEPT_SECONDS: f64 = 60.0;

/// One server's sending connection: NOTIFYs in the order they are made.
pub struct Notifier {
    conn: PgConnection,
}

impl Notifier {
    /// NOTIFY `channel` with `payload` (under 8000 bytes).
    pub async fn notify(&mut self, channel: &str, payload: &str) -> Result<()> {
        sqlx::query("SELECT pg_notify($1, $2)")
            .bind(channel)
            .bind(payload)
            .execute(&mut self.conn)
            .await?;
        Ok(())
    }

    /// Keep a message too large for a notification; the row id to name in one instead.
    pub async fn keep_body(&mut self, body: &str) -> Result<i64> {
        Ok(
            sqlx::query("INSERT INTO relay_bodies (body) VALUES ($1) RETURNING id")
                .bind(body)
                .fetch_one(&mut self.conn)
                .await?
                .get("id"),
        )
    }

    /// Drop the kept bodies older than a minute.
    pub async fn forget_old_bodies(&mut self) -> Result<u64> {
        Ok(sqlx::query(
            "DELETE FROM relay_bodies WHERE created_at < now() - make_interval(secs => $1)",
        )
        .bind(BODY_KEPT_SECONDS)
        .execute(&mut self.conn)
        .await?
        .rows_affected())
    }
}

impl Store {
    /// A connection listening on `channel` (PostgreSQL; `None` on SQLite). It reconnects by
    /// itself when its connection is lost; what was sent meanwhile is not received.
    pub async fn listener(&self, channel: &str) -> Result<Option<PgListener>> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(None);
        };
        let mut listener = PgListener::connect_with(pool).await?;
        listener.listen(channel).await?;
        Ok(Some(listener))
    }

    /// A connection of its own for sending notifications (PostgreSQL; `None` on SQLite).
    pub async fn notifier(&self) -> Result<Option<Notifier>> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(None);
        };
        let conn = PgConnection::connect_with(&pool.connect_options()).await?;
        Ok(Some(Notifier { conn }))
    }

    /// A message body [`Notifier::keep_body`] kept, if it is still there.
    pub async fn relay_body(&self, id: i64) -> Result<Option<String>> {
        let Db::Postgres(pool) = &self.db else {
            return Ok(None);
        };
        Ok(sqlx::query("SELECT body FROM relay_bodies WHERE id = $1")
            .bind(id)
            .fetch_optional(pool)
            .await?
            .map(|r| r.get("body")))
    }
}
