-- PostgreSQL's copy of ../0002_surveys.sql.
-- The paper's three 5-point questions, asked of the trainer after a human session.
CREATE TABLE surveys (
    session_id              TEXT PRIMARY KEY REFERENCES sessions (id) ON DELETE CASCADE,
    overall_experience      BIGINT NOT NULL CHECK (overall_experience BETWEEN 1 AND 5),
    perceived_intelligence  BIGINT NOT NULL CHECK (perceived_intelligence BETWEEN 1 AND 5),
    cognitive_ease          BIGINT NOT NULL CHECK (cognitive_ease BETWEEN 1 AND 5),
    answered_at             TEXT NOT NULL
);
