use serde_json::json;

use super::*;
use crate::guidance::drpl::acquisition::Acquisition;
use crate::guidance::query_rule::UcbForm;
use crate::rl::kernels::KernelPath;
use crate::rl::{ActorMix, CriticLoss};
use crate::sim::{GripObservation, HoopShape, PlacingSuccess, Variant};

fn dref(task: Task, settings: &Settings) -> Result<EvaluativeRunConfig, SettingsError> {
    settings.evaluative(task, EvaluativeMethod::Dref, 0)
}

#[test]
fn pairs_read_json_where_it_is_json_and_text_elsewhere() {
    let s = Settings::from_pairs([
        ("hidden", "256,256"),
        ("c", "0.3"),
        ("ucb", "paper"),
        ("human_critic_mask", "true"),
        ("target_entropy", "auto"),
        ("k", "7"),
    ])
    .unwrap();
    assert_eq!(s.sac.hidden, Some(vec![256, 256]));
    assert_eq!(s.query_rule.c, Some(0.3));
    assert_eq!(s.query_rule.ucb, Some(UcbForm::Paper));
    assert_eq!(s.human_critic.human_critic_mask, Some(true));
    assert_eq!(
        s.sac.target_entropy,
        Some(TargetEntropy::Auto(AutoWord::Auto))
    );
    assert_eq!(s.query_rule.k, Some(7));
    let s = Settings::from_pairs([("target_entropy", "-2"), ("hidden", "[32, 32]")]).unwrap();
    assert_eq!(s.sac.target_entropy, Some(TargetEntropy::Value(-2.0)));
    assert_eq!(s.sac.hidden, Some(vec![32, 32]));
    // A later pair wins.
    let s = Settings::from_pairs([("c", "0.1"), ("c", "0.2")]).unwrap();
    assert_eq!(s.query_rule.c, Some(0.2));
}

#[test]
fn unknown_keys_and_wrong_types_are_refused_by_name() {
    let e = Settings::from_pairs([("no_such_key", "1")]).unwrap_err();
    assert!(
        matches!(&e, SettingsError::UnknownKey { key, .. } if key == "no_such_key"),
        "{e:?}"
    );
    let e = e.to_string();
    assert!(e.contains("no_such_key") && e.contains("pace_hz"), "{e}");
    let e = Settings::from_json(json!({"pace_hz": "fast"})).unwrap_err();
    assert_eq!(e.key(), Some("pace_hz"));
    let e = e.to_string();
    assert!(e.contains("invalid type"), "{e}");
    assert!(Settings::from_pairs([("hidden", "64,x")]).is_err());
    assert!(Settings::from_pairs([("k", "-1")]).is_err());
    assert!(Settings::from_pairs([("ucb", "best")]).is_err());
    let e = Settings::from_pairs([("critic_loss", "l1")]).unwrap_err();
    assert_eq!(e.key(), Some("critic_loss"), "{e}");
    let e = Settings::from_pairs([("critic_layer_norm", "yes")]).unwrap_err();
    assert_eq!(e.key(), Some("critic_layer_norm"), "{e}");
    assert!(Settings::from_json(json!({"trajectories": {"a": 1}})).is_err());
    assert!(Settings::from_json(json!({"variant": "robosuite"})).is_err());
}

