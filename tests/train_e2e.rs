//! `dualrep expert` then `dualrep train` end to end on a tiny budget (seconds, not minutes):
//! the files `reproduce` reads, the feedback accounting, and clear errors on bad input.

use std::path::Path;
use std::process::Output;

use crate::support::cli;

use cli::{ok, running_once};

fn dualrep(args: &[&str], dir: &Path) -> Output {
    cli::dualrep_in(args, Some(dir))
}

const TINY: [&str; 4] = ["--set", "hidden=16,16", "--set", "batch_size=32"];

/// Train a tiny expert for `task` into `d/models/<task>.safetensors`; its note.
fn tiny_expert(d: &Path, task: &str, steps: &str, eval_episodes: &str) -> serde_json::Value {
    let out = format!("models/{task}.safetensors");
    let mut args = vec![
        "expert",
        "--task",
        task,
        "--steps",
        steps,
        "--eval-episodes",
        eval_episodes,
        "--out",
        &out,
    ];
    args.extend(TINY);
    ok(&dualrep(&args, d))
}

#[test]
fn an_expert_trains_and_drives_dref_and_ef_runs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let note = tiny_expert(d, "reaching", "300", "2");
    assert_eq!(note["steps"], 300);
    assert!(d.join("models/reaching.safetensors").is_file());
    assert!(d.join("models/reaching.json").is_file());

    for (method, steps) in [("dref", 400), ("ef-100", 150), ("sac", 150)] {
        let out_dir = format!("runs/{method}");
        let steps_s = steps.to_string();
        let mut args = vec![
            "train", "--task", "reaching", "--method", method, "--steps", &steps_s, "--seed", "4",
            "--out", &out_dir,
        ];
        args.extend(TINY);
        let summary = ok(&dualrep(&args, d));
        let written: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join(&out_dir).join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(written["steps"], steps);
        assert_eq!(written["cumulative_return"], summary["cumulative_return"]);
        for field in [
            "task",
            "method",
            "seed",
            "feedback_count",
            "feedback_fraction",
            "final_mean_return",
            "wall_seconds",
            "updates_per_second",
            "threads",
            "longest_flood",
            "longest_flood_after_2k",
        ] {
            assert!(!written[field].is_null(), "{method}: {field} missing");
        }
        let kernels = written["kernels"].as_str().unwrap_or_default();
        assert!(
            ["portable", "avx2", "avx512"].contains(&kernels),
            "{method}: kernels {kernels:?}"
        );
        let fraction = written["feedback_fraction"].as_f64().unwrap();
        match method {
            "ef-100" => assert_eq!(fraction, 1.0),
            "sac" => assert_eq!(fraction, 0.0),
            _ => assert!(fraction > 0.0 && fraction <= 1.0),
        }
        let csv = std::fs::read_to_string(d.join(&out_dir).join("metrics.csv")).unwrap();
        let mut lines = csv.lines();
        assert_eq!(
            lines.next(),
            Some(
                "step,episode,return,length,outcome,cumulative_return,feedback_count,\
                 feedback_fraction,states_with_feedback,steps_since_query,longest_flood"
            )
        );
        let mut last_cumulative = 0.0;
        let mut last_step = 0.0;
        for line in lines {
            let cols: Vec<&str> = line.split(',').collect();
            assert_eq!(cols.len(), 11, "{line}");
            assert!(
                ["success", "failure", "time_limit"].contains(&cols[4]),
                "outcome {line}"
            );
            let num = |i: usize| -> f64 { cols[i].parse().unwrap() };
            // Only DREF ranks abstract states; it has had feedback in at least one by its
            // first episode's end (it asks at its first step).
            assert_eq!(num(8) > 0.0, method == "dref", "{method}: {line}");
            // The rule's pacing: a silence no longer than the run, a flood no longer than the
            // steps so far, and none for plain SAC (which never asks).
            assert!(num(9) <= num(0), "steps since a query {line}");
            assert!(num(10) <= num(0), "flood {line}");
            assert_eq!(num(10) == 0.0, method == "sac", "{method}: {line}");
            // The length is the steps since the previous episode ended.
            assert_eq!(num(3), num(0) - last_step, "length {line}");
            assert_eq!(num(2) == 100.0, cols[4] == "success", "{line}");
            assert!(
                (num(5) - (last_cumulative + num(2))).abs() < 1e-6,
                "cumulative column adds returns"
            );
            last_cumulative = num(5);
            last_step = num(0);
        }
        // The learner's curves: a row per episode at the same step, the means of that
        // episode's updates (one a step from the first); the human critic's loss is 0 without
        // one (SAC), and a temperature is always positive.
        let learner = std::fs::read_to_string(d.join(&out_dir).join("learner.csv")).unwrap();
        let mut rows = learner.lines();
        assert_eq!(
            rows.next(),
            Some("step,episode,updates,critic_loss,actor_loss,human_critic_loss,ent_coef")
        );
        let rows: Vec<Vec<f64>> = rows
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        let episodes: Vec<Vec<&str>> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect())
            .collect();
        assert_eq!(
            rows.len(),
            episodes.len(),
            "{method}: a learner row per episode"
        );
        for (row, episode) in rows.iter().zip(&episodes) {
            assert_eq!(row[0], episode[0].parse::<f64>().unwrap(), "{method}: step");
            assert_eq!(
                row[2],
                episode[3].parse::<f64>().unwrap(),
                "{method}: updates"
            );
            assert!(row[3..].iter().all(|v| v.is_finite()), "{method}: {row:?}");
            assert_eq!(row[5] == 0.0, method == "sac", "{method}: {row:?}");
            assert!(row[6] > 0.0, "{method}: {row:?}");
        }
        // The answers by sign: a row per episode at the same step, whose counts add up to the
        // queries `metrics.csv` counts (EF-100: every step of the episode; SAC: none).
        let answers = std::fs::read_to_string(d.join(&out_dir).join("answers.csv")).unwrap();
        let mut rows = answers.lines();
        assert_eq!(rows.next(), Some("step,episode,asked,good,bad,none"));
        let rows: Vec<Vec<u64>> = rows
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        assert_eq!(
            rows.len(),
            episodes.len(),
            "{method}: an answers row per episode"
        );
        let mut asked_so_far = 0;
        for (row, episode) in rows.iter().zip(&episodes) {
            assert_eq!(row[0], episode[0].parse::<u64>().unwrap(), "{method}: step");
            assert_eq!(row[2], row[3] + row[4] + row[5], "{method}: {row:?}");
            asked_so_far += row[2];
            assert_eq!(asked_so_far, episode[6].parse::<u64>().unwrap(), "{method}");
            let length: u64 = episode[3].parse().unwrap();
            match method {
                "ef-100" => assert_eq!(row[2], length, "{method}: {row:?}"),
                "sac" => assert_eq!(row[2], 0, "{method}: {row:?}"),
                _ => {}
            }
        }
        // A teacher without faults always judges: +1 or -1, never "no feedback".
        assert!(rows.iter().all(|r| r[5] == 0), "{method}");
    }
}

