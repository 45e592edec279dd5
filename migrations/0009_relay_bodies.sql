-- Servers on one PostgreSQL pass each other commands, replies and the sessions' broadcasts
-- with NOTIFY (docs/serving-several.md), whose payload must stay under 8000 bytes. A message
-- larger than that (a preference query with its clips) is kept here for a minute and the
-- notification names its row. SQLite has one server: this table stays empty here (the same
-- schema as `postgres/0009_relay_bodies.sql`, in SQLite's types).

CREATE TABLE relay_bodies (
    id          INTEGER PRIMARY KEY AUTOINCREMENT,
    body        TEXT NOT NULL,
    created_at  TEXT NOT NULL
);