#[test]
fn evaluative_settings_reach_the_run() {
    let s = Settings::from_json(json!({
        "hidden": [32, 32], "c": 0.5, "k": 7, "ucb": "paper", "batch_size": 64,
        "lambda": 2.0, "mix": "paper", "reward_scale": 0.1, "variant": "uniform",
        "release_at": 0.9, "observe_grip": "level", "success": "through", "hoop": "ring",
        "critic_loss": "huber", "critic_layer_norm": true
    }))
    .unwrap();
    let c = dref(Task::Placing, &s).unwrap();
    assert_eq!(c.sac.hidden, vec![32, 32]);
    assert_eq!((c.query_rule.c, c.query_rule.k), (0.5, 7));
    assert_eq!(c.query_rule.form, UcbForm::Paper);
    assert_eq!(c.sac.batch_size, 64);
    assert_eq!(c.sac.critic_loss, CriticLoss::Huber);
    assert!(c.sac.critic_layer_norm);
    assert!(
        !dref(Task::Placing, &Settings::default())
            .unwrap()
            .sac
            .critic_layer_norm
    );
    let critic = c.sac.human_critic.unwrap();
    assert_eq!((critic.lambda, critic.mix), (2.0, ActorMix::Paper));
    assert_eq!(c.reward_scale, 0.1);
    assert_eq!(c.env.variant, Variant::Uniform);
    assert_eq!(c.env.release_at, 0.9);
    assert_eq!(c.env.observe_grip, GripObservation::Level);
    assert_eq!(c.env.placing_success(), PlacingSuccess::Through);
    assert_eq!(c.env.hoop, HoopShape::Ring);
}

