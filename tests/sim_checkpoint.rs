//! `dualrep sim --checkpoint` end to end: the policy a stopped `train` run had learnt (or a
//! finished one kept with `--keep-checkpoints`), rolled out step by step, and clear errors on a
//! checkpoint that does not fit.

use std::path::Path;
use std::process::Output;

use crate::support::cli::{self, ok, running_once};

fn dualrep(args: &[&str], dir: &Path) -> Output {
    cli::dualrep_in(args, Some(dir))
}

/// `train` of a small SAC on Lunar Lander into `out`, checkpointing every `every` steps.
fn small_lunar_sac<'a>(steps: &'a str, every: &'a str, out: &'a str) -> Vec<&'a str> {
    let mut args = vec!["train", "--task", "lunar-lander", "--method", "sac"];
    args.extend(["--steps", steps, "--checkpoint-every", every, "--out", out]);
    args.extend(["--set", "hidden=16,16", "--set", "batch_size=32"]);
    args
}

#[test]
fn sim_rolls_out_the_policy_of_a_runs_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A SAC run on Lunar Lander, stopped once its first checkpoint is on disk.
    let args = small_lunar_sac("5000", "200", "run");
    let mut child = running_once(&args, d, "run/checkpoint.run");
    child.kill().unwrap();
    child.wait().unwrap();

    let sim = |extra: &[&str]| {
        let mut args = vec![
            "sim",
            "--checkpoint",
            "run/checkpoint.run",
            "--episodes",
            "2",
        ];
        args.extend(extra);
        dualrep(&args, d)
    };
    let sampled = ok(&sim(&["--steps", "steps.csv"]));
    assert_eq!(sampled["task"], "lunar-lander", "the run's task");
    assert_eq!(sampled["policy"], "learned");
    let steps = std::fs::read_to_string(d.join("steps.csv")).unwrap();
    assert_eq!(
        steps.lines().count() as f64,
        1.0 + 2.0 * sampled["mean_length"].as_f64().unwrap()
    );
    // Its own actions, not the heuristic's: the heuristic on the same seeds steps otherwise.
    ok(&dualrep(
        &[
            "sim",
            "--task",
            "lunar-lander",
            "--episodes",
            "2",
            "--steps",
            "h.csv",
        ],
        d,
    ));
    assert_ne!(std::fs::read_to_string(d.join("h.csv")).unwrap(), steps);
    // The mean action is one policy, the same every time.
    let mean = ok(&sim(&["--deterministic"]));
    assert_eq!(
        mean["mean_return"],
        ok(&sim(&["--deterministic"]))["mean_return"]
    );

    let refused = |extra: &[&str], expected: &str| {
        let stderr = cli::refused(&sim(extra));
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
    };
    refused(&["--task", "reaching"], "is of a lunar-lander run");
    refused(&["--policy", "random"], "cannot be used with");
    let out = dualrep(&["sim", "--checkpoint", "nowhere.run"], d);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--checkpoint nowhere.run"));
    std::fs::write(d.join("junk.run"), b"hello").unwrap();
    let out = dualrep(&["sim", "--checkpoint", "junk.run"], d);
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a dualrep"));
}

/// `train --keep-checkpoints`: every checkpoint outlives the run under `checkpoints/`, each with
/// the bytes of its own step (a run resumed from the first one ends as the run did), and `sim`
/// reads a finished run's policy from them.
#[test]
fn a_finished_run_keeps_each_checkpoint_by_its_step() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let train = |out: &str, keep: bool| {
        let mut args = small_lunar_sac("1200", "300", out);
        if keep {
            args.push("--keep-checkpoints");
        }
        dualrep(&args, d)
    };
    let kept = ok(&train("kept", true));
    assert!(
        !d.join("kept/checkpoint.run").exists(),
        "the run's own is removed"
    );
    let mut files: Vec<String> = std::fs::read_dir(d.join("kept/checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    files.sort();
    let steps: Vec<u64> = files
        .iter()
        .map(|f| f["step-".len()..f.len() - ".run".len()].parse().unwrap())
        .collect();
    assert!(steps.len() >= 2, "{files:?}");
    for (i, step) in steps.iter().enumerate() {
        assert!(*step >= 300 * (i as u64 + 1) && *step < 1200, "{files:?}");
    }
    // Without the flag nothing is kept, and the run is the same.
    let plain = ok(&train("plain", false));
    assert!(!d.join("plain/checkpoints").exists());
    assert_eq!(plain["cumulative_return"], kept["cumulative_return"]);

    // The first kept checkpoint is the run at its step: resumed from it, the run ends as it did.
    let again = d.join("again");
    std::fs::create_dir_all(&again).unwrap();
    for file in ["metrics.csv", "learner.csv", "answers.csv"] {
        if d.join("kept").join(file).exists() {
            std::fs::copy(d.join("kept").join(file), again.join(file)).unwrap();
        }
    }
    std::fs::copy(
        d.join("kept/checkpoints").join(&files[0]),
        again.join("checkpoint.run"),
    )
    .unwrap();
    let out = train("again", false);
    let resumed = ok(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("resumed from checkpoint.run at step {}", steps[0])),
        "{stderr}"
    );
    assert_eq!(resumed["cumulative_return"], kept["cumulative_return"]);
    assert_eq!(resumed["episodes"], kept["episodes"]);

    // And `sim` acts with the policy of the last one.
    let last = format!("kept/checkpoints/{}", files.last().unwrap());
    let rolled = ok(&dualrep(
        &["sim", "--checkpoint", &last, "--episodes", "1"],
        d,
    ));
    assert_eq!(rolled["policy"], "learned");
}

