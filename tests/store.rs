//! The store against real databases (sessions, queries, answers, steps, checkpoints; people and
//! studies in `store_people.rs`): every test here runs twice, on SQLite (a file in a
//! temporary data dir, as `dualrep serve` opens it) and on PostgreSQL (a fresh database on the
//! tests' throwaway cluster, `support::postgres`), from the same body.

use crate::support::store_backends::{on_both, store_with_session};
use dualrep::guidance::drpl::trainer::Preference;
use dualrep::guidance::evaluative_run::{AskedStep, EpisodeRecord};
use dualrep::scene_graph::AbstractState;
use dualrep::session::{AnswerValue, Answerer, QueryKind, StoredMoment};
use dualrep::sim::Outcome;
use dualrep::store::{CommitOutcome, Db, Status, Store, SyntheticAnswer};

on_both!(
    the_first_committed_answer_wins_and_repeats_are_idempotent,
    stored_moments_carry_each_querys_step_action_and_answer,
    a_re_asked_query_keeps_its_id_and_replay_stops_at_the_first_gap,
    synthetic_batches_store_queries_with_answers_once,
    status_episodes_checkpoints_and_recovery,
    an_undo_reopens_an_answer_and_the_resume_replays_it_where_it_was_applied,
    asked_steps_come_back_bit_for_bit_with_their_moments,
    synthetic_answers_store_their_steps_once,
    a_stored_step_that_is_not_whole_f32s_is_an_error_that_names_its_column,
);

async fn the_first_committed_answer_wins_and_repeats_are_idempotent(store: Store) {
    let store = store_with_session(store, "s1").await;
    let q = store
        .upsert_query("s1", 0, QueryKind::Evaluative, 17, 5, "{}", None)
        .await
        .unwrap();
    let good = AnswerValue::Evaluation(1);
    assert_eq!(
        store
            .commit_answer(q, "s1", good, Answerer::Trainer, None, 120)
            .await
            .unwrap(),
        CommitOutcome::Committed
    );
    assert_eq!(
        store
            .commit_answer(q, "s1", good, Answerer::Trainer, None, 130)
            .await
            .unwrap(),
        CommitOutcome::AlreadyAnswered(good)
    );
    assert_eq!(
        store
            .commit_answer(
                q,
                "s1",
                AnswerValue::Evaluation(-1),
                Answerer::Timeout,
                None,
                0
            )
            .await
            .unwrap(),
        CommitOutcome::AlreadyAnswered(good)
    );
    let answers = store.answers("s1").await.unwrap();
    assert_eq!(answers.len(), 1);
    assert_eq!(
        (answers[0].step, answers[0].value, answers[0].latency_ms),
        (17, good, 120)
    );
    assert_eq!(answers[0].who, Answerer::Trainer);
}

/// What a resumed remote session catches up on: each evaluative query's step, the action of
/// its stored transition (none without one) and its answer, if any.
async fn stored_moments_carry_each_querys_step_action_and_answer(store: Store) {
    let store = store_with_session(store, "s1").await;
    let data = r#"{"kind": "evaluative", "observation": [0.0], "action": [0.25, -0.830583],
                   "reward": 0.0, "next_observation": [0.0]}"#;
    let answered = store
        .upsert_query("s1", 0, QueryKind::Evaluative, 7, 1, "{}", Some(data))
        .await
        .unwrap();
    store
        .upsert_query("s1", 1, QueryKind::Evaluative, 8, 0, "{}", None)
        .await
        .unwrap();
    store
        .commit_answer(
            answered,
            "s1",
            AnswerValue::Evaluation(-1),
            Answerer::Trainer,
            None,
            5,
        )
        .await
        .unwrap();
    assert_eq!(
        store.stored_moments("s1").await.unwrap(),
        vec![
            StoredMoment {
                seq: 0,
                step: 7,
                action: Some(vec![0.25, -0.830583]),
                value: Some(AnswerValue::Evaluation(-1)),
                asked: None,
            },
            StoredMoment {
                seq: 1,
                step: 8,
                action: None,
                value: None,
                asked: None,
            },
        ]
    );
}

