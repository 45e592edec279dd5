//! Tests of `robustness`: the grid's runs and command lines, labels, aggregation and table.

use super::*;
use crate::report::run_files::{PrefsSummary, RunKey, TrainSummary};

fn config() -> RobustnessConfig {
    RobustnessConfig {
        tasks: vec![Task::Reaching, Task::Placing],
        seeds: 2,
        steps: 1000,
        queries: 5,
        train_methods: vec!["dref".into(), "ef-100".into()],
        prefs_methods: vec!["drpl".into()],
        errors: vec![0, 20],
        betas: vec![Some(2.0), None],
        sets: vec!["hidden=8,8".into()],
        out: PathBuf::from("/g"),
    }
}

#[test]
fn the_grid_sweeps_errors_for_train_and_betas_for_prefs() {
    let runs = config().runs();
    assert_eq!(runs.len(), 2 * 2 * 2 * 2 + 2 * 2 * 2);
    // The cheap preference runs come first.
    assert!(runs[..8].iter().all(|r| r.args[0] == "prefs"));
    let err = runs
        .iter()
        .find(|r| r.method == "ef-100-err20" && r.seed == 1 && r.task == Task::Placing)
        .unwrap();
    assert_eq!(err.dir, PathBuf::from("/g/placing/ef-100-err20/seed1"));
    let args = err.args.join(" ");
    assert!(
        args.starts_with("train --task placing --method ef-100 --steps 1000 --seed 1"),
        "{args}"
    );
    assert!(
        args.ends_with("--set teacher_error=0.2 --set hidden=8,8"),
        "{args}"
    );
    // The perfect teachers get no fault setting at all.
    let clean = runs.iter().find(|r| r.method == "dref-err0").unwrap();
    assert!(!clean.args.join(" ").contains("teacher"));
    let beta = runs.iter().find(|r| r.method == "drpl-beta2").unwrap();
    assert!(
        beta.args
            .join(" ")
            .contains("prefs --task reaching --method drpl --queries 5")
    );
    assert!(beta.args.join(" ").contains("--set teacher_beta=2"));
    let rational = runs.iter().find(|r| r.method == "drpl-rational").unwrap();
    assert!(!rational.args.join(" ").contains("teacher"));
}

#[test]
fn labels_parse_back() {
    assert_eq!(
        parse_label("dref-err10"),
        Some(("dref".into(), Level::Error(10)))
    );
    assert_eq!(
        parse_label("ef-100-err0"),
        Some(("ef-100".into(), Level::Error(0)))
    );
    assert_eq!(
        parse_label("drpl-ss-beta0.5"),
        Some(("drpl-ss".into(), Level::Beta(Some(0.5))))
    );
    assert_eq!(
        parse_label("drpl-rational"),
        Some(("drpl".into(), Level::Beta(None)))
    );
    assert_eq!(parse_label("dref"), None);
    assert_eq!(parse_label("ef-100"), None);
}

#[test]
fn bad_grids_are_refused() {
    let mut c = config();
    c.errors = vec![100];
    assert!(c.validate().is_err());
    let mut c = config();
    c.betas = vec![Some(-1.0)];
    assert!(c.validate().is_err());
    let mut c = config();
    c.train_methods.clear();
    c.prefs_methods.clear();
    assert!(c.validate().is_err());
    assert!(config().validate().is_ok());
}

fn train(task: Task, label: &str, seed: u64, cumulative: f64) -> TrainRun {
    TrainRun {
        key: RunKey {
            task,
            method: label.into(),
            seed,
        },
        episodes: Vec::new(),
        summary: TrainSummary {
            task: task.id().into(),
            method: label.into(),
            seed,
            steps: 1000,
            cumulative_return: cumulative,
            feedback_count: 10,
            feedback_fraction: 0.01,
            final_mean_return: 1.0,
            wall_seconds: None,
            updates_per_second: None,
            longest_flood_after_2k: None,
            config: Default::default(),
        },
    }
}

fn prefs(task: Task, label: &str, seed: u64, alignment: f64) -> PrefsRun {
    PrefsRun {
        key: RunKey {
            task,
            method: label.into(),
            seed,
        },
        alignment: Vec::new(),
        summary: PrefsSummary {
            task: task.id().into(),
            method: "drpl".into(),
            seed,
            queries: 5,
            final_alignment: alignment,
            mean_segment_length: None,
            belief_update_ms_median: None,
        },
    }
}

#[test]
fn results_aggregate_per_cell_and_the_table_gives_ratios_to_ef_100() {
    let train_runs = vec![
        train(Task::Reaching, "dref-err0", 0, 100.0),
        train(Task::Reaching, "dref-err0", 1, 120.0),
        train(Task::Reaching, "ef-100-err0", 0, 100.0),
        train(Task::Reaching, "ef-100-err0", 1, 100.0),
        train(Task::Reaching, "dref-err20", 0, 50.0),
        train(Task::Reaching, "ef-100-err20", 0, 25.0),
    ];
    let prefs_runs = vec![
        prefs(Task::Reaching, "drpl-rational", 0, 0.9),
        prefs(Task::Reaching, "drpl-beta2", 0, 0.5),
        prefs(Task::Reaching, "drpl-beta2", 1, 0.7),
    ];
    let tasks = aggregate(&train_runs, &prefs_runs);
    assert_eq!(tasks.len(), 1);
    let t = &tasks[0];
    let dref0 = t
        .errors
        .iter()
        .find(|c| c.method == "dref" && c.error == 0)
        .unwrap();
    assert_eq!((dref0.cumulative.mean, dref0.cumulative.n), (110.0, 2));
    assert_eq!(t.betas.len(), 2);
    assert_eq!(t.betas[0].beta, Some(2.0));
    assert!((t.betas[0].final_alignment.mean - 0.6).abs() < 1e-12);
    assert_eq!(t.betas[1].beta, None, "the rational teacher last");
    let text = table(&tasks);
    assert!(
        text.contains("| 0 % | DREF | 2 | 110 ± 10 | 1.10 |"),
        "{text}"
    );
    assert!(
        text.contains("| 20 % | DREF | 1 | 50 ± 0 | 2.00 |"),
        "{text}"
    );
    assert!(
        text.contains("| rational | DRPL | 1 | 0.900 ± 0.000 |"),
        "{text}"
    );
}