#[test]
fn judge_sets_the_runs_critic_beside_its_teacher_on_each_step() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // An EF-100 run learns a human critic from an answer on every step.
    let mut args = small_lunar_sac("1200", "300", "ef");
    args[4] = "ef-100";
    args.push("--keep-checkpoints");
    ok(&dualrep(&args, d));
    let mut kept: Vec<String> = std::fs::read_dir(d.join("ef/checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    kept.sort();
    let last = format!("ef/checkpoints/{}", kept.last().unwrap());
    // Three episodes of the last checkpoint's policy, judged, with `extra` arguments.
    let judged = |extra: &[&str]| {
        let mut args = vec!["sim", "--checkpoint", &last, "--episodes", "3", "--judge"];
        args.extend(extra);
        ok(&dualrep(&args, d))
    };
    let sim = judged(&["--steps", "steps.csv"]);
    let judge = &sim["judge"];
    let count = |key: &str| judge[key].as_u64().unwrap();
    let steps = count("steps");
    assert_eq!(
        steps as f64,
        3.0 * sim["mean_length"].as_f64().unwrap(),
        "every step judged"
    );
    assert_eq!(count("good") + count("bad") + count("none"), steps);
    assert!(count("good") > 0 && count("bad") > 0, "{judge}");
    // The steps' rows say the same, counted apart from the summary.
    let table = std::fs::read_to_string(d.join("steps.csv")).unwrap();
    let mut lines = table.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&header[header.len() - 2..], ["h_hat", "answer"]);
    let (mut good, mut bad, mut agree) = (0, 0, 0);
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        let h_hat: f32 = cells[cells.len() - 2].parse().unwrap();
        match cells[cells.len() - 1] {
            "1" => (good, agree) = (good + 1, agree + usize::from(h_hat > 0.0)),
            "-1" => (bad, agree) = (bad + 1, agree + usize::from(h_hat < 0.0)),
            "0" => {}
            other => panic!("answer {other:?}"),
        }
    }
    assert_eq!((good, bad), (count("good") as usize, count("bad") as usize));
    let agreement = judge["sign_agreement"].as_f64().unwrap();
    assert!((agreement - agree as f64 / (good + bad) as f64).abs() < 1e-12);
    let auc = judge["auc_good_over_bad"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&auc), "{auc}");

    // Another run's critic on the same steps: the same steps, other judgements of them.
    let first = format!("ef/checkpoints/{}", kept[0]);
    let other = judged(&["--critic-from", &first]);
    assert!(
        judge.get("within_state_rank_correlation").is_none(),
        "off by default"
    );
    // Actions around each step's, ranked by the critic and by the teacher's critic.
    let around = judged(&["--judge-actions", "4"]);
    let rho = around["judge"]["within_state_rank_correlation"]
        .as_f64()
        .unwrap();
    assert!((-1.0..=1.0).contains(&rho), "{rho}");
    assert!(around["judge"]["within_state_steps"].as_u64().unwrap() > 0);
    assert_eq!(
        around["judge"]["good"], judge["good"],
        "the same steps and answers"
    );
    assert_eq!(other["judge"]["steps"], judge["steps"]);
    assert_eq!(
        other["judge"]["good"], judge["good"],
        "the same teacher's answers"
    );
    assert_ne!(
        other["judge"]["h_hat_mean_good"], judge["h_hat_mean_good"],
        "another critic"
    );

    // The run's critic fitted again from fresh heads on its first 100 answers: the same steps
    // and answers, another critic, said in the summary; the same seed gives the same critic.
    let refit = |seed: &str| {
        judged(&[
            "--refit-critic",
            "30",
            "--refit-answers",
            "100",
            "--refit-seed",
            seed,
        ])
    };
    let (refit_a, refit_b, refit_c) = (refit("0"), refit("0"), refit("1"));
    assert_eq!(refit_a["judge"]["good"], judge["good"]);
    let report = &refit_a["judge"]["refit"];
    assert_eq!(
        (report["updates"].as_u64(), report["answers"].as_u64()),
        (Some(30), Some(100))
    );
    assert!(
        judge.get("refit").is_none(),
        "the run's own critic: no refit"
    );
    assert_eq!(refit_a["judge"], refit_b["judge"]);
    for fitted in [&refit_a, &refit_c] {
        assert_ne!(fitted["judge"]["h_hat_mean_good"], judge["h_hat_mean_good"]);
    }
    assert_ne!(
        refit_c["judge"]["h_hat_mean_good"],
        refit_a["judge"]["h_hat_mean_good"]
    );
    // More answers than the replay holds: refused, naming the option and the count.
    let mut args = vec![
        "sim",
        "--checkpoint",
        &last,
        "--judge",
        "--refit-critic",
        "5",
    ];
    args.extend(["--refit-answers", "100000"]);
    let out = dualrep(&args, d);
    let stderr = cli::refused(&out);
    assert!(
        stderr.contains("--refit-critic") && stderr.contains("100000 answers asked for"),
        "{stderr}"
    );
    // No gradient steps is no refit: refused rather than read as "the run's own critic".
    let out = dualrep(
        &[
            "sim",
            "--checkpoint",
            &last,
            "--judge",
            "--refit-critic",
            "0",
        ],
        d,
    );
    let stderr = cli::refused(&out);
    assert!(stderr.contains("--refit-critic"), "{stderr}");

    // A run without answers has no critic to judge.
    let mut sac = small_lunar_sac("400", "200", "sac-kept");
    sac.push("--keep-checkpoints");
    ok(&dualrep(&sac, d));
    let first = std::fs::read_dir(d.join("sac-kept/checkpoints"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let out = dualrep(
        &["sim", "--checkpoint", first.to_str().unwrap(), "--judge"],
        d,
    );
    let stderr = cli::refused(&out);
    assert!(stderr.contains("no human critic"), "{stderr}");
}
