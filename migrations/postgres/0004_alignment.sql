-- PostgreSQL's copy of ../0004_alignment.sql.
-- A preference session's posterior alignment with the synthetic trainer's reward, after every
-- answer (and again after an undo changes the posterior at the same query count).
CREATE TABLE alignments (
    session_id         TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    queries            BIGINT NOT NULL,
    alignment          DOUBLE PRECISION NOT NULL,
    alignment_of_mean  DOUBLE PRECISION NOT NULL,
    PRIMARY KEY (session_id, queries)
);
