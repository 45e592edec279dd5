use serde_json::json;

use super::report::build;
use super::simulate::Score;
use super::*;
use crate::guidance::human_pace::{HumanPace, PEOPLE_QUERIES_PER_MINUTE};

fn study() -> Value {
    json!({
        "title": "Reaching with people",
        "conditions": [
            {"name": "dref", "task": "reaching", "method": "dref"},
            {"name": "ef-50", "task": "reaching", "method": "ef-50",
             "params": {"hidden": [16, 16]}},
            {"name": "sac", "task": "reaching", "method": "sac"}
        ],
        "budget": {"steps": 3000},
        "seed": 9,
        "main_contrast": ["dref", "sac"]
    })
}

fn pilot(value: Value, overrides: Overrides) -> Result<PilotSpec, String> {
    let file = PilotFile::parse(&value.to_string(), Format::Json).map_err(|e| e.to_string())?;
    let study = file.study.clone();
    PilotSpec::new(file, study, overrides).map_err(|e| e.to_string())
}

#[test]
fn a_pilot_file_in_toml_gets_the_defaults() {
    let text = r#"
[teachers]
teacher_beta = [0.5, 5.0]
teacher_error = [0.0, 0.2]

[study]
title = "Two methods"
budget = { steps = 300 }

[[study.conditions]]
name = "ef-100"
task = "reaching"
method = "ef-100"

[[study.conditions]]
name = "sac"
task = "reaching"
method = "sac"
"#;
    let file = PilotFile::parse(text, Format::Toml).unwrap();
    assert_eq!(file.study_path(), None);
    let study = file.study.clone();
    let spec = PilotSpec::new(file, study, Overrides::default()).unwrap();
    assert_eq!(spec.ns, DEFAULT_NS);
    assert_eq!(spec.participants, 16);
    assert_eq!(spec.studies, 1000);
    assert_eq!(spec.alpha, 0.05);
    assert_eq!(spec.seed, 0);
    assert_eq!(spec.contrast(), [0, 1]);
    assert_eq!(spec.teachers.ranges().len(), 2);
    // The study may be a file's path instead.
    let by_path = PilotFile::parse("study = \"study.json\"\n", Format::Toml).unwrap();
    assert_eq!(by_path.study_path(), Some("study.json"));
}

#[test]
fn the_command_line_wins_over_the_file_and_sizes_are_sorted() {
    let spec = pilot(
        json!({"study": study(), "ns": [8, 4, 8], "participants": 6, "studies": 50, "seed": 3}),
        Overrides {
            participants: Some(5),
            ns: None,
            studies: Some(20),
            seed: None,
        },
    )
    .unwrap();
    assert_eq!(spec.ns, [4, 8]);
    assert_eq!((spec.participants, spec.studies, spec.seed), (5, 20, 3));
    assert_eq!(spec.contrast(), [0, 2]);
    // Without a seed of its own the pilot takes the study's.
    assert_eq!(
        pilot(json!({"study": study()}), Overrides::default())
            .unwrap()
            .seed,
        9
    );
}

#[test]
fn each_refusal_names_the_field() {
    let cases = [
        (
            json!({"study": study(), "ns": []}),
            "ns: give at least one study size",
        ),
        (
            json!({"study": study(), "ns": [1, 4]}),
            "ns: a study has 2 to 1000",
        ),
        (
            json!({"study": study(), "participants": 1}),
            "participants: the pool has 2 to",
        ),
        (json!({"study": study(), "studies": 0}), "studies: 1 to"),
        (
            json!({"study": study(), "alpha": 1.5}),
            "alpha: expected a level in (0, 1)",
        ),
        (
            json!({"study": study(), "teacher": {}}),
            "unknown field `teacher`",
        ),
        (
            json!({"study": study(), "teachers": {"teacher_temper": [0, 1]}}),
            "teachers.teacher_temper: not a teacher setting",
        ),
        (json!({"teachers": {}}), "missing field `study`"),
    ];
    for (value, expected) in cases {
        let err = pilot(value.clone(), Overrides::default()).unwrap_err();
        assert!(err.contains(expected), "{value}: {err}");
    }
    let mut bad = study();
    bad["conditions"][2]["name"] = json!("dref");
    let err = pilot(json!({"study": bad}), Overrides::default()).unwrap_err();
    assert_eq!(
        err,
        "study.conditions: condition \"dref\" appears more than once"
    );
    let mut bad = study();
    bad["conditions"][0]["method"] = json!("dreff");
    let err = pilot(json!({"study": bad}), Overrides::default()).unwrap_err();
    assert!(
        err.starts_with("study.conditions[0].method: unknown method"),
        "{err}"
    );
    let err = PilotFile::parse("study = {", Format::Toml)
        .unwrap_err()
        .to_string();
    assert!(!err.is_empty());
    assert_eq!(Format::of_extension("TOML"), Some(Format::Toml));
    assert_eq!(Format::of_extension("yaml"), None);
}

