//! The wire format pinned: every message each way, the closed sets of values, and what bad
//! client text is refused with.

use super::*;
use crate::guidance::drpl::trainer::Preference;
use proptest::prelude::*;

#[test]
fn a_sessions_pacing_counts_frozen_episodes_as_the_grid_report_does() {
    use crate::guidance::ask_pacing::frozen_share;
    use crate::guidance::evaluative_run::EpisodeRecord;
    use crate::sim::Outcome;
    // Twelve failed episodes 1,000 steps apart; the rule last asked at step 2,999.
    let records: Vec<EpisodeRecord> = (1..=12u64)
        .map(|i| EpisodeRecord {
            step: 1_000 * i,
            episode: i - 1,
            episode_return: 0.0,
            length: 1_000,
            cumulative_return: 0.0,
            feedback_count: 3,
            feedback_fraction: 0.0,
            outcome: if i == 1 {
                Outcome::Success
            } else {
                Outcome::Failure
            },
            states_with_feedback: 1,
            steps_since_query: (1_000 * i).saturating_sub(3_000),
            longest_flood: 3,
        })
        .collect();
    let mut pacing = RulePacing::default();
    for e in &records {
        pacing.episode(e);
    }
    // By the 12th episode's end (step 12k) the rule has been silent for 9k steps: the
    // last 10 episodes failed, but that is not yet a freeze...
    assert_eq!(pacing.frozen_episodes, 0);
    // ... which it is once the silence reaches 10k steps.
    let mut late = records[11].clone();
    late.step = 13_000;
    late.steps_since_query = 10_000;
    pacing.episode(&late);
    assert_eq!(pacing.frozen_episodes, 1);
    assert_eq!((pacing.episodes, pacing.longest_flood), (13, 3));
    // The grid's report counts the same episodes.
    let mut all: Vec<(u64, bool)> = records
        .iter()
        .map(|e| (e.steps_since_query, e.outcome == Outcome::Success))
        .collect();
    all.push((10_000, false));
    assert!((frozen_share(&all) - 1.0 / 13.0).abs() < 1e-12);
}

#[test]
fn answers_parse_in_both_forms() {
    assert_eq!(
        parse_client(r#"{"type":"answer","id":7,"value":-1}"#).unwrap(),
        ClientMessage::Answer {
            id: 7,
            value: AnswerValue::Evaluation(-1)
        }
    );
    assert_eq!(
        parse_client(r#"{"type":"answer","id":7,"value":"left"}"#).unwrap(),
        ClientMessage::Answer {
            id: 7,
            value: AnswerValue::Preference(Preference::Left)
        }
    );
    assert_eq!(
        parse_client(r#"{"type":"undo","id":3}"#).unwrap(),
        ClientMessage::Undo { id: 3 }
    );
}

#[test]
fn bad_messages_get_codes() {
    assert_eq!(
        parse_client("{").unwrap_err().code,
        ErrorCode::MalformedJson
    );
    assert_eq!(parse_client("[1]").unwrap_err().code, ErrorCode::BadMessage);
    assert_eq!(
        parse_client(r#"{"type":"answer","id":"x","value":1}"#)
            .unwrap_err()
            .code,
        ErrorCode::BadMessage
    );
    assert_eq!(
        parse_client(r#"{"type":"answer","id":1,"value":"maybe"}"#)
            .unwrap_err()
            .code,
        ErrorCode::BadMessage
    );
    assert_eq!(
        parse_client(r#"{"type":"hack","id":1}"#).unwrap_err().code,
        ErrorCode::BadMessage
    );
    assert_eq!(
        parse_client(r#"{"type":"answer","id":1,"value":1,"x":2}"#)
            .unwrap_err()
            .code,
        ErrorCode::BadMessage
    );
    for combined in [
        r#"0.5"#,
        r#"{"tally":{"left":1,"right":1,"equal":0,"skip":0}}"#,
    ] {
        let text = format!(r#"{{"type":"answer","id":1,"value":{combined}}}"#);
        assert_eq!(parse_client(&text).unwrap_err().code, ErrorCode::BadMessage);
    }
    assert_eq!(
        id_of(r#"{"type":"answer","id":12,"value":"maybe"}"#),
        Some(12)
    );
}

#[test]
fn server_messages_are_tagged_snake_case() {
    let m = ServerMessage::Withdrawn {
        id: 4,
        reason: WithdrawReason::Answered,
    };
    assert_eq!(
        m.to_text(),
        r#"{"type":"withdrawn","id":4,"reason":"answered"}"#
    );
    let e = ServerMessage::Ended {
        status: Status::Finished,
        reason: None,
    };
    assert_eq!(e.to_text(), r#"{"type":"ended","status":"finished"}"#);
}

proptest! {
    // Whatever arrives, the parser answers with a message or an error; it never panics.
    #[test]
    fn the_parser_never_panics_on_text(text in ".{0,200}") {
        let _ = parse_client(&text);
        let _ = id_of(&text);
    }

    #[test]
    fn the_parser_never_panics_on_json_shaped_text(
        ty in prop::sample::select(vec!["answer", "undo", "hello", "", "ANSWER"]),
        id in prop::option::of(any::<i64>()),
        value in prop::sample::select(vec!["1", "0", "-1", "2", "1.5", "\"left\"", "\"skip\"", "null", "[]", "{}", "\"\"", "99999999999999999999"]),
    ) {
        let negative = id.is_some_and(|i| i < 0);
        let id = id.map_or("null".to_string(), |i| i.to_string());
        let text = format!(r#"{{"type":"{ty}","id":{id},"value":{value}}}"#);
        match parse_client(&text) {
            Ok(ClientMessage::Answer { value, .. }) => prop_assert!(ty == "answer" && (value.as_evaluation().is_some() || value.as_preference().is_some() || matches!(value, AnswerValue::Evaluation(_)))),
            Ok(ClientMessage::Undo { .. }) => prop_assert!(false, "undo takes no value"),
            // A well-formed answer naming a negative query is an unknown query.
            Err(e) => prop_assert!(e.code == ErrorCode::BadMessage || (negative && e.code == ErrorCode::UnknownQuery)),
        }
    }
}
