-- The paper's three 5-point questions, asked of the trainer after a human session.
CREATE TABLE surveys (
    session_id              TEXT PRIMARY KEY REFERENCES sessions (id) ON DELETE CASCADE,
    overall_experience      INTEGER NOT NULL CHECK (overall_experience BETWEEN 1 AND 5),
    perceived_intelligence  INTEGER NOT NULL CHECK (perceived_intelligence BETWEEN 1 AND 5),
    cognitive_ease          INTEGER NOT NULL CHECK (cognitive_ease BETWEEN 1 AND 5),
    answered_at             TEXT NOT NULL
);
