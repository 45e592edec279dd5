//! `dualrep prefs` end to end on a tiny budget: the files `reproduce fig5` reads (through the
//! report's own reader and the grid's own command line), the per-query log, determinism, and
//! clear errors on bad input. These tests check the structure of a run; how well it learns is
//! Figure 5's (docs/results/fig5).

use std::path::Path;
use std::process::Output;

use dualrep::report::grid::{Figure, GridConfig};
use dualrep::report::run_files::{RunKey, load_prefs_runs, read_prefs_run};
use dualrep::scene_graph::SceneGraph;
use dualrep::sim::Task;

use crate::support::cli;

use cli::ok;

fn dualrep(args: &[&str]) -> Output {
    cli::dualrep_in(args, None)
}

fn prefs(task: &str, method: &str, queries: u32, seed: u64, out: &Path) -> serde_json::Value {
    ok(&dualrep(&[
        "prefs",
        "--task",
        task,
        "--method",
        method,
        "--queries",
        &queries.to_string(),
        "--seed",
        &seed.to_string(),
        "--out",
        out.to_str().unwrap(),
        "--trajectories",
        "8",
    ]))
}

fn jsonl(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn every_method_writes_what_the_report_reads() {
    let dir = tempfile::tempdir().unwrap();
    for (task, method) in [
        ("reaching", "drpl"),
        ("placing", "drpl-ss"),
        ("lunar-lander", "fragment"),
        ("reaching", "full"),
        ("placing", "drpl-mi"),
    ] {
        let out = dir.path().join(format!("{task}-{method}"));
        let summary = prefs(task, method, 4, 3, &out);
        let t: Task = task.parse().unwrap();
        let dim = dualrep::guidance::drpl::features::dim(t);
        assert_eq!(summary["task"], task);
        assert_eq!(summary["method"], method);
        assert_eq!(
            (summary["seed"].as_u64(), summary["queries"].as_u64()),
            (Some(3), Some(4))
        );
        assert_eq!(summary["trajectories"], 8);
        // DRPL-MI is DRPL with the mutual-information pick; the others pick uniformly.
        let acquisition = if method == "drpl-mi" {
            "mutual_information"
        } else {
            "uniform"
        };
        assert_eq!(summary["config"]["acquisition"], acquisition, "{method}");
        assert_eq!(summary["theta_true"].as_array().unwrap().len(), dim);
        assert_eq!(summary["feature_names"].as_array().unwrap().len(), dim);
        for field in [
            "final_alignment",
            "final_alignment_of_mean",
            "mean_segment_length",
            "belief_update_ms_median",
        ] {
            assert!(
                summary[field].is_number(),
                "{task} {method}: {field} in {summary}"
            );
        }
        assert!(summary["segments"].as_u64().unwrap() > 0);

        // The report's reader accepts the run; rows 0 (the prior) to 4.
        let key = RunKey {
            task: t,
            method: method.into(),
            seed: 3,
        };
        let run = read_prefs_run(key, &out).unwrap();
        let rows: Vec<u32> = run.alignment.iter().map(|r| r.query).collect();
        assert_eq!(rows, vec![0, 1, 2, 3, 4]);
        for r in &run.alignment {
            assert!((-1.0..=1.0).contains(&r.alignment), "{r:?}");
            assert!((-1.0..=1.0).contains(&r.alignment_of_mean), "{r:?}");
        }
        // (serde_json's float parsing may be one ulp off the csv's.)
        assert!((run.summary.final_alignment - run.alignment[4].alignment).abs() < 1e-12);

        let lines = jsonl(&out.join("queries.jsonl"));
        assert_eq!(lines.len(), 4);
        for (k, line) in lines.iter().enumerate() {
            assert_eq!(line["query"], k + 1);
            assert!(["left", "right"].contains(&line["answer"].as_str().unwrap()));
            assert!((-1.0..=1.0).contains(&line["alignment"].as_f64().unwrap()));
            for side in ["left", "right"] {
                assert_eq!(line[side]["features"].as_array().unwrap().len(), dim);
                assert_eq!(line[side]["raw_features"].as_array().unwrap().len(), dim);
                let g = &line[side]["abstract_state"];
                match method {
                    "drpl" | "drpl-mi" | "drpl-ss" => {
                        let bits = g.as_str().unwrap();
                        assert_eq!(bits.len(), SceneGraph::for_task(t).dim());
                        assert!(bits.chars().all(|c| c == '0' || c == '1'));
                    }
                    _ => assert!(g.is_null()),
                }
            }
            if method == "drpl-ss" {
                assert_eq!(
                    line["left"]["abstract_state"],
                    line["right"]["abstract_state"]
                );
            }
            if method == "drpl" || method == "drpl-mi" {
                // The two states differ in the predicate the line names.
                let names: Vec<_> = SceneGraph::for_task(t)
                    .predicates()
                    .iter()
                    .map(|p| p.name)
                    .collect();
                let i = names
                    .iter()
                    .position(|n| *n == line["predicate"].as_str().unwrap())
                    .unwrap();
                let bit = |s: &str| line[s]["abstract_state"].as_str().unwrap().as_bytes()[i];
                assert_ne!(bit("left"), bit("right"));
            }
        }
    }
}

#[test]
fn the_grid_command_line_runs_and_is_found() {
    let dir = tempfile::tempdir().unwrap();
    let grid = GridConfig {
        figure: Figure::Fig5,
        tasks: vec![Task::Placing],
        seeds: 1,
        steps: None,
        queries: 2,
        methods: vec!["drpl".into()],
        sets: vec!["trajectories=6".into(), "samples=20".into()],
        out: dir.path().to_path_buf(),
    };
    let spec = grid.spec(Task::Placing, "drpl", 0);
    let args: Vec<&str> = spec.args.iter().map(String::as_str).collect();
    let summary = ok(&dualrep(&args));
    assert_eq!(summary["trajectories"], 6);
    assert_eq!(summary["config"]["belief"]["samples"], 20);
    let runs = load_prefs_runs(dir.path()).unwrap();
    assert_eq!(runs.len(), 1);
    assert_eq!(runs[0].summary.queries, 2);
    assert_eq!(runs[0].alignment.len(), 3);
}

#[test]
fn a_seed_reproduces_its_run() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        dir.path().join("a"),
        dir.path().join("b"),
        dir.path().join("c"),
    );
    let sa = prefs("lunar-lander", "drpl", 5, 7, &a);
    let sb = prefs("lunar-lander", "drpl", 5, 7, &b);
    let sc = prefs("lunar-lander", "drpl", 5, 8, &c);
    assert_eq!(sa["theta_true"], sb["theta_true"]);
    assert_ne!(sa["theta_true"], sc["theta_true"]);
    let read = |p: &Path| std::fs::read_to_string(p.join("alignment.csv")).unwrap();
    assert_eq!(read(&a), read(&b));
    // The same pairs and answers (update times aside).
    let strip = |p: &Path| {
        jsonl(&p.join("queries.jsonl"))
            .into_iter()
            .map(|mut l| {
                l.as_object_mut().unwrap().remove("belief_update_ms");
                l
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(strip(&a), strip(&b));
    assert_ne!(strip(&a), strip(&c));
}

#[test]
fn bad_arguments_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let out = out.to_str().unwrap();
    let base = ["prefs", "--task", "reaching", "--out", out];
    for (extra, expect) in [
        (vec!["--method", "drpl-x"], "drpl-x"),
        (vec!["--method", "drpl", "--queries", "0"], "--queries"),
        (
            vec!["--method", "drpl", "--trajectories", "1"],
            "--trajectories",
        ),
        (
            vec!["--method", "drpl", "--acquisition", "greedy"],
            "expected uniform or mutual-information",
        ),
        (
            vec!["--method", "drpl", "--set", "hidden=3"],
            "hidden is a setting of evaluative methods",
        ),
        (vec!["--method", "drpl", "--set", "beta=x"], "beta"),
        (
            vec!["--method", "drpl", "--set", "no_such=1"],
            "unknown field `no_such`",
        ),
    ] {
        let args: Vec<&str> = base.iter().copied().chain(extra.iter().copied()).collect();
        let stderr = cli::refused(&dualrep(&args));
        assert!(stderr.contains(expect), "{extra:?}: {stderr}");
    }
    let o = dualrep(&["prefs", "--task", "mars", "--method", "drpl", "--out", out]);
    assert!(cli::refused(&o).contains("unknown task"));
    assert!(!Path::new(out).join("summary.json").exists());
}

#[test]
fn mutual_information_acquisition_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("mi");
    let summary = ok(&dualrep(&[
        "prefs",
        "--task",
        "reaching",
        "--method",
        "drpl",
        "--queries",
        "3",
        "--out",
        out.to_str().unwrap(),
        "--trajectories",
        "6",
        "--acquisition",
        "mutual-information",
    ]));
    assert_eq!(summary["config"]["acquisition"], "mutual_information");
    assert_eq!(summary["queries"], 3);
}
