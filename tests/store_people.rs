//! The store's people and studies against real databases, on SQLite and PostgreSQL alike
//! (`support::store_backends`): times, named trainers and their votes and surveys, study
//! participants and surveys, the queue ahead of a session.

use crate::support::store_backends::{on_both, store_with_session};
use dualrep::guidance::drpl::trainer::Preference;
use dualrep::session::{AnswerValue, Answerer, QueryKind};
use dualrep::store::{Status, Store};

on_both!(
    times_are_stored_alike_and_spans_computed_from_them,
    trainers_votes_and_surveys_keep_their_order_and_replace_in_place,
    a_study_numbers_its_participants_and_keeps_the_first_survey,
    the_queue_ahead_of_a_session_counts_earlier_queued_ones,
    surveys_commit_while_sessions_change_status_at_the_same_moment,
);

/// Times are the server's RFC 3339 text on either database, and the spans read from them.
async fn times_are_stored_alike_and_spans_computed_from_them(store: Store) {
    let store = store_with_session(store, "s1").await;
    let row = store.session("s1").await.unwrap().unwrap();
    let shape = |t: &str| {
        t.len() == 24 && t.ends_with('Z') && t.as_bytes()[10] == b'T' && t.as_bytes()[19] == b'.'
    };
    assert!(shape(&row.created_at), "{}", row.created_at);
    assert_eq!(
        store.session_seconds("s1").await.unwrap(),
        None,
        "not started"
    );
    assert_eq!(
        store.trainer_seconds("s1").await.unwrap(),
        None,
        "no answers"
    );
    store.set_status("s1", Status::Running, None).await.unwrap();
    let q = store
        .upsert_query("s1", 0, QueryKind::Evaluative, 1, 0, "{}", None)
        .await
        .unwrap();
    tokio::time::sleep(std::time::Duration::from_millis(30)).await;
    store
        .commit_answer(
            q,
            "s1",
            AnswerValue::Evaluation(1),
            Answerer::Trainer,
            None,
            30,
        )
        .await
        .unwrap();
    store
        .set_status("s1", Status::Finished, None)
        .await
        .unwrap();
    let row = store.session("s1").await.unwrap().unwrap();
    assert!(shape(row.started_at.as_deref().unwrap()) && shape(row.ended_at.as_deref().unwrap()));
    let t = store.trainer_seconds("s1").await.unwrap().unwrap();
    assert!((0.025..10.0).contains(&t), "{t}");
    let run = store.session_seconds("s1").await.unwrap().unwrap();
    assert!((0.025..10.0).contains(&run), "{run}");
    let person = store.person_answers("s1").await.unwrap();
    assert_eq!(person.len(), 1);
    let span = person[0].answered_s - person[0].asked_s;
    assert!((0.025..10.0).contains(&span), "{span}");
    assert!(person[0].asked_s > 1.7e9, "seconds since the Unix epoch");
}