#[test]
fn every_participant_trains_every_condition_with_their_own_teacher_in_their_order() {
    let spec = pilot(
        json!({"study": study(), "participants": 4, "teachers": {
            "teacher_error": [0.0, 0.2], "teacher_beta": 2.0
        }}),
        Overrides::default(),
    )
    .unwrap();
    let runs = spec.runs().unwrap();
    assert_eq!(runs.len(), 12);
    let design = spec.study.design();
    for (p, chunk) in runs.chunks(3).enumerate() {
        let order: Vec<&str> = chunk
            .iter()
            .map(|r| spec.study.conditions[r.condition].name.as_str())
            .collect();
        assert_eq!(order, design.order_for(p));
        let drawn = spec.teacher(p)["teacher_error"].as_f64().unwrap();
        for (position, run) in chunk.iter().enumerate() {
            assert_eq!(
                (run.participant, run.position, run.budget),
                (p, position, 3000)
            );
            assert_eq!(run.seed, chunk[0].seed);
            let RunConfig::Evaluative(c) = &run.config else {
                panic!("evaluative")
            };
            // The draw is added to the condition's own settings.
            assert_eq!(c.teacher.error, drawn);
            assert_eq!(c.teacher.beta, Some(2.0));
            assert_eq!(c.seed, run.seed);
            let name = spec.study.conditions[run.condition].name.as_str();
            if name == "ef-50" {
                assert_eq!(c.sac.hidden, vec![16, 16]);
            }
            // DREF asks at a person's pace, as in the study; the others have none.
            let pace = (name == "dref").then(|| HumanPace::new(PEOPLE_QUERIES_PER_MINUTE, 20.0));
            assert_eq!(c.human_pace, pace, "{name}");
        }
    }
    assert_ne!(runs[0].seed, runs[3].seed);
}

#[test]
fn a_session_that_cannot_be_simulated_or_run_with_people_is_refused_with_its_condition() {
    let mut s = study();
    s["conditions"][1]["params"] = json!({"answers_per_query": 3, "combine": "majority"});
    let spec = pilot(json!({"study": s, "participants": 2}), Overrides::default()).unwrap();
    let err = spec.runs().unwrap_err().to_string();
    assert!(
        err.starts_with(
            "study.conditions[1] (ef-50), simulated participant 0: answers_per_query = 3"
        ),
        "{err}"
    );
    // Teacher settings belong in the pilot's `teachers`, not in a study people will answer.
    let mut s = study();
    s["conditions"][2]["params"] = json!({"teacher_error": 0.3});
    let spec = pilot(json!({"study": s, "participants": 2}), Overrides::default()).unwrap();
    let err = spec.runs().unwrap_err().to_string();
    assert!(
        err.starts_with("study.conditions[2] (sac), simulated participant 0: teacher_* settings"),
        "{err}"
    );
}

#[test]
fn the_report_holds_every_participant_and_a_power_row_per_size() {
    let spec = pilot(
        json!({"study": study(), "participants": 6, "ns": [4, 6], "studies": 100,
               "teachers": {"teacher_error": [0.0, 0.2]}}),
        Overrides::default(),
    )
    .unwrap();
    let runs = spec.runs().unwrap();
    // dref always far above sac: a huge effect.
    let scores: Vec<Score> = runs
        .iter()
        .map(|r| Score {
            score: [1000.0, 500.0, 10.0][r.condition] + r.participant as f64,
            feedback_count: 30,
            feedback_percent: Some(1.0),
            episodes: 5,
        })
        .collect();
    let report = build(&spec, &runs, &scores);
    assert_eq!(report.measure, "cumulative_reward");
    assert_eq!(report.power.len(), 2);
    assert_eq!(report.power[0].bootstrap.power, 0.0);
    assert_eq!(report.power[1].subsample.unwrap().power, 1.0);
    assert!(report.power[1].friedman_bootstrap.is_some());
    assert_eq!(report.pool[0].score.mean, 1002.5);
    assert_eq!(report.pool_contrast.difference.mean, 990.0);
    assert_eq!(report.pool_participants.len(), 6);
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.starts_with("n = 4: the exact"))
    );
    let md = report.markdown();
    assert!(md.contains("| 6 | 1.000 ± 0.000 | 1.000 ± 0.000 |"), "{md}");
    assert!(md.contains("Friedman, bootstrap"));
    assert!(md.contains("uniform in [0, 0.2]"));
    let csv = report.participants_csv();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 1 + 18);
    assert_eq!(
        lines[0],
        "participant,seed,position,condition,teacher_beta,teacher_gamma,teacher_error,teacher_skip,\
         teacher_equal,cumulative_reward,feedback_count,feedback_percent,episodes"
    );
    // Participant 0 meets the conditions in the design's first order.
    assert!(
        lines[1].starts_with(&format!("0,{},0,dref,,,0.", runs[0].seed)),
        "{}",
        lines[1]
    );
    let json = serde_json::to_value(&report).unwrap();
    assert_eq!(json["teachers"], json!({"teacher_error": [0.0, 0.2]}));
}
