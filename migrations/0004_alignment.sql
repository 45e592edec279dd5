-- A preference session's posterior alignment with the synthetic trainer's reward, after every
-- answer (and again after an undo changes the posterior at the same query count).
CREATE TABLE alignments (
    session_id         TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    queries            INTEGER NOT NULL,
    alignment          REAL NOT NULL,
    alignment_of_mean  REAL NOT NULL,
    PRIMARY KEY (session_id, queries)
);