async fn a_re_asked_query_keeps_its_id_and_replay_stops_at_the_first_gap(store: Store) {
    let store = store_with_session(store, "s1").await;
    let a = store
        .upsert_query("s1", 0, QueryKind::Preference, 0, 0, "{}", None)
        .await
        .unwrap();
    let b = store
        .upsert_query("s1", 1, QueryKind::Preference, 1, 0, "{}", None)
        .await
        .unwrap();
    assert_eq!(
        store
            .upsert_query("s1", 1, QueryKind::Preference, 1, 0, "{}", None)
            .await
            .unwrap(),
        b
    );
    let c = store
        .upsert_query("s1", 2, QueryKind::Preference, 2, 0, "{}", None)
        .await
        .unwrap();
    for (q, v) in [(a, Preference::Left), (c, Preference::Skip)] {
        store
            .commit_answer(
                q,
                "s1",
                AnswerValue::Preference(v),
                Answerer::Trainer,
                None,
                5,
            )
            .await
            .unwrap();
    }
    // Query 1 is unanswered: the replay holds query 0 only, and query 1 is asked again.
    assert_eq!(
        store.replay_answers("s1").await.unwrap(),
        vec![AnswerValue::Preference(Preference::Left)]
    );
    let counts = store.answer_counts("s1").await.unwrap();
    assert_eq!(
        (counts.total, counts.by_trainer, counts.no_feedback),
        (2, 2, 1)
    );
}

async fn synthetic_batches_store_queries_with_answers_once(store: Store) {
    let store = store_with_session(store, "s1").await;
    let batch: Vec<SyntheticAnswer> = (0..5)
        .map(|i| SyntheticAnswer {
            seq: i,
            kind: QueryKind::Evaluative,
            step: i * 10,
            abstract_state: 1,
            value: AnswerValue::Evaluation(if i % 2 == 0 { 1 } else { -1 }),
            data: None,
            asked: None,
        })
        .collect();
    store.insert_synthetic("s1", &batch).await.unwrap();
    // A resumed synthetic session replays the same answers: nothing is duplicated.
    store.insert_synthetic("s1", &batch).await.unwrap();
    let answers = store.answers("s1").await.unwrap();
    assert_eq!(answers.len(), 5);
    assert!(answers.iter().all(|a| a.who == Answerer::Synthetic));
    assert_eq!(store.replay_answers("s1").await.unwrap().len(), 5);
}

async fn status_episodes_checkpoints_and_recovery(store: Store) {
    let store = store_with_session(store, "s1").await;
    store.set_status("s1", Status::Running, None).await.unwrap();
    let row = store.session("s1").await.unwrap().unwrap();
    assert_eq!(row.status, Status::Running);
    assert!(row.started_at.is_some() && row.ended_at.is_none());
    let e = EpisodeRecord {
        step: 40,
        episode: 0,
        episode_return: -3.5,
        length: 40,
        cumulative_return: -3.5,
        feedback_count: 4,
        feedback_fraction: 0.1,
        outcome: Outcome::Success,
        states_with_feedback: 3,
        steps_since_query: 2,
        longest_flood: 4,
    };
    store.insert_episode("s1", &e).await.unwrap();
    store.insert_episode("s1", &e).await.unwrap();
    let episodes = store.episodes("s1").await.unwrap();
    assert_eq!(episodes.len(), 1);
    assert_eq!(
        (episodes[0].episode_return, episodes[0].outcome.as_str()),
        (-3.5, "success")
    );
    store
        .insert_checkpoint("s1", 40, 4, "abc", Some("checkpoints/s1.safetensors"))
        .await
        .unwrap();
    store
        .insert_checkpoint("s1", 80, 9, "def", None)
        .await
        .unwrap();
    assert_eq!(
        store.latest_checkpoint("s1").await.unwrap().unwrap().digest,
        "def"
    );
    // A crash leaves it running: the next start calls it interrupted.
    let (interrupted, queued) = store.recover_after_restart().await.unwrap();
    assert_eq!((interrupted, queued.len()), (vec!["s1".to_string()], 0));
    let row = store.session("s1").await.unwrap().unwrap();
    assert_eq!(row.status, Status::Interrupted);
    assert!(row.reason.unwrap().contains("stopped"));
}