/// Trainers, their own answers in the order given, and the surveys and alignments that a
/// second write replaces in place.
async fn trainers_votes_and_surveys_keep_their_order_and_replace_in_place(store: Store) {
    use dualrep::store::{AddTrainer, AlignmentRow, Survey, TrainerOrigin, VoteOutcome};
    let store = store_with_session(store, "s1").await;
    let mut ids = Vec::new();
    for (name, token) in [("Zoe", "tz"), ("ada", "ta"), ("Émile", "te")] {
        match store
            .add_trainer("s1", name, token, TrainerOrigin::Joined)
            .await
            .unwrap()
        {
            AddTrainer::Added(t) => {
                assert_eq!((t.name.as_str(), t.origin), (name, TrainerOrigin::Joined));
                ids.push(t.id);
            }
            AddTrainer::NameTaken => panic!("{name} is new"),
        }
    }
    assert!(matches!(
        store
            .add_trainer("s1", "ada", "other", TrainerOrigin::Invited)
            .await
            .unwrap(),
        AddTrainer::NameTaken
    ));
    let names: Vec<String> = store
        .trainers("s1")
        .await
        .unwrap()
        .into_iter()
        .map(|t| t.name)
        .collect();
    assert_eq!(names, ["Zoe", "ada", "Émile"]);
    assert_eq!(
        store.trainer_by_token("ta").await.unwrap().unwrap().id,
        ids[1]
    );
    let q = store
        .upsert_query("s1", 0, QueryKind::Preference, 0, 0, "{}", None)
        .await
        .unwrap();
    // Given last-first: they come back in the order given, not by trainer.
    let left = AnswerValue::Preference(Preference::Left);
    let right = AnswerValue::Preference(Preference::Right);
    for (id, v) in [(ids[2], left), (ids[0], right), (ids[1], left)] {
        assert_eq!(
            store.commit_vote(q, "s1", id, v, 40).await.unwrap(),
            VoteOutcome::Committed
        );
    }
    assert_eq!(
        store.commit_vote(q, "s1", ids[0], left, 50).await.unwrap(),
        VoteOutcome::AlreadyAnswered(right)
    );
    let votes: Vec<(i64, AnswerValue)> = store
        .query_votes(q)
        .await
        .unwrap()
        .into_iter()
        .map(|(t, v)| (t.id, v))
        .collect();
    assert_eq!(votes, [(ids[2], left), (ids[0], right), (ids[1], left)]);
    assert_eq!(store.person_answers("s1").await.unwrap().len(), 3);
    let survey = |n| Survey {
        overall_experience: n,
        perceived_intelligence: 2,
        cognitive_ease: 3,
    };
    store
        .save_trainer_survey(ids[0], "s1", &survey(1))
        .await
        .unwrap();
    store
        .save_trainer_survey(ids[0], "s1", &survey(5))
        .await
        .unwrap();
    assert_eq!(
        store.trainer_surveys("s1").await.unwrap(),
        [(ids[0], survey(5))]
    );
    store.save_survey("s1", &survey(2)).await.unwrap();
    store.save_survey("s1", &survey(4)).await.unwrap();
    assert_eq!(store.survey("s1").await.unwrap(), Some(survey(4)));
    for alignment in [0.5, 0.75] {
        let a = AlignmentRow {
            queries: 1,
            alignment,
            alignment_of_mean: -0.25,
        };
        store.record_alignment("s1", a).await.unwrap();
    }
    let curve = store.alignment("s1").await.unwrap();
    assert_eq!((curve.len(), curve[0].alignment), (1, 0.75));
}

/// Participants numbered in the order they came, a position's session linked once, and a
/// survey's first answers kept (sorted by question in byte order on both databases).
async fn a_study_numbers_its_participants_and_keeps_the_first_survey(store: Store) {
    use dualrep::store::{StudySessionRow, SurveyOutcome};
    let store = store_with_session(store, "s1").await;
    let spec = serde_json::json!({"title": "t"});
    let study = store.insert_study("st1", "t", &spec, "link").await.unwrap();
    assert_eq!((study.spec, study.link_token.as_str()), (spec, "link"));
    assert_eq!(
        store.study_by_link("link").await.unwrap().unwrap().id,
        "st1"
    );
    let order = |n: usize| vec![format!("c{n}")];
    let first = store
        .add_participant("st1", "p0", "tok0", order)
        .await
        .unwrap();
    let second = store
        .add_participant("st1", "p1", "tok1", order)
        .await
        .unwrap();
    assert_eq!((first.number, second.number), (0, 1));
    assert_eq!(second.ordering, ["c1"]);
    store.consent("p0").await.unwrap();
    let consented = store
        .participant_by_token("tok0")
        .await
        .unwrap()
        .unwrap()
        .consented_at;
    store.consent("p0").await.unwrap();
    assert_eq!(
        store
            .participant_by_token("tok0")
            .await
            .unwrap()
            .unwrap()
            .consented_at,
        consented,
        "the first consent's time stays"
    );
    let link = StudySessionRow {
        participant_id: "p0".into(),
        position: 0,
        condition: "c0".into(),
        session_id: "s1".into(),
    };
    assert!(store.link_study_session(&link).await.unwrap());
    assert!(!store.link_study_session(&link).await.unwrap());
    assert_eq!(store.study_sessions("st1").await.unwrap(), [link]);
    let answers: Vec<(String, i64)> = [("b", 2), ("B", 1), ("a_z", 3), ("az", 4)]
        .map(|(q, v)| (q.to_string(), v))
        .into();
    assert_eq!(
        store.save_study_survey("p0", 0, &answers).await.unwrap(),
        SurveyOutcome::Stored
    );
    assert_eq!(
        store
            .save_study_survey("p0", 0, &answers[..1])
            .await
            .unwrap(),
        SurveyOutcome::AlreadyAnswered
    );
    let questions: Vec<String> = store
        .study_answers("st1")
        .await
        .unwrap()
        .into_iter()
        .map(|a| a.question)
        .collect();
    assert_eq!(questions, ["B", "a_z", "az", "b"]);
    assert_eq!(store.answered_positions("p0").await.unwrap(), [0]);
}