#[test]
fn settings_of_other_tasks_and_methods_are_refused() {
    let one = |v: serde_json::Value| Settings::from_json(v).unwrap();
    let e = dref(Task::Reaching, &one(json!({"trajectories": 10}))).unwrap_err();
    assert!(
        matches!(
            e,
            SettingsError::WrongFamily {
                key: "trajectories",
                family: Family::Preference,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("preference"), "{e}");
    assert!(dref(Task::Reaching, &one(json!({"side_engines_on_a0": true}))).is_err());
    assert!(dref(Task::LunarLander, &one(json!({"side_engines_on_a0": true}))).is_ok());
    assert!(dref(Task::Reaching, &one(json!({"release_at": 0.9}))).is_err());
    let e = dref(Task::Reaching, &one(json!({"hoop": "ring"}))).unwrap_err();
    assert_eq!(e.to_string(), "hoop applies to placing only, not reaching");
    assert!(Settings::from_json(json!({"hoop": "basket"})).is_err());
    assert!(dref(Task::LunarLander, &one(json!({"variant": "uniform"}))).is_err());
    let e = one(json!({"c": 0.3}))
        .preference(Task::Reaching, QueryMethod::Drpl, 0)
        .unwrap_err();
    assert!(e.to_string().contains("evaluative"), "{e}");
    assert!(
        one(json!({"release_at": 0.9}))
            .preference(Task::Reaching, QueryMethod::Drpl, 0)
            .is_err()
    );
}

#[test]
fn values_out_of_range_are_refused() {
    for bad in [
        json!({"tau": 1.5}),
        json!({"gamma": -0.1}),
        json!({"batch_size": 0}),
        json!({"lambda": -1}),
        json!({"learning_rate": 0}),
        json!({"hidden": []}),
        json!({"hidden": [64, 0]}),
        json!({"release_at": 1.5}),
        json!({"reward_scale": -1}),
        json!({"c": -0.1}),
    ] {
        let s = Settings::from_json(bad.clone()).unwrap();
        assert!(dref(Task::Placing, &s).is_err(), "{bad}");
    }
    for bad in [
        json!({"trajectories": 1}),
        json!({"samples": 0}),
        json!({"thinning": 0}),
    ] {
        let s = Settings::from_json(bad.clone()).unwrap();
        assert!(
            s.preference(Task::Placing, QueryMethod::Drpl, 0).is_err(),
            "{bad}"
        );
    }
}

#[test]
fn the_human_critic_switches_with_its_settings() {
    let sac = |v: serde_json::Value| {
        Settings::from_json(v)
            .unwrap()
            .evaluative(Task::Reaching, EvaluativeMethod::Sac, 0)
            .unwrap()
            .sac
            .human_critic
    };
    assert!(sac(json!({})).is_none());
    assert!(sac(json!({"lambda": 3})).is_some());
    assert!(sac(json!({"human_critic": true})).is_some());
    let off = Settings::from_json(json!({"human_critic": false}))
        .unwrap()
        .evaluative(Task::Reaching, EvaluativeMethod::Dref, 0)
        .unwrap();
    assert!(off.sac.human_critic.is_none());
}

#[test]
fn preference_settings_reach_the_run() {
    let s = Settings::from_json(json!({
        "trajectories": 10, "max_steps": 50, "min_run": 2, "acquisition": "mutual_information",
        "beta": 2.0, "samples": 50, "variant": "uniform"
    }))
    .unwrap();
    let c = s.preference(Task::Placing, QueryMethod::DrplSs, 3).unwrap();
    assert_eq!((c.trajectories, c.max_steps, c.min_run), (10, 50, 2));
    assert_eq!(c.acquisition, Acquisition::MutualInformation);
    assert_eq!((c.belief.beta, c.belief.samples), (2.0, 50));
    assert_eq!(c.env.variant, Variant::Uniform);
    assert_eq!(c.seed, 3);
}

/// `drpl-mi` defaults to the mutual-information pick; an `acquisition` setting wins over it,
/// so `drpl-mi` with `acquisition=uniform` is the paper's DRPL but for its name.
#[test]
fn drpl_mi_defaults_to_mutual_information_and_a_setting_wins() {
    let none = Settings::from_pairs(std::iter::empty::<(&str, &str)>()).unwrap();
    let mi = none
        .preference(Task::Placing, QueryMethod::DrplMi, 4)
        .unwrap();
    assert_eq!(mi.acquisition, Acquisition::MutualInformation);
    let drpl = none
        .preference(Task::Placing, QueryMethod::Drpl, 4)
        .unwrap();
    assert_eq!(drpl.acquisition, Acquisition::Uniform);
    let uniform = Settings::from_pairs([("acquisition", "uniform")])
        .unwrap()
        .preference(Task::Placing, QueryMethod::DrplMi, 4)
        .unwrap();
    assert_eq!(uniform.acquisition, Acquisition::Uniform);
    assert_eq!(
        PreferenceRunConfig {
            method: QueryMethod::Drpl,
            ..uniform
        },
        drpl
    );
}

#[test]
fn preference_settings_override_by_name_and_reject_nonsense() {
    let settings = |pairs: &[(&str, &str)]| Settings::from_pairs(pairs.iter().copied());
    let c = settings(&[
        ("trajectories", "12"),
        ("min_run", "1"),
        ("acquisition", "mutual-information"),
        ("samples", "50"),
        ("beta", "2.5"),
        ("side_engines_on_a0", "true"),
    ])
    .unwrap()
    .preference(Task::LunarLander, QueryMethod::Drpl, 0)
    .unwrap();
    assert_eq!((c.trajectories, c.min_run, c.belief.samples), (12, 1, 50));
    assert_eq!(c.acquisition, Acquisition::MutualInformation);
    assert_eq!(c.belief.beta, 2.5);
    for bad in [
        ("trajectories", "1"),
        ("beta", "nan"),
        ("thinning", "0"),
        ("hidden", "3"),
    ] {
        let refused =
            settings(&[bad]).and_then(|s| s.preference(Task::LunarLander, QueryMethod::Drpl, 0));
        assert!(refused.is_err(), "{bad:?}");
    }
    assert!(
        settings(&[("side_engines_on_a0", "true")])
            .unwrap()
            .preference(Task::Reaching, QueryMethod::Drpl, 0)
            .is_err()
    );
}

#[test]
fn session_settings_default_and_validate() {
    let none = Settings::default().session().unwrap();
    assert_eq!(none.pace_hz, DEFAULT_PACE_HZ);
    assert_eq!(none.answer_timeout_s, DEFAULT_ANSWER_TIMEOUT_S);
    assert!(none.record);
    let s = Settings::from_json(json!({"pace_hz": 5, "answer_timeout_s": 2.5, "record": false}))
        .unwrap();
    let session = s.session().unwrap();
    assert_eq!((session.pace_hz, session.answer_timeout_s), (5.0, 2.5));
    assert!(!session.record);
    // Session settings are not the algorithm's: the run builds without them.
    dref(Task::Reaching, &s).unwrap();
    assert_eq!(
        s.session_keys_set(),
        vec!["pace_hz", "answer_timeout_s", "record"]
    );
    for bad in [
        json!({"pace_hz": -1}),
        json!({"pace_hz": 5000}),
        json!({"answer_timeout_s": 0}),
        json!({"clip_frames": 0}),
        json!({"rerun_connect": ""}),
    ] {
        assert!(
            Settings::from_json(bad.clone()).unwrap().session().is_err(),
            "{bad}"
        );
    }
    assert!(Settings::from_json(json!({"record": "no"})).is_err());
}

#[test]
fn the_offered_defaults_are_the_runs_defaults_and_apply_cleanly() {
    // What GET /api/tasks offers for a task, sent back unchanged, builds the default run.
    for task in [Task::Reaching, Task::Placing, Task::LunarLander] {
        let offered = Settings::defaults(task, Family::Evaluative);
        let round_trip = Settings::from_json(serde_json::to_value(&offered).unwrap()).unwrap();
        assert_eq!(round_trip, offered);
        // `start` and `success` are offered as the variant's own, which the default leaves
        // implicit.
        let mut expected = EvaluativeRunConfig::new(task, EvaluativeMethod::Dref, 0);
        if task != Task::LunarLander {
            expected.env.start = Some(expected.env.start_pose());
        }
        if task == Task::Placing {
            expected.env.success = Some(expected.env.placing_success());
        }
        assert_eq!(dref(task, &offered).unwrap(), expected, "{task}");
        offered.session().unwrap();
        let offered = Settings::defaults(task, Family::Preference);
        let mut expected = PreferenceRunConfig::new(task, QueryMethod::Drpl, 0);
        if task == Task::Placing {
            expected.env.success = Some(expected.env.placing_success());
        }
        assert_eq!(
            offered.preference(task, QueryMethod::Drpl, 0).unwrap(),
            expected,
            "{task}"
        );
        // The task versions are Reaching's and Placing's only.
        assert_eq!(offered.env.variant.is_some(), task != Task::LunarLander);
        assert_eq!(offered.env.release_at.is_some(), task == Task::Placing);
        assert_eq!(
            offered.scene_graph.side_engines_on_a0.is_some(),
            task == Task::LunarLander
        );
    }
}

#[test]
fn merged_settings_take_the_later_value() {
    let file = Settings::from_json(json!({"c": 0.1, "k": 3})).unwrap();
    let flags = Settings::from_pairs([("c", "0.2")]).unwrap();
    let s = file.merged(flags).unwrap();
    assert_eq!((s.query_rule.c, s.query_rule.k), (Some(0.2), Some(3)));
}

#[test]
fn kernels_are_a_session_setting_and_nonsense_is_refused() {
    let s = Settings::from_json(json!({"kernels": "portable"})).unwrap();
    assert_eq!(s.session().unwrap().kernels, Some(KernelPath::Portable));
    assert_eq!(s.session_keys_set(), vec!["kernels"]);
    // Not the algorithm's: the run builds with it set.
    dref(Task::Reaching, &s).unwrap();
    assert_eq!(Settings::default().session().unwrap().kernels, None);
    for bad in [json!({"kernels": "fast"}), json!({"kernels": 2})] {
        let err = Settings::from_json(bad.clone()).unwrap_err();
        assert!(err.to_string().contains("kernels"), "{bad}: {err}");
    }
}

#[test]
fn teacher_faults_and_a_persons_pace_reach_the_runs() {
    let s = Settings::from_json(json!({
        "teacher_beta": 5, "teacher_gamma": 0.9, "teacher_error": 0.2,
        "teacher_skip": -1.5, "teacher_equal": 0.01, "max_queries_per_minute": 6, "pace_hz": 10
    }))
    .unwrap();
    let c = dref(Task::Reaching, &s).unwrap();
    assert_eq!(c.teacher.beta, Some(5.0));
    assert_eq!((c.teacher.gamma, c.teacher.error), (Some(0.9), 0.2));
    assert_eq!((c.teacher.skip, c.teacher.equal), (Some(-1.5), 0.01));
    let pace = c.human_pace.unwrap();
    assert_eq!((pace.max_per_minute, pace.steps_per_minute), (6, 600));
    let p = Settings::from_json(json!({"teacher_beta": 2, "teacher_error": 0.1}))
        .unwrap()
        .preference(Task::Placing, QueryMethod::Drpl, 0)
        .unwrap();
    assert_eq!((p.teacher.beta, p.teacher.error), (Some(2.0), 0.1));
    // The words for "no fault", and 0 for "no limit", leave the paper's runs as they were.
    let perfect = Settings::from_json(json!({
        "teacher_beta": "rational", "teacher_skip": "never", "teacher_gamma": 1,
        "teacher_error": 0, "max_queries_per_minute": 0
    }))
    .unwrap();
    assert_eq!(
        dref(Task::Reaching, &perfect).unwrap(),
        EvaluativeRunConfig::new(Task::Reaching, EvaluativeMethod::Dref, 0)
    );
    for bad in [
        json!({"teacher_error": 1.0}),
        json!({"teacher_gamma": 0}),
        json!({"teacher_gamma": 1.5}),
        json!({"teacher_beta": -2}),
    ] {
        let s = Settings::from_json(bad.clone()).unwrap();
        assert!(dref(Task::Reaching, &s).is_err(), "{bad}");
    }
    assert!(Settings::from_json(json!({"teacher_beta": "sometimes"})).is_err());
    let paced = Settings::from_json(json!({"max_queries_per_minute": 3})).unwrap();
    assert!(
        paced
            .preference(Task::Reaching, QueryMethod::Drpl, 0)
            .is_err()
    );
}

#[test]
fn feedback_until_stops_the_questions_of_any_evaluative_run_and_zero_never_does() {
    let until = |v: serde_json::Value, method: &str| {
        let s = Settings::from_json(v).unwrap();
        let m: EvaluativeMethod = method.parse().unwrap();
        s.evaluative(Task::LunarLander, m, 0)
            .map(|c| c.feedback_until)
    };
    assert_eq!(
        until(json!({"feedback_until": 15000}), "ef-100"),
        Ok(Some(15000))
    );
    assert_eq!(
        until(json!({"feedback_until": 15000}), "dref"),
        Ok(Some(15000))
    );
    assert_eq!(until(json!({"feedback_until": 0}), "ef-100"), Ok(None));
    assert_eq!(until(json!({}), "ef-100"), Ok(None));
    assert!(Settings::from_json(json!({"feedback_until": -1})).is_err());
    assert!(Settings::from_json(json!({"feedback_until": "soon"})).is_err());
    let cut = Settings::from_json(json!({"feedback_until": 100})).unwrap();
    assert!(matches!(
        cut.preference(Task::Reaching, QueryMethod::Drpl, 0),
        Err(SettingsError::WrongFamily { .. })
    ));
}

#[test]
fn answers_per_query_needs_a_rule_and_the_rule_needs_several_answers() {
    let session = |v: serde_json::Value| Settings::from_json(v).unwrap().session();
    let s = session(json!({"answers_per_query": 3, "combine": "mean"})).unwrap();
    assert_eq!((s.answers_per_query, s.combine), (3, Combine::Mean));
    assert_eq!(session(json!({})).unwrap().combine, Combine::First);
    for bad in [
        json!({"answers_per_query": 0}),
        json!({"answers_per_query": 2}),
        json!({"answers_per_query": 2, "combine": "first"}),
        json!({"combine": "majority"}),
    ] {
        assert!(session(bad.clone()).is_err(), "{bad}");
    }
    assert_eq!(
        Settings::from_json(json!({"answers_per_query": 2, "combine": "each"}))
            .unwrap()
            .session_keys_set(),
        vec!["answers_per_query", "combine"]
    );
}

#[test]
fn the_keys_are_the_sections_fields_each_once() {
    let keys = Settings::keys();
    for (i, key) in keys.iter().enumerate() {
        assert!(!keys[..i].contains(key), "{key} is in two sections");
    }
    // The list the unknown-key error gives is this one.
    let e = Settings::from_pairs([("no_such_key", "1")])
        .unwrap_err()
        .to_string();
    assert!(e.ends_with(&format!("`{}`", keys.last().unwrap())), "{e}");
}