async fn an_undo_reopens_an_answer_and_the_resume_replays_it_where_it_was_applied(store: Store) {
    use dualrep::session::events::{Revision, StoredRevision};
    use dualrep::store::{ReanswerOutcome, UndoOutcome};
    let store = store_with_session(store, "s1").await;
    let (good, bad) = (AnswerValue::Evaluation(1), AnswerValue::Evaluation(-1));
    let q0 = store
        .upsert_query("s1", 0, QueryKind::Evaluative, 3, 1, "{}", None)
        .await
        .unwrap();
    let q1 = store
        .upsert_query("s1", 1, QueryKind::Evaluative, 9, 1, "{}", None)
        .await
        .unwrap();
    assert_eq!(
        store
            .undo_answer(q0, "s1", QueryKind::Evaluative, None)
            .await
            .unwrap(),
        UndoOutcome::NotAnswered
    );
    store
        .commit_answer(q0, "s1", good, Answerer::Trainer, None, 50)
        .await
        .unwrap();
    store
        .commit_answer(q1, "s1", good, Answerer::Trainer, None, 60)
        .await
        .unwrap();
    // Not undone: a new answer does not replace it.
    assert_eq!(
        store
            .reanswer(q0, bad, Answerer::Trainer, None, 10)
            .await
            .unwrap(),
        ReanswerOutcome::Stands(good)
    );
    assert_eq!(
        store
            .undo_answer(q0, "s1", QueryKind::Evaluative, None)
            .await
            .unwrap(),
        UndoOutcome::Undone(1)
    );
    assert_eq!(
        store
            .undo_answer(q0, "s1", QueryKind::Evaluative, None)
            .await
            .unwrap(),
        UndoOutcome::AlreadyUndone
    );
    // Meanwhile the answer reads as "no feedback", what the learner uses.
    assert_eq!(
        store.answer_value(q0).await.unwrap(),
        Some(AnswerValue::Evaluation(0))
    );
    store.revision_applied("s1", 0, 1, 4).await.unwrap();
    assert_eq!(
        store
            .reanswer(q0, bad, Answerer::Trainer, None, 700)
            .await
            .unwrap(),
        ReanswerOutcome::Committed(2)
    );
    assert_eq!(
        store
            .reanswer(q0, good, Answerer::Trainer, None, 800)
            .await
            .unwrap(),
        ReanswerOutcome::Stands(bad),
        "the first new answer wins"
    );
    let answers = store.answers("s1").await.unwrap();
    assert_eq!(
        (answers[0].value, answers[0].revision, answers[0].latency_ms),
        (bad, 2, 700)
    );
    assert_eq!(store.answer_counts("s1").await.unwrap().total, 2);
    // A resume feeds the answer as first given, then the undo at 4 and the new answer (never
    // applied: the server stopped first) once the replay is over.
    assert_eq!(store.replay_answers("s1").await.unwrap(), vec![good, good]);
    assert_eq!(
        store.replay_revisions("s1").await.unwrap(),
        vec![
            StoredRevision {
                revision: Revision {
                    seq: 0,
                    revision: 1,
                    value: None
                },
                applied_at: Some(4),
            },
            StoredRevision {
                revision: Revision {
                    seq: 0,
                    revision: 2,
                    value: Some(bad)
                },
                applied_at: None,
            },
        ]
    );
    // Applied at most once: a resumed session's re-application keeps the first progress.
    store.revision_applied("s1", 0, 1, 9).await.unwrap();
    assert_eq!(
        store.replay_revisions("s1").await.unwrap()[0].applied_at,
        Some(4)
    );
}

/// A step whose numbers JSON would not give back bit for bit without care.
fn asked_step(mark: f32) -> AskedStep {
    AskedStep {
        obs: vec![0.1 + mark, f32::MIN_POSITIVE, -1.0 / 3.0],
        action: vec![mark.sin(), -0.830583],
        reward: 0.7 * mark,
        next_obs: vec![0.2 + mark, 1e-30, 2.0 / 3.0],
        terminated: mark > 1.0,
        abstract_state: AbstractState(5),
        predicted: -0.123_456_79,
    }
}

