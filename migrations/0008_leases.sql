-- Several `dualrep serve` processes on one PostgreSQL (docs/serving-several.md): which server
-- runs a session and until when its lease holds, and the latest resume checkpoint of a session
-- on a remote env in the database. SQLite has one server: these columns and this table stay
-- empty here (the same schema as `postgres/0008_leases.sql`, in SQLite's types).

ALTER TABLE sessions ADD COLUMN owner TEXT;
ALTER TABLE sessions ADD COLUMN lease_until TEXT;

CREATE TABLE session_resumes (
    session_id  TEXT PRIMARY KEY REFERENCES sessions (id) ON DELETE CASCADE,
    bytes       BLOB NOT NULL
);
