-- PostgreSQL's copy of ../0006_studies.sql.
-- Human-subject studies (the paper's Figures 4 and 6). A study is a researcher's StudySpec
-- (JSON) behind one link; each person who opens the link becomes a pseudonymous participant
-- with a link of their own, meets the study's conditions in their counterbalanced order (a
-- human session each), and answers the study's survey after each.

CREATE TABLE studies (
    id          TEXT COLLATE "C" PRIMARY KEY,
    title       TEXT NOT NULL,
    -- The validated StudySpec, as JSON.
    spec        TEXT NOT NULL,
    -- The one link every participant opens (/study/{link_token}).
    link_token  TEXT NOT NULL UNIQUE,
    created_at  TEXT COLLATE "C" NOT NULL
);

CREATE TABLE participants (
    -- Pseudonymous: never a name.
    id            TEXT PRIMARY KEY,
    study_id      TEXT NOT NULL REFERENCES studies (id) ON DELETE CASCADE,
    -- 0-based, in the order people opened the link: picks their row of the ordering.
    number        BIGINT NOT NULL,
    -- The participant's own link (/participate/{token}).
    token         TEXT NOT NULL UNIQUE,
    -- The conditions in the order this participant meets them (JSON list of names).
    ordering      TEXT NOT NULL,
    consented_at  TEXT,
    created_at    TEXT NOT NULL,
    UNIQUE (study_id, number)
);

-- A participant's session in the condition at `position` of their order, once launched.
CREATE TABLE study_sessions (
    participant_id  TEXT NOT NULL REFERENCES participants (id) ON DELETE CASCADE,
    position        BIGINT NOT NULL,
    condition       TEXT NOT NULL,
    session_id      TEXT NOT NULL UNIQUE REFERENCES sessions (id),
    PRIMARY KEY (participant_id, position)
);

-- The survey after a condition: one row per question.
CREATE TABLE study_answers (
    participant_id  TEXT NOT NULL REFERENCES participants (id) ON DELETE CASCADE,
    position        BIGINT NOT NULL,
    question        TEXT COLLATE "C" NOT NULL,
    value           BIGINT NOT NULL,
    answered_at     TEXT NOT NULL,
    PRIMARY KEY (participant_id, position, question)
);