async fn asked_steps_come_back_bit_for_bit_with_their_moments(store: Store) {
    let store = store_with_session(store, "s1").await;
    let data = r#"{"kind": "evaluative", "observation": [0.0], "action": [0.0, 0.0],
                   "reward": 0.0, "next_observation": [0.0]}"#;
    let q = store
        .upsert_query("s1", 0, QueryKind::Evaluative, 7, 5, "{}", Some(data))
        .await
        .unwrap();
    store
        .store_asked_step(q, "s1", &asked_step(0.5))
        .await
        .unwrap();
    // Asked again under its number (a resumed run met the moment again): the first one stays.
    store
        .store_asked_step(q, "s1", &asked_step(2.0))
        .await
        .unwrap();
    store
        .commit_answer(
            q,
            "s1",
            AnswerValue::Evaluation(1),
            Answerer::Trainer,
            None,
            5,
        )
        .await
        .unwrap();
    let open = store
        .upsert_query("s1", 1, QueryKind::Evaluative, 8, 5, "{}", None)
        .await
        .unwrap();
    store
        .store_asked_step(open, "s1", &asked_step(3.0))
        .await
        .unwrap();

    let moments = store.stored_moments("s1").await.unwrap();
    assert_eq!(moments.len(), 2);
    let (first, second) = (&moments[0], &moments[1]);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let expected = asked_step(0.5);
    let got = first.asked.as_ref().expect("the step was kept");
    assert_eq!(got, &expected);
    assert_eq!(bits(&got.obs), bits(&expected.obs));
    assert_eq!(got.reward.to_bits(), expected.reward.to_bits());
    assert_eq!(got.predicted.to_bits(), expected.predicted.to_bits());
    // The catch-up compares the exact action, not the one in `queries.data`.
    assert_eq!(first.action.as_deref(), Some(expected.action.as_slice()));
    assert_eq!(first.value, Some(AnswerValue::Evaluation(1)));
    // A query left open keeps its step too (it has no answer to take in).
    assert_eq!(second.asked, Some(asked_step(3.0)));
    assert_eq!(second.value, None);
    assert!(second.asked.as_ref().unwrap().terminated);
}

async fn synthetic_answers_store_their_steps_once(store: Store) {
    let store = store_with_session(store, "s1").await;
    let batch: Vec<SyntheticAnswer> = (0..3u64)
        .map(|i| SyntheticAnswer {
            seq: i,
            kind: QueryKind::Evaluative,
            step: 20 + i,
            abstract_state: 5,
            value: AnswerValue::Evaluation(-1),
            data: None,
            asked: (i != 1).then(|| asked_step(i as f32)),
        })
        .collect();
    store.insert_synthetic("s1", &batch).await.unwrap();
    store.insert_synthetic("s1", &batch).await.unwrap();
    let moments = store.stored_moments("s1").await.unwrap();
    let asked: Vec<Option<AskedStep>> = moments.into_iter().map(|m| m.asked).collect();
    assert_eq!(
        asked,
        vec![Some(asked_step(0.0)), None, Some(asked_step(2.0))]
    );
    let count = "SELECT COUNT(*) FROM query_transitions";
    let rows: i64 = match store.db() {
        Db::Sqlite { reader, .. } => sqlx::query_scalar(count).fetch_one(reader).await,
        Db::Postgres(pool) => sqlx::query_scalar(count).fetch_one(pool).await,
    }
    .unwrap();
    assert_eq!(rows, 2);
}

async fn a_stored_step_that_is_not_whole_f32s_is_an_error_that_names_its_column(store: Store) {
    let store = store_with_session(store, "s1").await;
    let q = store
        .upsert_query("s1", 0, QueryKind::Evaluative, 7, 5, "{}", None)
        .await
        .unwrap();
    store
        .store_asked_step(q, "s1", &asked_step(0.5))
        .await
        .unwrap();
    let corrupt = "UPDATE query_transitions SET next_observation = $1";
    let five_bytes = vec![0u8, 1, 2, 3, 0xff];
    match store.db() {
        Db::Sqlite { writer, .. } => sqlx::query(corrupt)
            .bind(five_bytes)
            .execute(writer)
            .await
            .map(|_| ()),
        Db::Postgres(pool) => sqlx::query(corrupt)
            .bind(five_bytes)
            .execute(pool)
            .await
            .map(|_| ()),
    }
    .unwrap();
    let err = store.stored_moments("s1").await.unwrap_err().to_string();
    assert!(
        err.contains("query_transitions.next_observation: 5 bytes"),
        "{err}"
    );
}
