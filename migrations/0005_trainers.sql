-- Trainers as people. A researcher invites named trainers to a session (each with a link of
-- their own), or a trainer names themself on the session's shared link; every answer, undo and
-- survey stores who. A session that combines several answers per query keeps every trainer's
-- own answer in `trainer_answers` and what they combined into in `answers`. Answers stored
-- before this read as an anonymous trainer (`trainer_id` NULL).

CREATE TABLE trainers (
    id          INTEGER PRIMARY KEY AUTOINCREMENT,
    session_id  TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    name        TEXT NOT NULL,
    -- The trainer's own token (their link).
    token       TEXT NOT NULL UNIQUE,
    -- 'invited' (a researcher made the link) or 'joined' (named on the shared link).
    origin      TEXT NOT NULL CHECK (origin IN ('invited', 'joined')),
    created_at  TEXT NOT NULL,
    UNIQUE (session_id, name)
);

ALTER TABLE answers ADD COLUMN trainer_id INTEGER REFERENCES trainers (id);
ALTER TABLE answer_revisions ADD COLUMN trainer_id INTEGER REFERENCES trainers (id);

CREATE TABLE trainer_answers (
    query_id     INTEGER NOT NULL REFERENCES queries (id) ON DELETE CASCADE,
    session_id   TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    trainer_id   INTEGER NOT NULL REFERENCES trainers (id) ON DELETE CASCADE,
    -- JSON as in `answers`.
    value        TEXT NOT NULL,
    latency_ms   INTEGER NOT NULL,
    answered_at  TEXT NOT NULL,
    PRIMARY KEY (query_id, trainer_id)
);
CREATE INDEX trainer_answers_by_session ON trainer_answers (session_id);

-- A named trainer's answers to the paper's three questions (an anonymous trainer's stay in
-- `surveys`).
CREATE TABLE trainer_surveys (
    trainer_id              INTEGER PRIMARY KEY REFERENCES trainers (id) ON DELETE CASCADE,
    session_id              TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    overall_experience      INTEGER NOT NULL CHECK (overall_experience BETWEEN 1 AND 5),
    perceived_intelligence  INTEGER NOT NULL CHECK (perceived_intelligence BETWEEN 1 AND 5),
    cognitive_ease          INTEGER NOT NULL CHECK (cognitive_ease BETWEEN 1 AND 5),
    answered_at             TEXT NOT NULL
);

-- What the learner saw at a query, for datasets (JSON): an evaluative query's transition
-- (observation, action, reward, next observation), a preference query's two segments
-- (trajectory, steps, abstract state, features). NULL for queries stored before.
ALTER TABLE queries ADD COLUMN data TEXT;
