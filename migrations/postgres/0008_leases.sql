-- PostgreSQL's copy of ../0008_leases.sql. Several `dualrep serve` processes on one database
-- (docs/serving-several.md): the server that runs a session (`owner`, a random id per process)
-- and until when its lease holds (`lease_until`, the database's clock: one clock for every
-- server). A session whose lease ran out is claimed by another server and resumed.
-- `session_resumes`: the latest resume checkpoint of a session on a remote env, so that any
-- server can resume it (the file in a server's data dir is that server's copy).

ALTER TABLE sessions ADD COLUMN owner TEXT;
ALTER TABLE sessions ADD COLUMN lease_until TIMESTAMPTZ;
CREATE INDEX sessions_claimable ON sessions (created_at)
    WHERE status IN ('queued', 'running', 'waiting');

CREATE TABLE session_resumes (
    session_id  TEXT PRIMARY KEY REFERENCES sessions (id) ON DELETE CASCADE,
    bytes       BYTEA NOT NULL
);