/// A participant's survey is stored while sessions start and end around it: on SQLite a
/// status change written beside the writer connection (as `set_status` once was, through a
/// reader) invalidates the survey's read-then-insert and fails it with "database is locked"
/// (SQLITE_BUSY_SNAPSHOT, which no busy timeout waits out), and the study page shows a 500.
async fn surveys_commit_while_sessions_change_status_at_the_same_moment(store: Store) {
    use dualrep::store::SurveyOutcome;
    let store = store_with_session(store, "s1").await;
    let spec = serde_json::json!({"title": "t"});
    store.insert_study("st1", "t", &spec, "link").await.unwrap();
    const PEOPLE: usize = 60;
    for i in 0..PEOPLE {
        store
            .add_participant("st1", &format!("p{i}"), &format!("tok{i}"), |_| {
                vec!["c0".into()]
            })
            .await
            .unwrap();
    }
    let answers: Vec<(String, i64)> = ["E", "L", "T"].map(|q| (q.to_string(), 3)).into();
    let statuses = {
        let store = store.clone();
        tokio::spawn(async move {
            for k in 0..(PEOPLE * 8) {
                let status = if k % 2 == 0 {
                    Status::Running
                } else {
                    Status::Waiting
                };
                store.set_status("s1", status, None).await?;
            }
            anyhow::Ok(())
        })
    };
    let surveys: Vec<_> = (0..PEOPLE)
        .map(|i| {
            let (store, answers) = (store.clone(), answers.clone());
            tokio::spawn(
                async move { store.save_study_survey(&format!("p{i}"), 0, &answers).await },
            )
        })
        .collect();
    for (i, survey) in surveys.into_iter().enumerate() {
        let outcome = survey.await.unwrap();
        assert!(
            matches!(outcome, Ok(SurveyOutcome::Stored)),
            "participant {i}'s survey: {outcome:?}"
        );
    }
    statuses
        .await
        .unwrap()
        .expect("every status change commits");
    assert_eq!(
        store.study_answers("st1").await.unwrap().len(),
        PEOPLE * answers.len()
    );
}

/// A participant's page says how many sessions wait before theirs: the queued ones launched
/// earlier, not the running ones, not the later ones.
async fn the_queue_ahead_of_a_session_counts_earlier_queued_ones(store: Store) {
    let mut store = store;
    for id in ["a", "b", "c", "d"] {
        store = store_with_session(store, id).await;
    }
    store.set_status("b", Status::Running, None).await.unwrap();
    let row = |id: &'static str| {
        let store = store.clone();
        async move { store.session(id).await.unwrap().unwrap() }
    };
    // Launched in order a, b, c, d (ties in time broken by id): a is queued, b runs.
    assert_eq!(store.queued_before(&row("a").await).await.unwrap(), 0);
    assert_eq!(store.queued_before(&row("c").await).await.unwrap(), 1);
    assert_eq!(store.queued_before(&row("d").await).await.unwrap(), 2);
}
