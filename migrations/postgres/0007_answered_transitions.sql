-- PostgreSQL's copy of ../0007_answered_transitions.sql.
-- The step each evaluative query of a session on a remote env asked about, exactly as the
-- session's run stored it in its replay buffer beside the answer (arrays of f32 as
-- little-endian bytes). Such a session resumes from its latest run checkpoint; the answers
-- given after that checkpoint, on moments its env does not bring back (a robot), are taken
-- back into the run from here, so that its learner learns from them and nobody is asked them
-- again. Stored with the query, before any answer to it can be committed: every committed
-- answer has its step here (the answers are in `answers`). Sessions on our simulator replay
-- from step 0 and store none.

CREATE TABLE query_transitions (
    query_id          BIGINT PRIMARY KEY REFERENCES queries (id) ON DELETE CASCADE,
    session_id        TEXT NOT NULL REFERENCES sessions (id) ON DELETE CASCADE,
    observation       BYTEA NOT NULL,
    -- Normalised to [-1, 1].
    action            BYTEA NOT NULL,
    -- The env's reward (the replay holds it times the run's `reward_scale`).
    reward            DOUBLE PRECISION NOT NULL,
    next_observation  BYTEA NOT NULL,
    -- True: stored as an end of the MDP (no bootstrap past it).
    terminated        BOOLEAN NOT NULL,
    -- The human critic's prediction H_hat when it was asked (DREF's rule learns |H - H_hat|).
    predicted         DOUBLE PRECISION NOT NULL
);
CREATE INDEX query_transitions_by_session ON query_transitions (session_id);
