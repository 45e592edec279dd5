//! `GET /api/sessions/{id}/export?format=jsonl`: everything about a session, one JSON record a
//! line, each tagged with what it is (`"record"`): the session, then every answer and episode,
//! each trainer's summary (`trainer`) and own answers (`trainer_answer`), and the trainers'
//! agreement. Pure: the caller gathers the records.
//!
//! The session, trainer and agreement records are the API's own views of them (built in
//! `http`, above this module), so they come in as anything serialisable.

use serde::Serialize;
use serde_json::Value;

use crate::store::{AnswerRow, EpisodeRow, PersonAnswer};

/// A session's records, in the order the download lists them.
pub struct SessionRecords<'a, Session, Trainer, Agreement> {
    pub session: &'a Session,
    pub answers: &'a [AnswerRow],
    pub episodes: &'a [EpisodeRow],
    pub trainers: &'a [Trainer],
    pub trainer_answers: &'a [PersonAnswer],
    pub agreement: &'a Agreement,
}

/// The JSONL text of `records`, one line each, `\n`-terminated.
pub fn session_jsonl<Session, Trainer, Agreement>(
    records: &SessionRecords<'_, Session, Trainer, Agreement>,
) -> String
where
    Session: Serialize,
    Trainer: Serialize,
    Agreement: Serialize,
{
    let mut out = String::new();
    let mut line = |record: &str, value: Value| {
        let mut v = value;
        v["record"] = record.into();
        out.push_str(&v.to_string());
        out.push('\n');
    };
    line("session", json(records.session));
    for a in records.answers {
        line("answer", json(a));
    }
    for e in records.episodes {
        line("episode", json(e));
    }
    for t in records.trainers {
        line("trainer", json(t));
    }
    for a in records.trainer_answers {
        line("trainer_answer", json(a));
    }
    line("agreement", json(records.agreement));
    out
}

/// A record's JSON; one that cannot be written is `null` (then `{"record": ...}` alone).
fn json(value: &impl Serialize) -> Value {
    serde_json::to_value(value).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    #[test]
    fn each_record_is_a_line_tagged_with_what_it_is_in_the_downloads_order() {
        let trainers = [json!({"name": "ada"}), json!({"name": "bo"})];
        let text = session_jsonl(&SessionRecords {
            session: &json!({"id": "s1"}),
            answers: &[],
            episodes: &[],
            trainers: &trainers,
            trainer_answers: &[],
            agreement: &json!({"pairs": 0}),
        });
        assert_eq!(
            text,
            concat!(
                r#"{"id":"s1","record":"session"}"#,
                "\n",
                r#"{"name":"ada","record":"trainer"}"#,
                "\n",
                r#"{"name":"bo","record":"trainer"}"#,
                "\n",
                r#"{"pairs":0,"record":"agreement"}"#,
                "\n"
            )
        );
    }
}
