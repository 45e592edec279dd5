//! Grid planning: which runs, with which command lines, in which order.

use std::path::Path;

use super::*;

fn config(figure: Figure, methods: &[&str]) -> GridConfig {
    GridConfig {
        figure,
        tasks: vec![Task::Reaching, Task::LunarLander],
        seeds: 2,
        steps: None,
        queries: DEFAULT_QUERIES,
        methods: methods.iter().map(|m| m.to_string()).collect(),
        sets: vec!["batch_size=64".into()],
        out: "grid".into(),
    }
}

#[test]
fn report_grid_train_command_line_and_directory() {
    let c = config(Figure::Fig3, &["dref"]);
    let run = c.spec(Task::LunarLander, "ef-50", 3);
    assert_eq!(run.dir, Path::new("grid/lunar-lander/ef-50/seed3"));
    assert_eq!(
        run.args,
        [
            "train",
            "--task",
            "lunar-lander",
            "--method",
            "ef-50",
            "--steps",
            "150000",
            "--seed",
            "3",
            "--out",
            "grid/lunar-lander/ef-50/seed3",
            "--set",
            "batch_size=64",
        ]
    );
    assert_eq!(run.label(), "lunar-lander/ef-50/seed3");
    // The paper's budgets unless --steps says otherwise.
    assert_eq!(c.steps_for(Task::Reaching), 100_000);
    let short = GridConfig {
        steps: Some(2_000),
        ..c
    };
    assert_eq!(short.steps_for(Task::LunarLander), 2_000);
}

#[test]
fn report_grid_prefs_command_line() {
    let c = config(Figure::Fig5, &["drpl"]);
    let run = c.spec(Task::Reaching, "drpl-ss", 0);
    assert_eq!(
        run.args[..9],
        [
            "prefs",
            "--task",
            "reaching",
            "--method",
            "drpl-ss",
            "--queries",
            "40",
            "--seed",
            "0"
        ]
    );
}

#[test]
fn report_grid_runs_dref_first_and_holds_back_the_matched_baseline() {
    let c = config(Figure::Fig3, &["sac", "ef-dref", "dref"]);
    let labels: Vec<String> = c.initial_runs().iter().map(RunSpec::label).collect();
    assert_eq!(
        labels,
        [
            "reaching/dref/seed0",
            "reaching/dref/seed1",
            "lunar-lander/dref/seed0",
            "lunar-lander/dref/seed1",
            "reaching/sac/seed0",
            "reaching/sac/seed1",
            "lunar-lander/sac/seed0",
            "lunar-lander/sac/seed1",
        ]
    );
    assert_eq!(c.matched_rows(), [(MATCHED_EF, "dref")]);
    assert!(c.has("dref") && !c.has(DREF_AUTHORS));
    assert_eq!(c.total_runs(), 12);
    let matched: Vec<String> = c
        .matched_runs(Task::Reaching, 1.63)
        .iter()
        .map(RunSpec::label)
        .collect();
    assert_eq!(
        matched,
        ["reaching/ef-1.63/seed0", "reaching/ef-1.63/seed1"]
    );
}

#[test]
fn report_grid_rejects_unknown_methods_before_running_anything() {
    assert!(
        config(Figure::Fig3, &["dref", "ef-12.5", "ef-dref"])
            .validate()
            .is_ok()
    );
    let err = config(Figure::Fig3, &["drpl"]).validate().unwrap_err();
    assert_eq!(
        err,
        GridError::UnknownMethod {
            method: "drpl".into(),
            figure: Figure::Fig3
        }
    );
    let err = err.to_string();
    assert!(err.contains("unknown method \"drpl\" for fig3"), "{err}");
    assert!(config(Figure::Fig3, &["ef-150"]).validate().is_err());
    assert!(config(Figure::Fig5, &["dref"]).validate().is_err());
    assert!(config(Figure::Fig5, &[]).validate().is_err());
    assert_eq!(Figure::Fig3.default_methods().len(), 6);
}

#[test]
fn report_grid_extra_rows_are_train_runs_with_their_settings() {
    let c = config(Figure::Fig3, &["dref-masked", "sac-r100"]);
    c.validate().unwrap();
    let masked = c.spec(Task::Reaching, "dref-masked", 1);
    assert_eq!(masked.dir, Path::new("grid/reaching/dref-masked/seed1"));
    assert_eq!(
        masked.args[..5],
        ["train", "--task", "reaching", "--method", "dref-authors"]
    );
    let sets: Vec<&str> = masked
        .args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].as_str())
        .collect();
    assert_eq!(sets, ["human_critic_mask=true", "batch_size=64"]);
    let fair = c.spec(Task::Reaching, "sac-r100", 0);
    assert_eq!(fair.args[4], "sac");
    assert!(!fair.args.contains(&"reward_scale=0.1".to_string()));
}
