-- Training sessions, the queries they asked, the answers people (or oracles, or timeouts) gave,
-- finished episodes and checkpoints. Times are RFC 3339 UTC text; JSON columns are TEXT.

CREATE TABLE sessions (
    id             TEXT PRIMARY KEY,
    task           TEXT NOT NULL,
    method         TEXT NOT NULL,
    trainer        TEXT NOT NULL CHECK (trainer IN ('human', 'synthetic')),
    seed           INTEGER NOT NULL,
    -- Environment steps (DREF, EF, SAC) or queries (DRPL and its baselines).
    budget         INTEGER NOT NULL,
    -- The whole launch request after defaults were filled in, as JSON.
    config         TEXT NOT NULL,
    trainer_token  TEXT NOT NULL,
    status         TEXT NOT NULL CHECK (status IN
                     ('queued', 'running', 'waiting', 'finished', 'failed', 'stopped', 'interrupted')),
    reason         TEXT,
    -- Steps or queries done, and the latest metrics as JSON (for lists without joins).
    progress       INTEGER NOT NULL DEFAULT 0,
    latest         TEXT NOT NULL DEFAULT '{}',
    created_at     TEXT NOT NULL,
    started_at     TEXT,
    ended_at       TEXT
);

CREATE TABLE queries (
    id              INTEGER PRIMARY KEY AUTOINCREMENT,
    session_id      TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    -- 0-based order within the session: a resumed session replays stored answers by seq.
    seq             INTEGER NOT NULL,
    kind            TEXT NOT NULL CHECK (kind IN ('evaluative', 'preference')),
    step            INTEGER NOT NULL,
    abstract_state  INTEGER NOT NULL,
    payload         TEXT NOT NULL,
    asked_at        TEXT NOT NULL,
    UNIQUE (session_id, seq)
);

CREATE TABLE answers (
    query_id     INTEGER PRIMARY KEY REFERENCES queries (id) ON DELETE CASCADE,
    session_id   TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    -- JSON: 1, 0 or -1 for evaluative queries; "left", "right", "equal" or "skip" for preferences.
    value        TEXT NOT NULL,
    -- 'trainer' (a person in a browser), 'synthetic' (an oracle) or 'timeout' (nobody answered).
    who          TEXT NOT NULL,
    latency_ms   INTEGER NOT NULL,
    answered_at  TEXT NOT NULL
);
CREATE INDEX answers_by_session ON answers (session_id, query_id);

CREATE TABLE episodes (
    session_id         TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    episode            INTEGER NOT NULL,
    step               INTEGER NOT NULL,
    return             REAL NOT NULL,
    length             INTEGER NOT NULL,
    cumulative_return  REAL NOT NULL,
    feedback_count     INTEGER NOT NULL,
    feedback_fraction  REAL NOT NULL,
    outcome            TEXT NOT NULL,
    PRIMARY KEY (session_id, episode)
);

CREATE TABLE checkpoints (
    session_id  TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    -- Steps (or queries) done when it was taken.
    progress    INTEGER NOT NULL,
    answers     INTEGER NOT NULL,
    -- FNV-1a of the learner's safetensors bytes: a resumed session checks its replay against it.
    digest      TEXT NOT NULL,
    -- The learner's weights, relative to the data dir (NULL for preference sessions).
    file        TEXT,
    created_at  TEXT NOT NULL,
    PRIMARY KEY (session_id, progress)
);