#[test]
fn periodic_checks_ship_the_best_policy_without_changing_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let expert = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "expert",
            "--task",
            "reaching",
            "--steps",
            "300",
            "--seed",
            "3",
            "--eval-episodes",
            "2",
            "--out",
            out,
        ];
        args.extend(TINY);
        args.extend(extra);
        ok(&dualrep(&args, d))
    };
    let plain = expert("plain/reaching.safetensors", &[]);
    let checked = expert("checked/reaching.safetensors", &["--eval-every", "100"]);

    // The checks evaluate a copy of the learner: the training run itself is the same run.
    let metrics = |dir: &str| {
        std::fs::read_to_string(d.join(dir).join("reaching.train/metrics.csv")).unwrap()
    };
    assert_eq!(metrics("plain"), metrics("checked"));
    assert_eq!(plain["final_mean_return"], checked["final_mean_return"]);
    assert!(plain.get("checks").is_none() && plain.get("shipped_step").is_none());

    let checks = checked["checks"].as_array().unwrap();
    let steps: Vec<u64> = checks.iter().map(|c| c["step"].as_u64().unwrap()).collect();
    assert_eq!(steps, [100, 200, 300]);
    let returns: Vec<f64> = checks
        .iter()
        .map(|c| c["mean_return"].as_f64().unwrap())
        .collect();
    let best = returns.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let first_best = steps[returns.iter().position(|r| *r == best).unwrap()];
    assert_eq!(checked["shipped_step"], first_best);
}

