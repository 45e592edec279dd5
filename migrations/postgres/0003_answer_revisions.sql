-- PostgreSQL's copy of ../0003_answer_revisions.sql.
-- Undo: a trainer may take back an answer and give it again. `answers` always holds the answer
-- that stands now (`revision` counts the changes); `answer_revisions` keeps each change with the
-- session's progress when its learner took it in, so a resumed session replays the undo at the
-- same point and reproduces its checkpoints. Revision 0 is the original answer, copied here at
-- the first undo.

ALTER TABLE answers ADD COLUMN revision BIGINT NOT NULL DEFAULT 0;

CREATE TABLE answer_revisions (
    -- SQLite's implicit rowid, made explicit: the store replays revisions never applied in the
    -- order they were stored (`ORDER BY rowid` on both databases).
    rowid       BIGINT GENERATED ALWAYS AS IDENTITY,
    query_id    BIGINT NOT NULL REFERENCES queries (id) ON DELETE CASCADE,
    session_id  TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    revision    BIGINT NOT NULL,
    -- JSON as in `answers`; NULL: undone (the query is open again).
    value       TEXT,
    who         TEXT NOT NULL,
    latency_ms  BIGINT NOT NULL,
    -- Steps or queries done when the session applied it; NULL until it did.
    applied_at  BIGINT,
    created_at  TEXT NOT NULL,
    PRIMARY KEY (query_id, revision)
);
CREATE INDEX answer_revisions_by_session ON answer_revisions (session_id);