#[test]
fn a_run_killed_midway_resumes_from_its_checkpoint_to_the_same_result() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tiny_expert(d, "placing", "200", "1");
    let train = |out: &str, every: &str, extra: &[&str]| {
        let mut args = vec![
            "train",
            "--task",
            "placing",
            "--method",
            "dref",
            "--steps",
            "1500",
            "--seed",
            "2",
            "--checkpoint-every",
            every,
            "--out",
            out,
        ];
        args.extend(TINY);
        args.extend(extra);
        args.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let straight = ok(&cli::dualrep_in(
        &train("straight", "0", &[])
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
        Some(d),
    ));

    // Kill the run as soon as its first checkpoint is on disk.
    let mut child = running_once(&train("killed", "300", &[]), d, "killed/checkpoint.run");
    let checkpoint = d.join("killed/checkpoint.run");
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!d.join("killed/summary.json").exists());

    // Another run's arguments are refused and the checkpoint stays.
    let other = train("killed", "300", &["--set", "c=0.5"]);
    let out = cli::dualrep_in(
        &other.iter().map(String::as_str).collect::<Vec<_>>(),
        Some(d),
    );
    let stderr = cli::refused(&out);
    assert!(
        stderr.contains("another configuration") && stderr.contains("delete it"),
        "{stderr}"
    );
    assert!(checkpoint.exists());

    let again = train("killed", "300", &[]);
    let out = cli::dualrep_in(
        &again.iter().map(String::as_str).collect::<Vec<_>>(),
        Some(d),
    );
    let resumed = ok(&out);
    assert!(String::from_utf8_lossy(&out.stderr).contains("resumed from checkpoint.run at step"));
    for field in [
        "steps",
        "episodes",
        "cumulative_return",
        "feedback_count",
        "final_mean_return",
        "final_success_rate",
    ] {
        assert_eq!(resumed[field], straight[field], "{field}");
    }
    let metrics = |run: &str| std::fs::read_to_string(d.join(run).join("metrics.csv")).unwrap();
    assert_eq!(metrics("killed"), metrics("straight"));
    // The learner's curves too: a row per episode, the same means bit for bit.
    let learner = |run: &str| std::fs::read_to_string(d.join(run).join("learner.csv")).unwrap();
    assert_eq!(learner("killed"), learner("straight"));
    assert_eq!(
        learner("straight").lines().count(),
        metrics("straight").lines().count()
    );
    // And the answers by sign.
    let answers = |run: &str| std::fs::read_to_string(d.join(run).join("answers.csv")).unwrap();
    assert_eq!(answers("killed"), answers("straight"));
    assert!(
        !checkpoint.exists(),
        "a finished run removes its checkpoint"
    );
}

#[test]
fn a_second_train_on_a_running_folder_is_refused_and_touches_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let train = |steps: &str| {
        let mut args = vec![
            "train",
            "--task",
            "reaching",
            "--method",
            "sac",
            "--steps",
            steps,
            "--seed",
            "1",
            "--checkpoint-every",
            "0",
            "--out",
            "run",
        ];
        args.extend(TINY);
        args.into_iter().map(String::from).collect::<Vec<_>>()
    };
    // The first run holds the folder once it has written its configuration.
    let mut first = running_once(&train("1000000"), d, "run/metrics.csv");
    let second = train("50");
    let out = dualrep(&second.iter().map(String::as_str).collect::<Vec<_>>(), d);
    let stderr = cli::refused(&out);
    assert!(
        stderr.contains("another `dualrep train` is writing"),
        "{stderr}"
    );
    assert!(!d.join("run/summary.json").exists());
    assert!(
        first.try_wait().unwrap().is_none(),
        "the refusal stopped the first run"
    );

    // Once the first run is gone (killed: its lock goes with it) the folder is free again.
    first.kill().unwrap();
    first.wait().unwrap();
    let summary = ok(&dualrep(
        &second.iter().map(String::as_str).collect::<Vec<_>>(),
        d,
    ));
    assert_eq!(summary["steps"], 50);
}

#[test]
fn bad_input_is_refused_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let refused = |args: &[&str], needle: &str| {
        let err = cli::refused(&dualrep(args, d));
        assert!(err.contains(needle), "{args:?}: {err}");
    };
    // Without `--expert` the binary's own expert is used; a named one must exist.
    refused(
        &[
            "train",
            "--task",
            "reaching",
            "--method",
            "dref",
            "--expert",
            "missing.safetensors",
            "--out",
            "x",
        ],
        "dualrep expert --task reaching",
    );
    refused(
        &[
            "train", "--task", "reaching", "--method", "ef-0", "--out", "x",
        ],
        "EF percentage",
    );
    refused(
        &[
            "train", "--task", "reaching", "--method", "sac", "--set", "hiden=3", "--out", "x",
        ],
        "hiden",
    );
    refused(
        &[
            "train", "--task", "reaching", "--method", "sac", "--set", "gamma", "--out", "x",
        ],
        "key=value",
    );
    refused(
        &[
            "train", "--task", "reaching", "--method", "sac", "--steps", "0", "--out", "x",
        ],
        "--steps",
    );
    std::fs::write(d.join("broken.safetensors"), b"not a checkpoint").unwrap();
    refused(
        &[
            "train",
            "--task",
            "reaching",
            "--method",
            "dref",
            "--expert",
            "broken.safetensors",
            "--out",
            "x",
        ],
        "loading the expert broken.safetensors",
    );
}
